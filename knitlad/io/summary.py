"""The sweep summary table (pandas): one row per job, written atomically as CSV (and Parquet); and the tables
one run writes beside its file (``write_table``).

Columns: ``job_id``, ``scene``, the job's inputs (the fields of its scene config,
in the config's units), ``status`` (pending, ok, failed), ``error``, then the
results of :meth:`knitlad.experiments.laddering.LadderResult.summary` (f_x^ini, f_x^fin,
n_lad/n_y, v_lad/c_b, measured l_x/l0 and l_y/l0, wall times, ...).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from knitlad.io.atomic import atomic_path

TIMING_COLUMNS = ("wall_s", "job_wall_s", "wall_stretch_s", "wall_propagate_s")  # differ from run to run


def markdown_table(df: pd.DataFrame) -> str:
    """``df`` as a markdown table, its floats to 3 significant digits (the tables of docs/ and the paper scripts)."""
    lines = ["| " + " | ".join(str(c) for c in df.columns) + " |", "|" + "---|" * len(df.columns)]
    for _, row in df.iterrows():
        lines.append("| " + " | ".join(f"{v:.3g}" if isinstance(v, float) else str(v) for v in row) + " |")
    return "\n".join(lines)


def mean_sd(values, fmt: str = ".3g", sd_fmt: str = ".2g", scale: float = 1.0) -> str:
    """'mean +- standard deviation' of the finite ``values`` x ``scale`` (one: the value and '(1 run)'; none: '-'),
    the tables' way of giving a point over its knits."""
    import numpy as np

    v = np.asarray(values, dtype=float) * scale
    v = v[np.isfinite(v)]
    if len(v) == 0:
        return "-"
    if len(v) == 1:
        return f"{v[0]:{fmt}} (1 run)"
    return f"{v.mean():{fmt}} +- {v.std(ddof=1):{sd_fmt}}"


def summary_frame(rows: list[dict]) -> pd.DataFrame:
    return pd.DataFrame(rows)


def write_summary(out_dir: str | Path, rows: list[dict]) -> Path:
    """``out_dir/summary.csv`` (and ``summary.parquet`` if pyarrow is there), each by rename."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    df = summary_frame(rows)
    path = out / "summary.csv"
    with atomic_path(path) as tmp:
        df.to_csv(tmp, index=False)
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return path
    with atomic_path(out / "summary.parquet") as tmp:
        df.to_parquet(tmp, index=False)
    return path


def read_summary(out_dir: str | Path) -> pd.DataFrame:
    path = Path(out_dir) / "summary.csv"
    if not path.exists():
        raise FileNotFoundError(f"{path} not found (is {out_dir} a sweep folder?)")
    return pd.read_csv(path)


def write_table(path: str | Path, rows, columns) -> Path:
    """A CSV of ``rows`` (an array or a list of rows) under ``columns``, atomically."""
    with atomic_path(path) as tmp:
        pd.DataFrame(rows, columns=list(columns)).to_csv(tmp, index=False)
    return Path(path)
