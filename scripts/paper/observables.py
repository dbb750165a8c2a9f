"""The observables as the paper reads them, from a laddering sweep with an ensemble axis.

    python scripts/paper/observables.py runs/observables16 [runs/observables16_onset ...] [--csv OUT.csv]

Per nominal f_x^ini (the ensemble's members are different knits: their own knit_seed, targets 0.5 % apart):
n_lad at the stop (the paper's photograph after the arrest) beside every cell undone at some time and the cells
hooked again; the two fronts (the laddering column's mid-line, the paper's reading, and the cells' first arrival);
the loop sequence read from where the cut thread went. Then f_x^thr twice: as the paper defines it, "the mean value
of f_x^fin for all experiments" that laddered and arrested (with its scatter, and the slope of f_x^fin against
f_x^ini that Fig. 3f finds flat), and as the onset bracket of the 4.2-cell rule on the final count. Every +- is
one standard deviation of the members unless it says otherwise. Prints markdown.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.experiments.resistance import LADDERING_ONSET_CELLS
from knitlad.fabric.measure import arrest_threshold
from knitlad.io.summary import mean_sd


def arrested(frame: pd.DataFrame) -> pd.Series:
    """A run that stopped on the arrest rule (the final state settled), not at an edge course or its time limit."""
    return frame.stop_reason.astype(str).str.startswith("no cell changed")


def onset_bracket(frame: pd.DataFrame) -> tuple[float, float]:
    """(highest nominal f_x^ini at which no member ladders, lowest at and above which every member ladders)."""
    by_point = frame.groupby("fx_point").n_lad.agg(["min", "max"]).sort_index()
    held = by_point.index[by_point["max"] < LADDERING_ONSET_CELLS]
    lower = float(held.max()) if len(held) else 0.0
    above = by_point[by_point.index > lower]
    every = [f for f in above.index if (above.loc[f:, "min"] >= LADDERING_ONSET_CELLS).all()]
    return lower, float(min(every)) if every else math.inf


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", help="sweep folders (their summary.csv) or summary CSVs")
    p.add_argument("--csv", help="write the finished runs' rows here (docs/reference/...)")
    args = p.parse_args()
    tables = []
    for run in args.runs:
        path = Path(run)
        tables.append(pd.read_csv(path / "summary.csv" if path.is_dir() else path))
    frame = pd.concat(tables, ignore_index=True)
    # a job pending in one sweep may be done in another (the same id): its result wins
    frame = frame.sort_values("status", key=lambda s: s.eq("pending"), kind="stable").drop_duplicates("job_id")
    done = frame[frame.status != "pending"]
    frame = frame[frame.status == "ok"].copy()
    # a member's point is its nominal target; a job run on its own, its fx to 0.1 (an ensemble's member lies within
    # 0.5 % of its target)
    nominal = frame.fx_nominal if "fx_nominal" in frame else pd.Series(np.nan, index=frame.index)
    frame["fx_point"] = nominal.where(nominal.notna(), frame.fx).round(1)
    frame["arrested"] = arrested(frame)
    if args.csv:
        done.to_csv(args.csv, index=False)
    failed = done[done.status == "failed"]
    for _, row in failed.iterrows():
        print(f"failed: f_x {row.fx:g} (knit_seed {row.get('knit_seed', '-')}): {row.error}")

    print("| f_x^ini (target) | knits | f_x^ini | n_lad at the stop | undone at some time | hooked again | stopped by "
          "| f_x^fin | v_lad/c_b, mid-line | first arrival | loop sequence |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for point, g in frame.groupby("fx_point"):
        stops = ", ".join(f"{n} {'arrest' if a else 'edge/time'}" for a, n in g.arrested.value_counts().items())
        sequences = "; ".join(sorted(set(g.loop_sequence.astype(object).fillna("-").astype(str))))
        print(f"| {point:g} | {len(g)} | {mean_sd(g.fx_ini)} | {mean_sd(g.n_lad)} | {mean_sd(g.n_lad_ever)} | "
              f"{mean_sd(g.n_lad_rehooked)} | {stops} | {mean_sd(g.fx_fin)} | {mean_sd(g.v_lad_over_cb)} | "
              f"{mean_sd(g.v_lad_first_arrival_over_cb)} | {sequences} |")

    laddered = frame.n_lad >= LADDERING_ONSET_CELLS
    thr = arrest_threshold(frame.fx_ini, frame.fx_fin, laddered, frame.arrested)
    stopped = arrest_threshold(frame.fx_ini, frame.fx_fin, laddered, np.ones(len(frame), dtype=bool))
    lower, upper = onset_bracket(frame)
    print()
    print(f"f_x^thr as the paper defines it (mean f_x^fin of the {thr['runs']} runs that laddered, "
          f">= {LADDERING_ONSET_CELLS} cells at the stop, and arrested): {thr['fx_thr']:.3g} +- {thr['fx_thr_sd']:.2g} "
          f"(scatter; standard error {thr['fx_thr_se']:.2g})")
    print(f"slope of f_x^fin against f_x^ini over those runs (Fig. 3f: flat): {thr['slope']:.3g} +- "
          f"{thr['slope_se']:.2g} (standard error)")
    print(f"f_x^fin at the stop of every run that laddered, arrested or not ({stopped['runs']} runs): "
          f"{stopped['fx_thr']:.3g} +- {stopped['fx_thr_sd']:.2g}; its slope against f_x^ini {stopped['slope']:.3g} +- "
          f"{stopped['slope_se']:.2g}")
    print(f"onset bracket (4.2-cell rule on the final count, every member): {lower:g} to {upper:g}")
    ever = frame.n_lad_ever >= LADDERING_ONSET_CELLS
    print(f"runs the latched count calls laddered but the final count does not: {int((ever & ~laddered).sum())} "
          f"of {len(frame)}")


if __name__ == "__main__":
    main()
