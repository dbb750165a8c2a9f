"""``python -m knitlad``: the command line (:mod:`knitlad.cli`)."""

from knitlad.cli import main

main()
