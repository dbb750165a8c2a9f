"""Loose to jammed: laddering against the yarn's thickness d/l0 (docs/reference/loose_to_jammed16.yaml), and the
threshold against it (docs/reference/threshold_thickness16.yaml).

    python scripts/paper/loose_to_jammed.py runs/loose_to_jammed16 [--csv FILE] [--png FILE]
    python scripts/paper/loose_to_jammed.py runs/threshold_thickness16 --threshold [--csv FILE]

Per (d/l0, nominal f_x^ini), over the stretched knits of the point (mean +- standard error): f_x^ini, the
knit's l_x/l0 and l_x/l_x0 (l_x0 the periodised stitch's f_x = 0 width at the knit's l_y, its unloaded
width, also printed per d/l0), n_lad/n_y, the cells released into loaded courses, v_lad/c_b and f_x^fin
of the courses the ladder crossed (the paper's post-arrest tension, its reading of f_thr). Prints a
markdown table. With --threshold, per d/l0: the threshold bracketed between the highest nominal tension at
which no knit laddered and the lowest at which every knit did (a cut ladders from
knitlad.experiments.resistance.LADDERING_ONSET_CELLS undone cells, the threshold study's criterion), with
each point's cells per knit.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.experiments.config import material_for
from knitlad.experiments.resistance import LADDERING_ONSET_CELLS
from knitlad.fabric.preparation import unloaded_width


def table(folder: Path) -> pd.DataFrame:
    summary = pd.read_csv(folder / "summary.csv")
    rows = []
    for _, job in summary.iterrows():
        d_l0 = float(job.d_over_l0)
        row = {"d_over_l0": d_l0, "fx_nominal": job.get("fx_nominal", job.fx), "status": job.status}
        if job.status == "pending":
            continue
        if job.status == "ok":
            m = material_for(d_l0)
            l_x0 = unloaded_width(float(job.ly), int(job.resolution), m, float(job.sagitta_radius))
            row.update(fx_ini=job.fx_ini, n_lad=job.n_lad, lx_over_l0=job.lx_over_l0, lx0_over_l0=l_x0,
                       lx_over_lx0=job.lx_over_l0 / l_x0, n_lad_over_ny=job.n_lad_over_ny,
                       released_over_ny=job.n_lad_released_over_ny, v_lad_over_cb=job.v_lad_over_cb,
                       fx_fin_crossed=job.fx_fin_crossed, reached_edge=bool(job.reached_edge))
        else:
            row["error"] = str(job.error).split(":")[0]
        rows.append(row)
    return pd.DataFrame(rows)


def by_point(df: pd.DataFrame) -> pd.DataFrame:
    """Mean and standard error over a point's knits (the failed ones counted apart)."""
    out = []
    for (d_l0, fx), g in df.groupby(["d_over_l0", "fx_nominal"]):
        ok = g[g.status == "ok"]
        row = {"l0_over_d": 1 / d_l0, "fx_nominal": fx, "knits": int(len(ok)), "failed": int(len(g) - len(ok))}
        for name in ("fx_ini", "lx_over_l0", "lx0_over_l0", "lx_over_lx0", "n_lad_over_ny", "released_over_ny",
                     "v_lad_over_cb", "fx_fin_crossed"):
            values = ok[name].dropna() if name in ok else pd.Series(dtype=float)
            row[name] = values.mean() if len(values) else np.nan
            row[name + "_se"] = values.std(ddof=1) / np.sqrt(len(values)) if len(values) > 1 else np.nan
        row["edge"] = int(ok.reached_edge.astype(bool).sum()) if "reached_edge" in ok else 0
        out.append(row)
    return pd.DataFrame(out).sort_values(["fx_nominal", "l0_over_d"], ascending=[True, False])


def thresholds(df: pd.DataFrame) -> pd.DataFrame:
    """Per d/l0: the cells each knit undid at each nominal tension, and the threshold's bracket (NaN where
    no tension held on every knit, or none laddered on every knit; a point whose knits disagree brackets
    nothing)."""
    out = []
    for d_l0, g in df[df.status == "ok"].groupby("d_over_l0"):
        held, laddered, cells = [], [], []
        for fx, p in g.groupby("fx_nominal"):
            ladders = p.n_lad >= LADDERING_ONSET_CELLS
            if not ladders.any():
                held.append(fx)
            elif ladders.all():
                laddered.append(fx)
            cells.append(f"{fx:g}: " + ", ".join(f"{n:.0f}" for n in p.n_lad))
        below = max(held) if held else np.nan
        above = min([f for f in laddered if not f < below]) if laddered else np.nan
        out.append({"l0_over_d": 1 / d_l0, "held_up_to": below, "laddered_from": above,
                    "cells_per_knit": "; ".join(cells)})
    return pd.DataFrame(out).sort_values("l0_over_d", ascending=False)


def markdown(points: pd.DataFrame) -> str:
    def pm(row, name, digits=2):
        mean, se = row[name], row[name + "_se"]
        if not np.isfinite(mean):
            return "-"
        return f"{mean:.{digits}f}" + (f" +- {se:.{digits}f}" if np.isfinite(se) else "")

    lines = ["| l0/d | f_x^ini | knits (failed) | l_x/l0 | l_x0/l0 | l_x/l_x0 | n_lad/n_y | released/n_y "
             "| v_lad/c_b | f_x^fin crossed | edge |", "|" + "---|" * 11]
    for _, r in points.iterrows():
        lines.append(f"| {r.l0_over_d:.0f} | {pm(r, 'fx_ini')} | {int(r.knits)} ({int(r.failed)}) "
                     f"| {pm(r, 'lx_over_l0', 3)} | {pm(r, 'lx0_over_l0', 3)} "
                     f"| {pm(r, 'lx_over_lx0', 3)} | {pm(r, 'n_lad_over_ny')} "
                     f"| {pm(r, 'released_over_ny')} | {pm(r, 'v_lad_over_cb', 3)} | {pm(r, 'fx_fin_crossed')} "
                     f"| {int(r.edge)} |")
    return "\n".join(lines)


def plot(points: pd.DataFrame, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(15, 3.6))
    names = [("n_lad_over_ny", "n_lad/n_y"), ("v_lad_over_cb", "v_lad/c_b"), ("fx_fin_crossed", "f_x^fin (crossed)"),
             ("lx_over_lx0", "l_x/l_x0")]
    for (name, label), ax in zip(names, axes):
        for fx, g in points.groupby("fx_nominal"):
            ax.errorbar(1 / g.l0_over_d, g[name], yerr=g[name + "_se"], marker="o", capsize=3,
                        label=f"f_x^ini = {fx:g}")
        ax.set_xlabel("d/l0")
        ax.set_ylabel(label)
    axes[0].legend()
    fig.suptitle("16 x 16 jersey, default preset, mu = 0.4, l_y/l0 = 0.25: laddering from loose to jammed")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--csv", type=Path)
    parser.add_argument("--png", type=Path)
    parser.add_argument("--threshold", action="store_true", help="bracket the threshold per d/l0")
    args = parser.parse_args()
    if args.threshold:
        brackets = thresholds(table(args.folder))
        print(brackets.to_string(index=False))
        if args.csv:
            brackets.to_csv(args.csv, index=False)
        return
    points = by_point(table(args.folder))
    print(markdown(points))
    if args.csv:
        points.to_csv(args.csv, index=False, float_format="%.5g")
    if args.png:
        plot(points, args.png)


if __name__ == "__main__":
    main()
