"""Stretched knits kept on disk and reused: jobs that share the stretch's settings stretch once.

A stretched knit depends only on its :class:`knitlad.fabric.preparation.StretchSettings` (the
stretch at mu = 0 is deterministic) and on the code that stretches it, so it is stored
under a hash of those settings, the knitlad version and the package's source,
``<folder>/<hash>.h5``, and read back exactly (:func:`knitlad.io.hdf5.read_stretched_knit`).
A sweep over mu, drag, twist or any other setting of the dynamics then stretches each
knit once. A file that does not read back (damaged, its attributes edited, or of another
version's layout) is made again. The cache is an optimisation: a write that fails is a
warning, never the job's failure; temporary files of writers that died are swept.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import warnings
from pathlib import Path
from typing import Callable

from knitlad import __version__
from knitlad.io.hdf5 import jsonable, read_stretched_knit, verify_datasets, write_stretched_knit


@functools.lru_cache(maxsize=1)
def source_hash() -> str:
    """sha256 of the package's Python sources: a knit stretched by other code is not reused."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def stretch_key(settings) -> str:
    """Hash of the stretch's settings, the knitlad version and its source (16 hex digits)."""
    blob = json.dumps({"settings": jsonable(settings), "version": __version__, "source": source_hash()},
                      sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def sweep_stale_temporaries(folder: Path) -> None:
    """Remove the temporary files (``<name>.<pid>.tmp``) of writers whose process is gone."""
    for tmp in folder.glob("*.tmp"):
        try:
            pid = int(tmp.name.rsplit(".", 2)[-2])
            os.kill(pid, 0)  # alive (or another user's): keep
        except ProcessLookupError:
            tmp.unlink(missing_ok=True)
        except (ValueError, IndexError, PermissionError, OSError):
            continue


def cached_stretch(settings, folder: str | Path, stretch: Callable, progress=None):
    """(the stretched knit for ``settings``, whether it came from ``folder``): read if stored and
    intact, else made by ``stretch(settings, progress)`` and stored."""
    path = Path(folder) / f"{stretch_key(settings)}.h5"
    if Path(folder).is_dir():
        sweep_stale_temporaries(Path(folder))
    if path.exists():
        try:
            verify_datasets(path)
            knit = read_stretched_knit(path)
            if knit.settings == settings:
                return knit, True
        except Exception:  # noqa: BLE001 - unreadable: make it again
            pass
    knit = stretch(settings, progress)
    try:
        write_stretched_knit(path, knit)
    except OSError as e:  # read-only, full, or not a folder: the job goes on without the cache
        warnings.warn(f"stretched knit not kept in {folder}: {e}", RuntimeWarning, stacklevel=2)
    return knit, False
