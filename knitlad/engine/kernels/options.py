"""Numba compilation options of every kernel, said once.

fast-math without "nnan"/"ninf", so the blow-up guard still sees NaN and infinity;
``error_model="numpy"`` so a division by zero gives inf/NaN instead of raising.
"""

NUMBA_OPTS = dict(cache=True, error_model="numpy", fastmath={"nsz", "arcp", "contract", "afn", "reassoc"})
PARALLEL_OPTS = dict(NUMBA_OPTS, parallel=True)
# helpers called once or twice per pair and step, inlined into their callers at Numba IR level:
# as compiled calls returning tuples they cost twice the pair's arithmetic (same results to the bit)
INLINE_OPTS = dict(NUMBA_OPTS, inline="always")
