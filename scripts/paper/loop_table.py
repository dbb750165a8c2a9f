"""The single-loop model's velocity table (paper, Fig. 5c): v_lad/c_b against f_x for mu = 0, 0.4, 0.8.

    python scripts/paper/loop_table.py [--geometry tails|periodic|periodic-sinkers|strip] [--columns 8]
                                 [--fx 1 2 4 8 12 16 20] [--mu 0 0.4 0.8] [--max-time-ms 1]

``tails`` is ``knitlad loop`` (:mod:`knitlad.experiments.loop_model`); the others are the rows
periodic along the course (:mod:`knitlad.experiments.periodic_loop`): one stitch per period under
an imposed tension, free in y (``periodic``) or with the loop row's sinkers held in y
(``periodic-sinkers``), or a strip of ``--columns`` columns at fixed period (``strip``;
with ``--force-controlled`` its period follows the tension).

Prints one row per (mu, f_x) beside the paper's inertial law 0.34 sqrt(f_x) (mu = 0)
and the straight line through the paper's two 42 x 42 DER points (mu = 0.4), with the
wall time of each run; for the periodic geometries also the column width at t_0 and
at the end, and how far the loop's centroid rose (in l_y: a loop that lets go by
opening stays near 0, one that climbs out bodily rises by rows). Then, for each mu,
the straight line v_lad^2 = v_0^2 + beta^2 f_x through the released runs with
2 <= f_x <= 12 (the paper's mu = 0 law is beta = 0.34, v_0 = 0).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from knitlad.experiments.config import LoopConfig
from knitlad.experiments.loop_model import LoopRun
from knitlad.experiments.periodic_loop import PeriodicLoopRun
from knitlad.viz.plots import PAPER_DER_VELOCITY


def paper_fabric(fx: float) -> float:
    """v_lad/c_b on the straight line through the paper's two 42 x 42 DER points (mu = 0.4)."""
    (f1, v1), (f2, v2) = PAPER_DER_VELOCITY
    return v1 + (v2 - v1) * (fx - f1) / (f2 - f1)


def run(geometry: str, fx: float, mu: float, args):
    cfg = LoopConfig(fx=fx, mu=mu, max_time_ms=args.max_time_ms, resolution=args.resolution, geometry=geometry,
                     **({"columns": args.columns} if geometry == "strip" else {}))
    if geometry == "tails":
        return LoopRun(cfg.settings()).run()
    return PeriodicLoopRun(cfg.settings(force_controlled=True if args.force_controlled else None)).run()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--geometry", choices=["tails", "periodic", "periodic-sinkers", "strip"], default="tails")
    p.add_argument("--columns", type=int, default=8, help="columns of the strip")
    p.add_argument("--force-controlled", action="store_true", help="the strip's period follows the tension")
    p.add_argument("--fx", type=float, nargs="+", default=[1, 2, 4, 8, 12, 16, 20])
    p.add_argument("--mu", type=float, nargs="+", default=[0.0, 0.4, 0.8])
    p.add_argument("--max-time-ms", type=float, default=1.0)
    p.add_argument("--resolution", type=int, default=36)
    args = p.parse_args()
    periodic = args.geometry != "tails"
    strip = f", {args.columns} columns" + (", force-controlled" if args.force_controlled else "")
    print(f"# geometry {args.geometry}" + (strip if args.geometry == "strip" else ""))
    head = f"{'mu':>4s} {'f_x':>5s} {'v_lad/c_b':>9s} {'paper':>6s} {'tau [us]':>9s} {'released':>8s} {'wall s':>7s}"
    print(head + (f" {'lx0/l0':>7s} {'lx_end':>7s} {'climb/ly':>8s}" if periodic else ""), flush=True)
    fits = []
    for mu in args.mu:
        released = []
        for fx in args.fx:
            t = time.perf_counter()
            r = run(args.geometry, fx, mu, args)
            wall = time.perf_counter() - t
            paper = 0.34 * math.sqrt(fx) if mu == 0 else paper_fabric(fx) if mu == 0.4 else math.nan
            line = (f"{mu:4.1f} {fx:5.1f} {r.v_lad_over_cb:9.3f} {paper:6.3f} {r.tau_s * 1e6:9.1f} "
                    f"{str(r.released):>8s} {wall:7.2f}")
            if periodic:
                line += f" {r.lx_over_l0:7.3f} {r.lx_end_over_l0:7.3f} {r.climb_over_ly:8.2f}"
            print(line, flush=True)
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
