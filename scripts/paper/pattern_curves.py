"""The knit patterns' loading curves at mu = 0: f_x and f_y against the box's l_x at a fixed l_y (docs/patterns.md).

    python scripts/paper/pattern_curves.py [--stitches 10] [--ly 0.25] [--csv FILE] [--png FILE]

Each pattern (jersey, rib, garter) is built as a stretch builds it (knitlad.fabric.preparation.KnitBox: rib
and garter narrower, where their loops interlock), narrowed affinely to --lx-bottom, then widened in steps of
0.01 l0 and relaxed at mu = 0 to a steady f_x at each (the stretch's FIRE, the default preset's resolution and contact).
The finite knit's f_x = 0 crossing is its unloaded width at this l_y (for jersey, the periodised stitch's
f_x = 0 width is given beside it). Prints the table; writes the CSV and the figure if asked.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.experiments.config import CutConfig
from knitlad.fabric.patterns import PATTERNS
from knitlad.fabric.preparation import KnitBox, unloaded_width
from knitlad.fabric.stretching import relax_to_steady_tension


def loading_curve(pattern: str, stitches: int, ly: float, lx_bottom: float, lx_top: float,
                  step: float = 0.01) -> pd.DataFrame:
    """The knit built, narrowed affinely to ``lx_bottom`` (relaxed at each step, not recorded), then widened to
    ``lx_top``, relaxed to a steady f_x at each step and recorded."""
    cfg = CutConfig(n_x=stitches, n_y=stitches, lx=lx_top, ly=ly, pattern=pattern, stretch_start="affine")
    box = KnitBox(cfg.stretch_settings())
    lx = box.lx
    while lx > lx_bottom + 1e-9:
        lx = round(max(lx - step, lx_bottom), 6)
        box.deform(lx, box.ly)
        box.relax()
    rows = []
    while lx <= lx_top + 1e-9:
        box.deform(lx, box.ly)
        fx = relax_to_steady_tension(box)
        fy = box.gauge.tension_y(box.sim)
        mlx, mly = box.gauge.periodicities(box.sim.state.x, box.lx)
        rows.append({"pattern": pattern, "box_lx": lx, "lx_over_l0": mlx, "ly_over_l0": mly, "fx": fx, "fy": fy})
        print(f"{pattern:7s} box l_x/l0 {lx:.3f}: f_x {fx:7.3f}  f_y {fy:7.3f}", flush=True)
        lx = round(lx + step, 6)
    return pd.DataFrame(rows)


def zero_crossing(curve: pd.DataFrame) -> float:
    """The box l_x/l0 where f_x first turns positive (linear between the readings); NaN if it never does
    or already is at the build."""
    fx, lx = curve.fx.to_numpy(), curve.box_lx.to_numpy()
    above = np.flatnonzero(fx > 0)
    if not above.size or above[0] == 0:
        return float("nan")
    k = above[0]
    return float(lx[k - 1] + (lx[k] - lx[k - 1]) * (0 - fx[k - 1]) / (fx[k] - fx[k - 1]))


def plot(curves: pd.DataFrame, png: Path, ly: float, stitches: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ay) = plt.subplots(1, 2, figsize=(10, 3.8))
    for pattern, g in curves.groupby("pattern", sort=False):
        ax.plot(g.box_lx, g.fx, marker="o", ms=3, label=pattern)
        ay.plot(g.box_lx, g.fy, marker="o", ms=3, label=pattern)
    for a, name in ((ax, "f_x = F_x/(n_y f0)"), (ay, "f_y = F_y/(n_x f0)")):
        a.axhline(0, color="grey", lw=0.5)
        a.set_xlabel("box l_x/l0")
        a.set_ylabel(name)
    ax.legend()
    fig.suptitle(f"{stitches} x {stitches} knits at mu = 0, l_y/l0 = {ly}, default preset: loading along x")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stitches", type=int, default=10)
    parser.add_argument("--ly", type=float, default=0.25)
    parser.add_argument("--lx-bottom", type=float, default=0.20)
    parser.add_argument("--lx-top", type=float, default=0.42)
    parser.add_argument("--csv", type=Path)
    parser.add_argument("--png", type=Path)
    args = parser.parse_args()
    curves = pd.concat([loading_curve(p, args.stitches, args.ly, args.lx_bottom, args.lx_top) for p in PATTERNS], ignore_index=True)
    cfg = CutConfig(lx=0.3, ly=args.ly)
    print(f"the periodised jersey stitch's f_x = 0 width at l_y/l0 = {args.ly}: "
          f"{unloaded_width(args.ly, cfg.resolution, cfg.stretch_settings().material, cfg.sagitta_radius):.3f}")
    for pattern, g in curves.groupby("pattern", sort=False):
        print(f"{pattern}: f_x = 0 at box l_x/l0 = {zero_crossing(g):.3f}; f_x at 0.36 / 0.40: "
              f"{np.interp(0.36, g.box_lx, g.fx):.2f} / {np.interp(0.40, g.box_lx, g.fx):.2f}")
    if args.csv:
        curves.to_csv(args.csv, index=False, float_format="%.5g")
    if args.png:
        plot(curves, args.png, args.ly, args.stitches)


if __name__ == "__main__":
    main()
