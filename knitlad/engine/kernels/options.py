"""Numba compilation options of every kernel, said once.

fast-math without "nnan"/"ninf", so the blow-up guard still sees NaN and infinity;
``error_model="numpy"`` so a division by zero gives inf/NaN instead of raising.

Every argument type a kernel is called with compiles a specialisation of it, and of what it calls: one
compile of the step kernels costs tens of seconds. So a kernel is called with one type per argument:
arrays C-contiguous (``Rods.replace_model`` makes them so), every argument given (no default omitted by
one caller and passed by another), optional ones as ``None`` or their value, and from inside a kernel
whole numbers as ``np.int64(...)`` (a literal ``0`` is typed ``Literal[int](0)``, a prange index
``uint64``: each would compile its own copy of the callee).
"""

NUMBA_OPTS = dict(cache=True, error_model="numpy", fastmath={"nsz", "arcp", "contract", "afn", "reassoc"})
PARALLEL_OPTS = dict(NUMBA_OPTS, parallel=True)
# helpers called once or twice per pair and step, inlined into their callers at Numba IR level:
# as compiled calls returning tuples they cost twice the pair's arithmetic (same results to the bit)
INLINE_OPTS = dict(NUMBA_OPTS, inline="always")
