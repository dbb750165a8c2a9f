"""The tiled stretch against the affine one: the stretched knit and its ladder, over an ensemble.

Each member of an ensemble (force-control targets a fraction of a percent apart, so
the run-to-run scatter is sampled) is stretched both ways (``CutConfig.stretch_start``:
``tiled`` from the periodised stitch, ``affine`` from the built knit) and laddered with
the same dynamics. Prints the stretch's wall time and FIRE steps, l_x and l_y at the
reached f_x^ini, and v_lad/c_b, n_lad/n_y and f_x^fin of each way.

    python scripts/stretch_start.py [--size 16] [--tensions 4 13.6] [--members 3] [--out runs/stretch_start]

Writes ``<out>/stretch_start.csv`` (resumable) and prints a markdown table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import pandas as pd

from knitlad.config import CutConfig
from knitlad.protocol import analyse, cut, propagate, stretch

sys.path.insert(0, str(Path(__file__).parent))
from ensemble import ensemble_arguments, resumed_rows, save_rows, target_offsets  # noqa: E402

STARTS = ("tiled", "affine")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ensemble_arguments(p, tensions=[4.0, 13.6], members=3, out="runs/stretch_start")
    args = p.parse_args()
    csv, rows = resumed_rows(args.out, "stretch_start")
    done = {(r["size"], r["fx_nominal"], r["member"], r["start"]) for r in rows}
    offsets = target_offsets(args.members)
    for fx in args.tensions:
        for k, offset in enumerate(offsets):
            for start in STARTS:
                if (args.size, fx, k, start) in done:
                    continue
                cfg = CutConfig(preset="fast", n_x=args.size, n_y=args.size, fx=fx * (1 + offset), stretch_start=start)
                t = time.perf_counter()
                knit = stretch(cfg.stretch_settings())
                wall_stretch = time.perf_counter() - t
                r = analyse(propagate(cut(knit, cfg.dynamics_settings())))
                rows.append({"size": args.size, "fx_nominal": fx, "member": k, "start": start, "fx_ini": knit.fx_ini,
                             "lx": knit.lx_over_l0, "ly": knit.ly_over_l0, "fire_steps": knit.relax_steps,
                             "wall_stretch_s": wall_stretch, "v": r.v_lad_over_cb, "n_lad": r.n_lad_over_ny,
                             "fx_fin": r.fx_fin, "wall_propagate_s": time.perf_counter() - t - wall_stretch})
                print(f"{start:6s} f_x^ini {knit.fx_ini:6.3f} l_x {knit.lx_over_l0:.4f} l_y {knit.ly_over_l0:.4f} "
                      f"({knit.relax_steps} FIRE steps, {wall_stretch:.1f} s): v {r.v_lad_over_cb:.3f} "
                      f"n_lad/n_y {r.n_lad_over_ny:.2f} f_x^fin {r.fx_fin:.2f}", flush=True)
                save_rows(csv, rows)
    df = pd.DataFrame(rows)
    print("\n| N | f_x^ini | start | knits | stretch wall [s] | FIRE steps | l_x/l0 | l_y/l0 | v_lad/c_b | n_lad/n_y | f_x^fin |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for (size, fx, start), g in df.groupby(["size", "fx_nominal", "start"]):
        def pm(col: str, digits: int) -> str:
            return f"{g[col].mean():.{digits}f} +- {g[col].std(ddof=1):.{digits}f}" if len(g) > 1 else f"{g[col].mean():.{digits}f}"
        print(f"| {size} | {fx:g} | {start} | {len(g)} | {g.wall_stretch_s.mean():.1f} | {g.fire_steps.mean():.0f} | "
              f"{pm('lx', 4)} | {pm('ly', 4)} | {pm('v', 3)} | {pm('n_lad', 2)} | {pm('fx_fin', 2)} |")


if __name__ == "__main__":
    main()
