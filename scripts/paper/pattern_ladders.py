"""A dropped stitch in each knit pattern: the table and the pictures of a patterns sweep (configs/patterns.yaml).

    python scripts/paper/pattern_ladders.py runs/patterns [--csv FILE] [--png FILE]

Per job: the pattern, f_x^ini, the knit's (l_x, l_y)/l0, n_lad/n_y (and the cells released into loaded courses),
the ladders up and down, the columns the damage spread over, v_lad/c_b, f_x^fin of the crossed courses and why
the run stopped. With ``--png``: each job's last frame seen from the front, side by side.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pandas as pd

ORDER = {"jersey": 0, "rib": 1, "garter": 2}


def spread(h5: Path) -> tuple[int, int]:
    """(columns with an undone cell, courses with one) in the job's final map."""
    with h5py.File(h5, "r") as f:
        laddered = np.asarray(f["final/laddered"][()], dtype=bool)
    return int(laddered.any(axis=0).sum()), int(laddered.any(axis=1).sum())


def table(folder: Path) -> pd.DataFrame:
    summary = pd.read_csv(folder / "summary.csv")
    rows = []
    for _, job in summary[summary.status == "ok"].iterrows():
        columns, courses = spread(folder / "jobs" / f"{job.job_id}.h5")
        rows.append({"pattern": job.pattern, "fx_ini": job.fx_ini, "lx_over_l0": job.lx_over_l0,
                     "ly_over_l0": job.ly_over_l0, "n_lad_over_ny": job.n_lad_over_ny,
                     "released_over_ny": job.n_lad_released_over_ny, "ladders_up": int(job.ladders_up),
                     "ladders_down": int(job.ladders_down), "columns": columns, "courses": courses,
                     "v_lad_over_cb": job.v_lad_over_cb, "fx_fin_crossed": job.fx_fin_crossed,
                     "stop": job.stop_reason, "job_id": job.job_id})
    out = pd.DataFrame(rows)
    out["order"] = out.pattern.map(ORDER)
    out["fx_nominal"] = out.fx_ini.round(0)
    return out.sort_values(["fx_nominal", "order"]).drop(columns=["order"])


def markdown(df: pd.DataFrame) -> str:
    lines = ["| pattern | f_x^ini | l_x/l0, l_y/l0 | n_lad/n_y (released) | ladders up, down | columns, courses "
             "undone | v_lad/c_b | f_x^fin crossed | stop |", "|" + "---|" * 9]
    for _, r in df.iterrows():
        v = "-" if not np.isfinite(r.v_lad_over_cb) else f"{r.v_lad_over_cb:.3f}"
        lines.append(f"| {r.pattern} | {r.fx_ini:.2f} | {r.lx_over_l0:.3f}, {r.ly_over_l0:.3f} | "
                     f"{r.n_lad_over_ny:.2f} ({r.released_over_ny:.2f}) | {r.ladders_up}, {r.ladders_down} | "
                     f"{r.columns}, {r.courses} | {v} | {r.fx_fin_crossed:.2f} | {r.stop} |")
    return "\n".join(lines)


def pictures(folder: Path, df: pd.DataFrame, png: Path) -> None:
    """Each job's last frame from the front (knitlad.viz.render), side by side, a row per f_x^ini."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from knitlad.viz.render import Run, render_run

    tensions = sorted(df.fx_nominal.unique())
    patterns = sorted(df.pattern.unique(), key=ORDER.get)
    fig, axes = plt.subplots(len(tensions), len(patterns), figsize=(4.2 * len(patterns), 3.4 * len(tensions)),
                             squeeze=False)
    with tempfile.TemporaryDirectory() as tmp:
        for _, r in df.iterrows():
            h5 = folder / "jobs" / f"{r.job_id}.h5"
            run, f = Run.open(h5)
            last = float(run.times_s[-1])
            f.close()
            path = render_run(h5, Path(tmp) / r.job_id, times_s=[last], views=("front",), size=(900, 675))[-1]
            image = plt.imread(path)
            ax = axes[tensions.index(r.fx_nominal), patterns.index(r.pattern)]
            ax.imshow(image[int(0.06 * image.shape[0]):int(0.9 * image.shape[0])])
            ax.set_title(f"{r.pattern}, f_x^ini {r.fx_ini:.1f}: n_lad/n_y {r.n_lad_over_ny:.2f}", fontsize=9)
    for ax in axes.ravel():
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(png, dpi=100)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--csv", type=Path)
    parser.add_argument("--png", type=Path)
    args = parser.parse_args()
    df = table(args.folder)
    print(markdown(df))
    if args.csv:
        df.drop(columns=["job_id"]).to_csv(args.csv, index=False, float_format="%.5g")
    if args.png:
        pictures(args.folder, df, args.png)


if __name__ == "__main__":
    main()
