"""The mu = 0 tension of a knit held at fixed boxes, and a ladder from the first box at a target.

At mu = 0 nothing holds the loops but their shape. With the course ends held at the tip
of straight tails (``--edge tail``) the knit creeps: at a
fixed box its tension keeps changing over thousands of FIRE steps (42 x 42 at box
l_x/l0 = 0.355: 0.33 to 0.94 f0 per thread over 20 rounds of 750 steps, to 2.04 over 57,
then a drop to 0.77), with residual forces of about f0 on some node; with the ends
clamped at the edge sinkers (``--edge clamped``, the default) it settles (2.36 to 2.28
over 30 rounds, residual 2e-3 f0). This script stretches along one path (boxes in the
given order, position control), relaxes ``--rounds`` rounds at each box, prints the
tension after every round, and with ``--target`` ladders (mu = 0.4, the defaults of
``knitlad cut``) from the first box whose tension is within 2 % of it. It also tracks
the head of every loop (the highest node of each course within each column; nodes are
material points, built ``nodes_per_stitch`` to a stitch): how far the heads have moved
along the yarn since the first box, and the yarn each stitch holds (nodes between
consecutive heads), to show yarn flowing from stitch to stitch (with tails: the two
outermost columns' heads moved 7.5 and 3.3 nodes, the interior < 1; clamped: <= 1).

    python scripts/creep_scan.py --boxes 0.34 0.35 0.355 0.36 --rounds 20 --target 1.58
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from knitlad.config import CutConfig
from knitlad.protocol import KnitBox, analyse, cut, propagate
from knitlad.scenes.jersey import EDGES
from knitlad.stretching import stretch_to


def loop_heads(box: KnitBox) -> np.ndarray:
    """(courses, columns) index along its course of the highest node of each loop."""
    x = box.sim.state.x
    centres = box.gauge.column_centres(box.lx)
    half = 0.5 * (centres[1] - centres[0])
    heads = np.full((len(box.knit.courses), centres.size), -1)
    for r in range(len(box.knit.courses)):
        xr = x[box.knit.course_nodes(r)]
        for c, centre in enumerate(centres):
            inside = np.flatnonzero(np.abs(xr[:, 0] - centre) < half)
            if inside.size:
                heads[r, c] = inside[np.argmax(xr[inside, 1])]
    return heads


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--boxes", type=float, nargs="+", required=True, help="box l_x/l0, in the order visited")
    p.add_argument("--rounds", type=int, default=20, help="relaxation rounds at each box")
    p.add_argument("--target", type=float, help="f_x^ini at which to cut and ladder")
    p.add_argument("--stitches", type=int, default=42, help="N for an N x N knit")
    p.add_argument("--edge", default="clamped", choices=EDGES, help="how the course ends are held")
    args = p.parse_args()
    if args.rounds < 1:
        p.error("--rounds must be >= 1")
    cfg = CutConfig(preset="fast", n_x=args.stitches, n_y=args.stitches, lx=args.boxes[-1], edge=args.edge)
    box = KnitBox(cfg.stretch_settings())
    f0 = box.s.material.f0
    t0 = time.perf_counter()
    first_heads = None
    for lx in args.boxes:
        stretch_to(box, lx, box.ly, box.s.stretch_increment)
        first_heads = loop_heads(box) if first_heads is None else first_heads
        series = [box.tension()]
        for _ in range(args.rounds):
            info = box.relax()
            series.append(box.tension())
        heads = loop_heads(box)
        yarn_per_stitch = np.diff(heads, axis=1)
        print(json.dumps({"box_lx_over_l0": lx, "fx_after_each_round": [round(f, 3) for f in series],
                          "max_residual_force_over_f0": round(info["max_force_N"] / f0, 3),
                          "largest_head_shift_nodes": int(np.abs(heads - first_heads).max()),
                          "mean_head_shift_by_column": np.abs(heads - first_heads).mean(axis=0).round(1).tolist(),
                          "nodes_per_stitch_min_max": [int(yarn_per_stitch.min()), int(yarn_per_stitch.max())],
                          "wall_s": round(time.perf_counter() - t0)}), flush=True)
        if args.target is not None and abs(series[-1] - args.target) <= 0.02 * args.target:
            knit = box.stretched(series[-1], True, time.perf_counter() - t0)
            print(json.dumps(analyse(propagate(cut(knit, cfg.dynamics_settings()))).summary(), default=float), flush=True)
            return
    if args.target is not None:
        print(f"no box reached f_x = {args.target} within 2 %")


if __name__ == "__main__":
    main()
