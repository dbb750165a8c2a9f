"""Stretched knits kept on disk and reused: jobs that share the stretch's settings stretch once.

A stretched knit depends only on its :class:`knitlad.protocol.StretchSettings` (the
stretch at mu = 0 is deterministic), so it is stored under a hash of those settings
and of the knitlad version, ``<folder>/<hash>.h5``, and read back exactly
(:func:`knitlad.io.hdf5.read_stretched_knit`). A sweep over mu, drag, twist or any other
setting of the dynamics then stretches each knit once. A file that does not read back
(damaged, or of another version's layout) is made again.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Callable

from knitlad import __version__
from knitlad.io.hdf5 import jsonable, read_stretched_knit, verify_datasets, write_stretched_knit


def stretch_key(settings) -> str:
    """Hash of the stretch's settings and the knitlad version (16 hex digits)."""
    blob = json.dumps({"settings": jsonable(settings), "version": __version__}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def cached_stretch(settings, folder: str | Path, stretch: Callable, progress=None):
    """(the stretched knit for ``settings``, whether it came from ``folder``): read if stored and
    intact, else made by ``stretch(settings, progress)`` and stored."""
    path = Path(folder) / f"{stretch_key(settings)}.h5"
    if path.exists():
        try:
            verify_datasets(path)
            knit = read_stretched_knit(path)
            if knit.settings == settings:
                return knit, True
        except Exception:  # noqa: BLE001 - unreadable: make it again
            pass
    knit = stretch(settings, progress)
    write_stretched_knit(path, knit)
    return knit, False
