"""Paper Fig. 3f with the arrest read where it happens: f_x^fin against f_x^ini, the mean over every course
beside the courses the ladder crossed and those it did not.

    python scripts/paper/final_tension.py runs/fig3f [--csv docs/reference/fig3f_summary.csv] [--png docs/fig3f.png]

Reads the summary of ``knitlad sweep docs/reference/fig3f.yaml`` (laddering until every front stopped).
Prints a markdown table.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from knitlad.viz.plots import final_tension_plot

COLUMNS = ["fx_ini", "fx_fin", "fx_fin_crossed", "fx_fin_intact", "n_lad_over_ny", "ladders_up", "ladders_down",
           "reached_edge", "stop_reason", "wall_s"]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folder", type=Path)
    p.add_argument("--csv", type=Path)
    p.add_argument("--png", type=Path)
    args = p.parse_args()
    table = pd.read_csv(args.folder / "summary.csv")
    table = table[table["status"] == "ok"].sort_values("fx_ini")[COLUMNS]
    print("| " + " | ".join(COLUMNS) + " |\n|" + "---|" * len(COLUMNS))
    for _, row in table.iterrows():
        print("| " + " | ".join(f"{v:.3f}" if isinstance(v, float) else str(v) for v in row) + " |")
    if args.csv:
        table.to_csv(args.csv, index=False, float_format="%.5g")
    if args.png:
        final_tension_plot(table, args.png)


if __name__ == "__main__":
    main()
