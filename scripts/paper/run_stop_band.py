"""Does a run-stop band hold the ladder? A table from a sweep over bands (configs/run_stop_band.yaml: the band's
friction; configs/run_stop_rib_band.yaml: a band knitted in rib beside the plain knit;
configs/run_stop_curvature_band.yaml: a band of a yarn with memory beside the plain knit).

    python scripts/paper/run_stop_band.py runs/run_stop_band [--csv FILE] [--png FILE]

For each job: the band (its first course and courses, what it is: friction x factor, rib, curvature K, or none for the
plain knit, read where the band would be), f_x^ini, the damage n_lad/n_y, how
far the ladders reached above and below the cut (the highest and lowest course with an undone cell, from
the job file's final ``laddered`` map), whether a ladder entered the band and whether one crossed it (an
undone cell above its last course), f_x^fin and v_lad/c_b. Prints a markdown table; with ``--png`` draws
each job's final map of undone cells with the band marked.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import h5py
import numpy as np
import pandas as pd

from knitlad.io.summary import markdown_table


def reach(h5: Path) -> tuple[np.ndarray, int, int]:
    """(the final laddered map (rows, columns), the highest and the lowest course with an undone cell)."""
    with h5py.File(h5, "r") as f:
        laddered = np.asarray(f["final/laddered"][()], dtype=bool)
    rows = np.flatnonzero(laddered.any(axis=1))
    return laddered, int(rows.max()) if rows.size else -1, int(rows.min()) if rows.size else -1


def table(folder: Path) -> pd.DataFrame:
    summary = pd.read_csv(folder / "summary.csv")
    out = []
    for _, job in summary.sort_values(["fx", "band_friction_factor"]).iterrows():
        if job.get("status", "ok") != "ok":
            continue
        _, top, bottom = reach(folder / "jobs" / f"{job.job_id}.h5")
        kind = job.get("band", "friction")
        if pd.isna(job.band_row):  # the plain knit beside a knitted band: where the band would be
            kind, first = "none", int(summary.band_row.dropna().iloc[0])
        else:
            first = int(job.band_row)
        last = first + int(job.band_courses) - 1
        factor = job.band_friction_factor if kind == "friction" else 1.0
        if kind == "curvature":  # a band of a yarn with memory: its K
            kind = f"curvature K{job.band_curvature:g}"
        out.append({"fx_nominal": job.get("fx_nominal", job.fx), "fx_ini": job.fx_ini, "band": f"{first}-{last}",
                    "kind": kind if kind != "friction" else f"friction x{factor:g}", "factor": factor,
                    "mu_band": job.mu * factor, "n_lad_over_ny": job.n_lad_over_ny,
                    "top_course": top, "bottom_course": bottom, "entered_band": top >= first,
                    "crossed_band": top > last, "fx_fin": job.fx_fin, "v_lad_over_cb": job.v_lad_over_cb,
                    "stop_reason": job.stop_reason, "job_id": job.job_id})
    return pd.DataFrame(out)


def by_point(df: pd.DataFrame) -> pd.DataFrame:
    """Per (nominal f_x, band: none, friction x factor, or a knitted pattern): the knits, how many crossed the
    band, n_lad/n_y and v_lad/c_b as mean and
    standard error over the knits (v over the runs that have a front fit)."""
    rows = []
    for (fx, kind), g in df.groupby(["fx_nominal", "kind"]):
        v = g.v_lad_over_cb.dropna()
        rows.append({"fx_nominal": fx, "band": kind, "knits": len(g), "crossed": int(g.crossed_band.sum()),
                     "n_lad_over_ny": g.n_lad_over_ny.mean(),
                     "n_lad_se": g.n_lad_over_ny.std(ddof=1) / np.sqrt(len(g)) if len(g) > 1 else np.nan,
                     "v_lad_over_cb": v.mean() if len(v) else np.nan,
                     "v_se": v.std(ddof=1) / np.sqrt(len(v)) if len(v) > 1 else np.nan})
    return pd.DataFrame(rows)


def panel_label(kind: str) -> str:
    """What a panel varies, in words: 'friction x3' is a band whose yarn has three times the fabric's friction."""
    if kind.startswith("friction x"):
        factor = float(kind[len("friction x"):])
        return "no band (the plain knit)" if factor == 1.0 else f"band friction {factor:g} x the fabric's mu"
    return "no band (the plain knit)" if kind == "none" else f"band: {kind}"


def draw(folder: Path, df: pd.DataFrame, png: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    df = df.drop_duplicates(["fx_nominal", "kind"])  # one knit per point: the first
    fig, axes = plt.subplots(1, len(df), figsize=(2.2 * len(df), 2.8), squeeze=False)
    for ax, (_, row) in zip(axes[0], df.iterrows()):
        laddered, _, _ = reach(folder / "jobs" / f"{row.job_id}.h5")
        ax.imshow(laddered, origin="lower", cmap="Greys", vmin=0, vmax=1)
        first, last = (int(v) for v in row.band.split("-"))
        ax.axhspan(first - 0.5, last + 0.5, color="tab:orange", alpha=0.35, lw=0)
        ax.set_title(f"f_x^ini {row.fx_ini:.1f}\n{panel_label(row.kind)}", fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle("undone cells (black) at the stop, the band's courses (orange)", fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=130)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folder", type=Path)
    p.add_argument("--csv")
    p.add_argument("--png")
    args = p.parse_args()
    df = table(args.folder)
    print(markdown_table(df.drop(columns=["job_id"])))
    print()
    print(markdown_table(by_point(df)))
    if args.csv:
        df.to_csv(args.csv, index=False)
    if args.png:
        draw(args.folder, df, args.png)
    print(json.dumps({"jobs": len(df)}))


if __name__ == "__main__":
    main()
