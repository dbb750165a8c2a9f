"""The laddering's time step, by paired runs: each stretched knit cut at several factors of the stability limit.

    python scripts/paper/paired_step_factor.py runs/step_factor_accurate [--reference 0.35] [--csv FILE]
    python scripts/paper/paired_step_factor.py docs/reference/step_factor_accurate_summary.csv
    python scripts/paper/paired_step_factor.py runs/continuous_edge16 --factor edge+bars --reference clamped+held

Reads a sweep over (f_x target, ``dt_safety``) (``docs/reference/step_factor_accurate.yaml``): the knits of one
nominal tension are targets a fraction of a percent apart, and every knit is laddered at every factor from the
same stretch (``--factor``: another column of the sweep that every knit was laddered at, such as ``edge``;
columns joined by ``+`` for a grid of
several, such as ``edge+bars``). Per nominal tension and factor it prints the mean observables and, per knit, the change against
the smallest factor (the reference): mean +- standard error over the knits. A factor may replace the reference
only where its paired change lies within two standard errors of zero and under the preset's stated error.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

OBSERVABLES = {"v_lad_over_cb": "v_lad/c_b", "n_lad_over_ny": "n_lad/n_y", "fx_fin": "f_x^fin"}


def nominal_tensions(targets: np.ndarray, spread: float = 0.02) -> dict[float, float]:
    """Each target f_x with the middle target of its group (targets within ``spread`` of each other)."""
    groups: list[list[float]] = []
    for fx in sorted(set(targets)):
        if groups and fx <= groups[-1][0] * (1 + spread):
            groups[-1].append(fx)
        else:
            groups.append([fx])
    return {fx: g[len(g) // 2] for g in groups for fx in g}


def paired_changes(df: pd.DataFrame, reference: float | None = None, factor: str = "dt_safety") -> pd.DataFrame:
    """One row per (nominal tension, factor): means, and the paired relative change of each observable
    against the ``reference`` factor (default: the smallest), mean and standard error over the knits that
    ran at both."""
    df = df[df["status"] == "ok"].copy()
    df["nominal"] = df["fx"].map(nominal_tensions(df["fx"].to_numpy()))
    rows = []
    for nominal, group in df.groupby("nominal"):
        ref = group[factor].min() if reference is None else reference
        base = group[group[factor] == ref].set_index("fx")
        for value, at in group.groupby(factor):
            at = at.set_index("fx")
            knits = at.index.intersection(base.index)
            row = {"fx_nominal": nominal, factor: value, "reference": ref, "knits": len(knits),
                   "fx_ini": at["fx_ini"].mean(), "steps": at["steps"].mean(),
                   "wall_propagate_s": at["wall_propagate_s"].mean()}
            for col in OBSERVABLES:
                row[col] = at[col].mean()
                change = 100.0 * (at.loc[knits, col] / base.loc[knits, col] - 1.0)
                row[f"{col}_change_pct"] = change.mean()
                row[f"{col}_change_se"] = change.std(ddof=1) / np.sqrt(len(knits)) if len(knits) > 1 else np.nan
            rows.append(row)
    return pd.DataFrame(rows).sort_values(["fx_nominal", factor], ascending=[True, factor != "dt_safety"])


def markdown(table: pd.DataFrame, factor: str = "dt_safety") -> str:
    head = f"| f_x^ini | {factor} | knits | steps | propagate [s] | " + " | ".join(
        f"{name} | change" for name in OBSERVABLES.values()) + " |"
    lines = [head, "|" + "---|" * (5 + 2 * len(OBSERVABLES))]
    for _, r in table.iterrows():
        cells = [f"{r.fx_ini:.2f}", f"{r[factor]}" if isinstance(r[factor], str) else f"{r[factor]:g}", f"{int(r.knits)}", f"{r.steps:,.0f}", f"{r.wall_propagate_s:.0f}"]
        for col in OBSERVABLES:
            change = "" if r[factor] == r.reference else f"{r[col + '_change_pct']:+.1f} +- {r[col + '_change_se']:.1f} %"
            cells += [f"{r[col]:.3f}", change]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run", type=Path, help="the sweep's output folder (its summary.csv), or a summary CSV")
    p.add_argument("--reference", default=None, help="the factor changes are taken against (default: the "
                   "smallest; a word for a column of words, such as bars: held)")
    p.add_argument("--factor", default="dt_safety", help="the column the knits were laddered at (default: dt_safety)")
    p.add_argument("--csv", type=Path, default=None, help="also write the table here")
    args = p.parse_args()
    summary = args.run if args.run.is_file() else args.run / "summary.csv"
    frame = pd.read_csv(summary)
    columns = args.factor.split("+")
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        p.error(f"--factor: the summary has no column {missing[0]!r}")
    if len(columns) > 1:  # a grid of several factors: each combination one level
        frame[args.factor] = frame[columns].astype(str).agg("+".join, axis=1)
    reference = args.reference
    if reference is not None and pd.api.types.is_numeric_dtype(frame[args.factor]):
        reference = float(reference)
    table = paired_changes(frame, reference, args.factor)
    print(markdown(table, args.factor))
    if args.csv is not None:
        table.to_csv(args.csv, index=False, float_format="%.6g")


if __name__ == "__main__":
    main()
