"""The knit patterns' periodised stitches at mu = 0: f_x against l_x at fixed l_y, and the f_x = 0 width
of each pattern at each l_y (docs/patterns.md).

    python scripts/paper/pattern_stitch_curves.py [--ly 0.22 0.25 0.28] [--step 0.01] [--csv FILE] [--png FILE]
        [--knit-csv docs/reference/pattern_curves10.csv] [--replot CSV]

Each pattern's cell is one repeat (jersey 1 x 1, rib 2 x 1, garter 1 x 2 stitches: knitlad.fabric.scenes.stitch),
built where its loops interlock (knitlad.fabric.stitch_model.StitchRun), narrowed affinely to --lx-bottom,
then widened in steps of --step, each relaxed at mu = 0 to the final tolerance (1e-4 f0) and read for
f_x, f_y per thread (the cell energy's derivatives), at the default preset's resolution and contact: the
protocol of scripts/paper/pattern_curves.py on the infinite fabric instead of a finite knit. The f_x = 0
width is where f_x first turns positive. With --knit-csv the finite knit's curves at l_y/l0 = 0.25 are
drawn beside the stitches' (at the knit's own measured l_x).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.experiments.config import CutConfig
from knitlad.fabric.patterns import PATTERNS
from knitlad.fabric.stitch_model import StitchRun, StitchSettings
from knitlad.engine.simulation import small_scene_threads
from knitlad.fabric.stretching import stretch_to


def stitch_loading_curve(pattern: str, ly: float, lx_bottom: float, lx_top: float, step: float = 0.01,
                         resolution: int | None = None, sagitta_radius: float | None = None) -> pd.DataFrame:
    """The pattern's cell at l_y, narrowed from its build to ``lx_bottom``, then widened to ``lx_top``: f_x, f_y
    at each step after the final relaxation."""
    cfg = CutConfig(lx=0.3, ly=ly)
    run = StitchRun(StitchSettings(
        lx=lx_top, ly=ly, material=cfg.stretch_settings().material,
        resolution=resolution or cfg.resolution,
        sagitta_radius=cfg.sagitta_radius if sagitta_radius is None else sagitta_radius, pattern=pattern))
    rows = []
    with small_scene_threads():
        run.relax()
        stretch_to(run, lx_bottom, ly, step, min_increments=0)
        lx = lx_bottom
        while lx <= lx_top + 1e-9:
            stretch_to(run, lx, ly, step, min_increments=0)
            info = run.settle()
            fx, fy = run.tensions()
            rows.append({"pattern": pattern, "ly_over_l0": ly, "lx_over_l0": lx, "fx": fx, "fy": fy,
                         "converged": bool(info["converged"])})
            print(f"{pattern:7s} l_y {ly:.3f} l_x {lx:.3f}: f_x {fx:8.3f}  f_y {fy:8.3f}", flush=True)
            lx = round(lx + step, 6)
    return pd.DataFrame(rows)


def zero_width(curve: pd.DataFrame) -> float:
    """l_x/l0 where f_x first turns positive (linear between readings); NaN if it never does or already is."""
    fx, lx = curve.fx.to_numpy(), curve.lx_over_l0.to_numpy()
    above = np.flatnonzero(fx > 0)
    if not above.size or above[0] == 0:
        return float("nan")
    k = above[0]
    return float(lx[k - 1] + (lx[k] - lx[k - 1]) * (0 - fx[k - 1]) / (fx[k] - fx[k - 1]))


def plot(curves: pd.DataFrame, knit: pd.DataFrame | None, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, az) = plt.subplots(1, 2, figsize=(10, 3.8))
    colours = dict(zip(PATTERNS, ("tab:blue", "tab:orange", "tab:green")))
    for (pattern, ly), g in curves.groupby(["pattern", "ly_over_l0"], sort=False):
        if np.isclose(ly, 0.25):
            ax.plot(g.lx_over_l0, g.fx, color=colours[pattern], label=f"{pattern}, periodised stitch")
    if knit is not None:
        for pattern, g in knit.groupby("pattern", sort=False):
            ax.plot(g.lx_over_l0, g.fx, "o", ms=3, color=colours[pattern], label=f"{pattern}, 10 x 10 knit")
    ax.axhline(0, color="grey", lw=0.5)
    ax.set_xlabel("l_x/l0")
    ax.set_ylabel("f_x = F_x/(n_y f0)")
    ax.set_ylim(-3, 12)
    ax.set_title("l_y/l0 = 0.25, mu = 0")
    ax.legend(fontsize=7)
    zero = curves.groupby(["pattern", "ly_over_l0"], sort=False).apply(zero_width).rename("lx0").reset_index()
    for pattern, g in zero.sort_values("ly_over_l0").groupby("pattern", sort=False):
        az.plot(g.lx0, g.ly_over_l0, "s-", color=colours[pattern], label=pattern)
    az.set_xlabel("l_x/l0 at f_x = 0")
    az.set_ylabel("l_y/l0")
    az.set_title("the f_x = 0 curve of each pattern's periodised stitch")
    az.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ly", type=float, nargs="+", default=[0.22, 0.25, 0.28])
    parser.add_argument("--lx-bottom", type=float, default=0.16)
    parser.add_argument("--lx-top", type=float, default=0.40)
    parser.add_argument("--step", type=float, default=0.01, help="l_x/l0 between readings")
    parser.add_argument("--patterns", nargs="+", default=list(PATTERNS))
    parser.add_argument("--csv", type=Path)
    parser.add_argument("--png", type=Path)
    parser.add_argument("--knit-csv", type=Path)
    parser.add_argument("--replot", type=Path, help="read the curves from this CSV (of --csv) instead of computing")
    args = parser.parse_args()
    if args.replot:
        curves = pd.read_csv(args.replot)
    else:
        curves = pd.concat([stitch_loading_curve(p, ly, args.lx_bottom, args.lx_top, args.step)
                            for p in args.patterns for ly in args.ly], ignore_index=True)
    for (pattern, ly), g in curves.groupby(["pattern", "ly_over_l0"], sort=False):
        print(f"{pattern}: l_y/l0 {ly:.3f}: f_x = 0 at l_x/l0 = {zero_width(g):.3f}; f_x at 0.30 / 0.36: "
              f"{np.interp(0.30, g.lx_over_l0, g.fx):.2f} / {np.interp(0.36, g.lx_over_l0, g.fx):.2f}")
    if args.csv:
        curves.to_csv(args.csv, index=False, float_format="%.5g")
    if args.png:
        plot(curves, pd.read_csv(args.knit_csv) if args.knit_csv else None, args.png)


if __name__ == "__main__":
    main()
