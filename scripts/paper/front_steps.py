"""What of a stick-slip ladder converges with the resolution: the front's step speeds and its mean speed.

Reads the front's arrival times that scripts/paper/reference_ladder.py records with each run
(``arrivals_ms`` in ``<ref>/ladder<size>.csv``) and prints, per target tension and resolution
(runs pooled over the ensemble's knits), in units of c_b:

* v_lad: the paper's fit over stitches 2 to 10 (mean +- standard error over the knits);
* the mean speed over the ladder's whole run, stitch 1 to the farthest, stalls included
  (:func:`knitlad.fabric.measure.mean_front_speed`; measured for arrested ladders too);
* the step speeds' distribution (:func:`knitlad.fabric.measure.front_step_speeds`): median and
  quartiles of l_y over the time between two arrivals, all steps of all knits pooled, and the
  slowest step's speed over that median (how deep the stick-slip's stalls are).

    python scripts/paper/front_steps.py [--ref docs/reference] [--size 16] [--variant "sagitta 11 implicit loss 0.03 air"]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.engine.units import NYLON
from knitlad.fabric.measure import front_step_speeds, mean_front_speed

DISSIPATED = "sagitta 11 implicit loss 0.03 air"


def arrivals_of(row) -> np.ndarray:
    """The front's arrival times of one run [s] (empty where the run recorded none)."""
    text = row.get("arrivals_ms")
    if not isinstance(text, str) or not text:
        return np.zeros(0)
    return np.array([float(t) for t in text.split(";")]) * 1e-3


def run_measures(row) -> dict:
    arrivals = arrivals_of(row)
    l_y = float(row["ly_over_l0"]) * NYLON.stitch_length
    return {"v_fit": float(row["v_lad_over_cb"]), "v_run": mean_front_speed(arrivals, l_y) / NYLON.c_b,
            "steps": front_step_speeds(arrivals, l_y) / NYLON.c_b, "reached": len(arrivals)}


def mean_se(values) -> str:
    x = np.array([v for v in values if math.isfinite(v)])
    if x.size == 0:
        return "-"
    if x.size == 1:
        return f"{x[0]:.3f}"
    return f"{x.mean():.3f} +- {x.std(ddof=1) / math.sqrt(x.size):.3f}"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ref", default="docs/reference")
    p.add_argument("--size", type=int, default=16)
    p.add_argument("--variant", default=DISSIPATED)
    args = p.parse_args()
    df = pd.read_csv(Path(args.ref) / f"ladder{args.size}.csv")
    df["variant"] = df["variant"].fillna("plain")
    df = df[(df.variant == args.variant) & df.get("arrivals_ms", pd.Series(index=df.index, dtype=object)).notna()]
    print(f"\n### The front's speeds, {args.size} x {args.size}, variant '{args.variant}' (v / c_b)\n")
    print("| f_x^ini | nodes | knits | stitches reached | v_lad (fit 2-10) | mean over the run | "
          "step speed: median [quartiles] | steps | slowest / median |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (fx, res), g in df.groupby(["fx_nominal", "resolution"]):
        runs = [run_measures(r) for _, r in g.iterrows()]
        steps = np.concatenate([r["steps"] for r in runs])
        steps = steps[np.isfinite(steps)]
        if steps.size:
            q1, med, q3 = np.percentile(steps, [25, 50, 75])
            dist = f"{med:.3f} [{q1:.3f}, {q3:.3f}]"
            stalls = f"{steps.min() / med:.2f}"
        else:
            dist, stalls = "-", "-"
        print(f"| {fx:g} | {res} | {len(runs)} | {', '.join(str(r['reached']) for r in runs)} | "
              f"{mean_se(r['v_fit'] for r in runs)} | {mean_se(r['v_run'] for r in runs)} | {dist} | "
              f"{steps.size} | {stalls} |")
    print("\n(mean +- standard error over the knits; the step speeds of all knits pooled; the arrival times are "
          "the observations', every 20 us: a step's speed is known to 20 us over its duration)")


if __name__ == "__main__":
    main()
