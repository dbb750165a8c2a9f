"""The tensile test of the knit patterns side by side (configs/tensile_patterns.yaml, docs/tensile.md).

    python scripts/paper/tensile_patterns.py runs/tensile_patterns [--csv FILE] [--png FILE]

For each job of the sweep (a pattern pulled along x at mu = 0.4 from its start l_x to the top and back): the
start and top of the box, the stretch from the start (the top's l_x over the start's, less one), f_x at the
start, the top and the end, friction's loop per stitch, and the stretch at which the loading first carries
f_x = 4 (linear between readings). Prints a markdown table; draws f_x against the box's l_x, loading solid and
unloading dashed, one colour per pattern.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import h5py
import numpy as np
import pandas as pd

from knitlad.io.summary import markdown_table

LEG, BOX_LX, FX = 0, 2, 6  # columns of knitlad.experiments.tensile.COLUMNS
LOADING, UNLOADING = 1, -1


def readings(h5: Path) -> np.ndarray:
    with h5py.File(h5, "r") as f:
        return np.asarray(f["tensile/readings"][()])


def stretch_at(r: np.ndarray, fx: float) -> float:
    """The box's stretch from its start, l_x/l_x(start) - 1, where the loading first reaches ``fx`` (NaN if
    it never does; 0 if it starts above)."""
    load = r[r[:, LEG] == LOADING]
    lx, f = load[:, BOX_LX], load[:, FX]
    above = np.flatnonzero(f >= fx)
    if not above.size:
        return float("nan")
    k = above[0]
    if k == 0:
        return 0.0
    at = lx[k - 1] + (lx[k] - lx[k - 1]) * (fx - f[k - 1]) / (f[k] - f[k - 1])
    return float(at / lx[0] - 1.0)


def table(folder: Path, fx_mark: float = 4.0) -> pd.DataFrame:
    summary = pd.read_csv(folder / "summary.csv")
    rows = []
    for _, job in summary[summary.status == "ok"].iterrows():
        r = readings(folder / "jobs" / f"{job.job_id}.h5")
        rows.append({"pattern": job.pattern, "mu": job.mu, "lx_start": r[0, BOX_LX], "lx_top": r[:, BOX_LX].max(),
                     "stretch_top": r[:, BOX_LX].max() / r[0, BOX_LX] - 1.0, "fx_start": job.fx_start,
                     "fx_top": job.fx_top, "fx_end": job.fx_end,
                     f"stretch_at_fx{fx_mark:g}": stretch_at(r, fx_mark),
                     "friction_loop_per_stitch": job.dissipated_per_stitch, "job_id": job.job_id})
    return pd.DataFrame(rows)


def draw(folder: Path, df: pd.DataFrame, png: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4))
    for (_, job), colour in zip(df.iterrows(), ("tab:blue", "tab:orange", "tab:green", "tab:red")):
        r = readings(folder / "jobs" / f"{job.job_id}.h5")
        top = int(np.argmax(r[:, BOX_LX]))
        ax.plot(r[: top + 1, BOX_LX], r[: top + 1, FX], "-o", ms=3, color=colour, label=f"{job.pattern}")
        ax.plot(r[top:, BOX_LX], r[top:, FX], "--", color=colour)
    ax.axhline(0, color="grey", lw=0.5)
    ax.set_xlabel("box l_x/l0")
    ax.set_ylabel("f_x = F_x/(n_y f0)")
    ax.set_title(f"tensile test along x at mu = {df.mu.iloc[0]:g}: loading solid, unloading dashed", fontsize=9)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png, dpi=120)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folder", type=Path)
    p.add_argument("--csv")
    p.add_argument("--png")
    args = p.parse_args()
    df = table(args.folder)
    print(markdown_table(df.drop(columns=["job_id"])))
    if args.csv:
        df.to_csv(args.csv, index=False)
    if args.png:
        draw(args.folder, df, args.png)
    print(json.dumps({"jobs": len(df)}))


if __name__ == "__main__":
    main()
