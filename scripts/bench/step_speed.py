"""Step speed of one checkout of knitlad: a ladder cut at f_x 13.6, 1,000 steps, then timed steps.

    NUMBA_NUM_THREADS=1 PYTHONPATH=/path/to/checkout python scripts/bench/step_speed.py 42 4000 new fast
    NUMBA_NUM_THREADS=1 PYTHONPATH=/path/to/old python scripts/bench/step_speed.py 42 4000 old default

Run two checkouts in turn, a few rounds, to compare code on one machine (its speed drifts between hours).
Only public names are imported (and the layout of 2026-12-03 as a fallback), so an older checkout runs its own
code; the last printed value, a position, must be the same to the bit for the two checkouts.
Arguments: stitches, timed steps, a label, the preset (24 nodes per stitch: ``fast`` today, ``default`` on
2026-12-03).
"""

import sys
import time

try:
    from knitlad import CutConfig, cut, stretch
except ImportError:  # the layout of 2026-12-03
    from knitlad.config import CutConfig
    from knitlad.protocol import cut, stretch
import knitlad

n, steps, label, preset = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4]
cfg = CutConfig(n_x=n, n_y=n, fx=13.6, twist=False, preset=preset)
run = cut(stretch(cfg.stretch_settings()), cfg.dynamics_settings())
run.sim.step(1000)
t0 = time.perf_counter()
c0 = time.process_time()
run.sim.step(steps)
t = time.perf_counter() - t0
c = time.process_time() - c0
nodes = run.sim.state.x.shape[0]
print(f"{label} {preset} ({knitlad.__file__.split('/knitlad/')[0]}) {nodes} nodes {steps} steps {t:.2f} s "
      f"{nodes * steps / t:.3e} node-steps/s, cpu {c:.2f} s, x[0] {run.sim.state.x[0, 0]!r}", flush=True)
