"""Numba kernels: plain ``@njit(cache=True)`` functions over arrays.

They keep no module state and write into preallocated outputs. Array layout
(said once, used everywhere): node arrays are ``(n, 3)`` float64 in internal
units (:mod:`knitlad.engine.units`); edge arrays are indexed by edge id ``k`` joining
``edge_a[k] -> edge_b[k]`` (plus ``edge_shift[k]`` for the closing edge of a
periodised yarn); hinge arrays are indexed by bending hinge ``h`` between edges
``hinge_e0[h]`` (ending at the hinge node) and ``hinge_e1[h]`` (starting there).
"""

import hashlib
import pickle
from pathlib import Path

from numba.core import caching

KERNELS_DIR = Path(__file__).resolve().parent


def kernel_sources_stamp(folder: Path = KERNELS_DIR) -> str:
    """The SHA-256 of every kernel module's name and source in ``folder``: what the compiled kernels were made
    from."""
    digest = hashlib.sha256()
    for path in sorted(folder.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


SOURCES_STAMP = kernel_sources_stamp()


class _FromKernelSources:
    """A cache locator for the kernels of this folder whose cache is fresh only for the sources it was
    compiled from: all of them. Numba's own stamp is the one file that defines a function, so an edit of a
    kernel it calls (another file) would leave it running the old code from the cache."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if Path(py_file).resolve().parent != KERNELS_DIR:
            return None
        return super().from_function(py_func, py_file)

    def get_source_stamp(self):
        return SOURCES_STAMP


def _register_locators() -> None:
    """Put a kernel-sources locator before each of Numba's file-backed ones (the user's NUMBA_CACHE_DIR, the
    package's __pycache__, the user-wide cache), in Numba's order; once per process."""
    locators = caching.CacheImpl._locator_classes
    if any(issubclass(c, _FromKernelSources) for c in locators):
        return
    ours = [type(f"KernelSources{base.__name__}", (_FromKernelSources, base), {})
            for base in (caching.UserProvidedCacheLocator, caching.InTreeCacheLocator, caching.UserWideCacheLocator)]
    locators[:0] = ours


_register_locators()


def is_compiled(kernel) -> bool:
    """Whether Numba's cache holds a specialisation of ``kernel`` (a dispatcher of this folder) made from the
    present kernel sources: False on a fresh install and after a kernel was edited."""
    try:
        return bool(kernel._cache._cache_file._load_index())
    except (AttributeError, OSError, EOFError, pickle.UnpicklingError):
        return False
