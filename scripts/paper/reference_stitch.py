"""The converged reference of the periodised stitch: f_x(l_x) at fixed l_y against the resolution.

For each l_y of ``--ly`` and each l_x of its grid, the periodised stitch (``knitlad stitch``)
is relaxed at every resolution of ``--resolutions``. From these rows
``scripts/paper/reference_tables.py`` derives f_x at fixed geometry, l_x at fixed f_x and the
f_x = 0 curve, each with its observed order. One Numba thread.

    python scripts/paper/reference_stitch.py [--ly 0.25 0.30 0.20] [--resolutions 24 36 48 64 96 140 200 280]
                                       [--out docs/reference]

Writes ``<out>/stitch.csv`` after every point (resumable: finished points are skipped).
"""

from __future__ import annotations

import argparse
import os

import numpy as np
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from knitlad.experiments.config import StitchConfig  # noqa: E402
from knitlad.fabric.stitch_model import StitchRun  # noqa: E402

from knitlad.studies.ensemble import resumed_rows, save_rows  # noqa: E402

# l_x/l0 grids: dense near the f_x = 0 width of each l_y, sparser above it
GRIDS = {
    0.20: [0.38, 0.385, 0.39, 0.395, 0.40, 0.41, 0.42],
    0.25: [0.32, 0.325, 0.33, 0.335, 0.34, 0.345, 0.35, 0.36, 0.37, 0.38, 0.39, 0.40],
    0.30: [0.255, 0.26, 0.265, 0.27, 0.28, 0.30, 0.32, 0.34],
}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ly", type=float, nargs="+", default=[0.25, 0.30, 0.20])
    p.add_argument("--resolutions", type=int, nargs="+", default=[24, 36, 48, 64, 96, 140, 200, 280])
    p.add_argument("--out", default="docs/reference")
    p.add_argument("--name", default="stitch", help="CSV name (another model variant: another name)")
    p.add_argument("--sagitta", type=float, default=0.0, help="the contact's sagitta correction, R in d (0: none)")
    p.add_argument("--redo-unconverged", type=int, default=0, metavar="N",
                   help="run again, with N FIRE steps per round (the final one 20 N), the points of these resolutions "
                        "whose relaxation did not reach its tolerance, and keep the new row")
    args = p.parse_args()
    csv, rows = resumed_rows(args.out, args.name)
    if args.redo_unconverged:
        redo = [r for r in rows if not r["converged"] and r["resolution"] in args.resolutions]
        rows = [r for r in rows if r not in redo]
    done = {(round(r["ly_over_l0"], 4), round(r["lx_over_l0"], 4), r["resolution"]) for r in rows}
    for res in args.resolutions:
        for ly in args.ly:
            for lx in GRIDS[ly] if not args.redo_unconverged else sorted({r["lx_over_l0"] for r in redo
                                                                          if np.isclose(r["ly_over_l0"], ly)
                                                                          and r["resolution"] == res}):
                if (round(ly, 4), round(lx, 4), res) in done:
                    continue
                cfg = StitchConfig(lx=lx, ly=ly, resolution=res, sagitta_radius=args.sagitta)
                t0 = time.perf_counter()
                choices = {"relax_steps": args.redo_unconverged} if args.redo_unconverged else {}
                result = StitchRun(cfg.settings(**choices)).run()
                row = {**result.summary(), "resolution": res, "sagitta_radius_d": args.sagitta,
                       "date": time.strftime("%Y-%m-%d")}
                row["wall_s"] = time.perf_counter() - t0
                rows.append(row)
                save_rows(csv, rows)
                print(f"l_y {ly:.3f} l_x {lx:.3f} res {res:3d}: f_x {row['fx']:8.4f} f_y {row['fy']:8.4f} "
                      f"{'converged' if row['converged'] else 'NOT converged'} ({row['wall_s']:.1f} s)", flush=True)


if __name__ == "__main__":
    main()
