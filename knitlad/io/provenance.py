"""Which code made a file: the package version and, in a git checkout, the commit.

Every output records :func:`code_identity`, so results made before and after a change of
the physics cannot mix silently in one table: ``knitlad sweep`` and ``knitlad plot`` say
which job files another code made (``--rerun-stale`` runs them again).
"""

from __future__ import annotations

import functools
import subprocess
from pathlib import Path

from knitlad import __version__


@functools.lru_cache(maxsize=1)
def code_commit() -> str:
    """The git commit of the package's checkout (with "-dirty" if it has uncommitted changes), or ""
    when knitlad is not run from a git checkout."""
    root = Path(__file__).resolve().parents[2]  # knitlad/io/provenance.py -> the checkout
    if not (root / ".git").exists():
        return ""
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short=12", "HEAD"], capture_output=True,
                                text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no", "--",
                                "knitlad"], capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""
    return f"{commit}-dirty" if commit and dirty else commit


def code_identity() -> str:
    """``version`` or ``version+commit``: what an output records as the code that made it."""
    commit = code_commit()
    return f"{__version__}+{commit}" if commit else __version__


def run_provenance() -> dict[str, str]:
    """Where and when a file was made, and by which interpreter and libraries: ``created_utc``, ``host``,
    ``platform``, ``python``, ``numpy``, ``numba``, ``h5py`` (every output file of a run records them)."""
    import platform
    import socket
    import sys
    import time

    import h5py
    import numba
    import numpy

    return {"created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "host": socket.gethostname(),
            "platform": platform.platform(), "python": sys.version.split()[0], "numpy": numpy.__version__,
            "numba": numba.__version__, "h5py": h5py.__version__, "code": code_identity()}
