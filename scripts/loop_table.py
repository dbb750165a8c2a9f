"""The single-loop model's velocity table (paper, Fig. 5c): v_lad/c_b against f_x for mu = 0, 0.4, 0.8.

    python scripts/loop_table.py [--fx 1 2 4 8 12 16 20] [--mu 0 0.4 0.8] [--max-time-ms 1]

Prints one row per (mu, f_x) beside the paper's inertial law 0.34 sqrt(f_x), and
the wall time of each run (the issue's speed goal: one run under 10 s). Then, for
each mu, the straight line v_lad^2 = v_0^2 + beta^2 f_x through the released runs
with 2 <= f_x <= 12 (at mu = 0 the paper's law is beta sqrt(f_x), beta = 0.34; v_0 is the
loop's bending recoil; tests/validation/test_single_loop.py).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from knitlad.config import LoopConfig
from knitlad.loop_model import LoopRun


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fx", type=float, nargs="+", default=[1, 2, 4, 8, 12, 16, 20])
    p.add_argument("--mu", type=float, nargs="+", default=[0.0, 0.4, 0.8])
    p.add_argument("--max-time-ms", type=float, default=1.0)
    p.add_argument("--resolution", type=int, default=36)
    args = p.parse_args()
    LoopRun(LoopConfig(fx=4.0, mu=0.0, max_time_ms=1e-2).settings()).run()  # compile outside the timings
    print(f"{'mu':>4s} {'f_x':>5s} {'v_lad/c_b':>9s} {'0.34 sqrt f':>11s} {'tau [us]':>9s} {'released':>8s} {'wall s':>7s}")
    fits = []
    for mu in args.mu:
        released = []
        for fx in args.fx:
            t = time.perf_counter()
            r = LoopRun(LoopConfig(fx=fx, mu=mu, max_time_ms=args.max_time_ms, resolution=args.resolution).settings()).run()
            wall = time.perf_counter() - t
            print(f"{mu:4.1f} {fx:5.1f} {r.v_lad_over_cb:9.3f} {0.34 * math.sqrt(fx):11.3f} {r.tau_s * 1e6:9.1f} "
                  f"{str(r.released):>8s} {wall:7.2f}", flush=True)
            if r.released and 2 <= fx <= 12:
                released.append((fx, r.v_lad_over_cb))
        if len(released) >= 2:
            f, v = np.array(released).T
            beta_sq, v0_sq = np.polyfit(f, v**2, 1)
            fits.append((mu, beta_sq, v0_sq, len(f)))
    for mu, beta_sq, v0_sq, n in fits:
        beta = math.sqrt(beta_sq) if beta_sq > 0 else math.nan
        v0 = math.sqrt(v0_sq) if v0_sq > 0 else math.nan
        print(f"mu {mu:.1f}: v^2 = v0^2 + beta^2 f_x over {n} runs (2 <= f_x <= 12): beta {beta:.3f} (paper, mu = 0: 0.34), "
              f"v0 {v0:.3f} c_b")


if __name__ == "__main__":
    main()
