"""Does the friction couple change the ladder? Paired runs, twist off and on, over an ensemble of knits.

One ladder's v_lad scatters from knit to knit (about +-20 % at low tension: a
perturbation far below any setting's effect sends the stick-slip releases down
another path), so one pair of runs cannot tell an effect from the scatter. Here
each knit of an ensemble (force-control targets a fraction of a percent apart)
is stretched once and cut twice (one StretchedKnit, two runs): twist-free (the
default) and with twist (CutConfig.twist: friction also turns the yarns). The paired change is averaged over the ensemble, with its standard error.

    python scripts/twist_ensemble.py [--size 16] [--tensions 1.6 4 13.6] [--members 5] [--out runs/twist]

Writes ``<out>/twist_ensemble.csv`` (resumable) and prints a markdown table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.config import CutConfig
from knitlad.protocol import analyse, cut, propagate, stretch

sys.path.insert(0, str(Path(__file__).parent))
from ensemble import ensemble_arguments, resumed_rows, save_rows, target_offsets  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ensemble_arguments(p, tensions=[1.6, 4.0, 13.6], members=5, out="runs/twist")
    args = p.parse_args()
    csv, rows = resumed_rows(args.out, "twist_ensemble")
    done = {(r["fx_nominal"], r["member"]) for r in rows}
    offsets = target_offsets(args.members)
    for fx in args.tensions:
        for k, offset in enumerate(offsets):
            if (fx, k) in done:
                continue
            cfg = CutConfig(preset="fast", n_x=args.size, n_y=args.size, fx=fx * (1 + offset))
            knit = stretch(cfg.stretch_settings())
            row = {"fx_nominal": fx, "member": k, "fx_ini": knit.fx_ini}
            for label, twist in (("free", False), ("twist", True)):
                t = time.perf_counter()
                result = analyse(propagate(cut(knit, cfg.model_copy(update={"twist": twist}).dynamics_settings())))
                row[f"v_{label}"] = result.v_lad_over_cb
                row[f"n_{label}"] = result.n_lad_over_ny
                row[f"wall_{label}_s"] = time.perf_counter() - t
            rows.append(row)
            print(f"f_x {row['fx_ini']:6.3f}  v {row['v_free']:.4f} -> {row['v_twist']:.4f}   "
                  f"n_lad/n_y {row['n_free']:.3f} -> {row['n_twist']:.3f}   "
                  f"{row['wall_free_s']:.0f} s / {row['wall_twist_s']:.0f} s", flush=True)
            save_rows(csv, rows)
    df = pd.DataFrame(rows)
    print("\n| f_x^ini | knits | v_lad/c_b twist-free | with twist | paired change (mean +- s.e.) "
          "| n_lad/n_y twist-free | with twist | wall with / without twist |")
    print("|---|---|---|---|---|---|---|---|")
    for fx, g in df.groupby("fx_nominal"):
        change = (g.v_twist - g.v_free) / g.v_free
        se = change.std(ddof=1) / np.sqrt(len(g)) if len(g) > 1 else float("nan")
        print(f"| {fx:g} | {len(g)} | {g.v_free.mean():.3f} +- {g.v_free.std(ddof=1):.3f} | "
              f"{g.v_twist.mean():.3f} +- {g.v_twist.std(ddof=1):.3f} | {change.mean():+.1%} +- {se:.1%} | "
              f"{g.n_free.mean():.3f} | {g.n_twist.mean():.3f} | {(g.wall_twist_s / g.wall_free_s).mean():.2f} |")


if __name__ == "__main__":
    main()
