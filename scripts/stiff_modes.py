"""Softer axial and contact springs: how much faster, and how far the laddering moves. Paired runs.

The explicit step is set by the axial springs (EA) and the contact springs, not by the bending
waves that carry the ladder. Each variant softens them (``axial_stiffness_factor``: EA of the
dynamics, the tensions kept at the cut; ``overlap_fraction``: the contact's overlap at
``contact_force_f0``, the stretch too). Each knit of an ensemble (force-control targets 0.5 %
apart) is stretched once per stretch setting and laddered under every variant; the change of
v_lad, n_lad/n_y and f_x^fin against the configured model is averaged over the ensemble, with
the steps and the wall time of the dynamics.

    python scripts/stiff_modes.py [--size 16] [--tensions 4 13.6] [--members 3]
        [--variants axial_stiffness_factor=0.25 axial_stiffness_factor=0.25,overlap_fraction=0.2 ...]
        [--base twist=true] [--out runs/stiff_modes]

``--base``: settings of every run, the reference's too (``twist=true`` compares the variants
of the twisting yarn, e.g. ``twist_inertia_factor=16``).

Writes ``<out>/stiff_modes.csv`` (resumable) and prints a markdown table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.config import CutConfig
from knitlad.observers import Interpenetration
from knitlad.protocol import analyse, cut, propagate, stretch
from knitlad.simulation import SimulationBlowUp

sys.path.insert(0, str(Path(__file__).parent))
from ensemble import ensemble_arguments, resumed_rows, save_rows, target_offsets  # noqa: E402
from step_factor import parse_settings  # noqa: E402

REFERENCE = "as configured"
DEFAULT_VARIANTS = ["axial_stiffness_factor=0.25", "overlap_fraction=0.2",
                    "axial_stiffness_factor=0.25,overlap_fraction=0.2",
                    "axial_stiffness_factor=0.111,overlap_fraction=0.45"]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ensemble_arguments(p, tensions=[4.0, 13.6], members=3, out="runs/stiff_modes")
    p.add_argument("--variants", nargs="*", default=DEFAULT_VARIANTS, help="comma-separated name=value settings")
    p.add_argument("--resolution", type=int, default=24, help="nodes per stitch")
    p.add_argument("--base", nargs="*", default=[], help="name=value settings of every run, the reference's too")
    args = p.parse_args()
    base = parse_settings(args.base)
    variants = [REFERENCE] + [v for v in args.variants if v != REFERENCE]
    csv, rows = resumed_rows(args.out, "stiff_modes")
    done = {(r["variant"], r["fx_nominal"], r["member"]) for r in rows}
    for fx in args.tensions:
        for k, offset in enumerate(target_offsets(args.members)):
            knits = {}  # stretch settings -> the knit stretched with them
            for variant in variants:
                if (variant, fx, k) in done:
                    continue
                settings = base | ({} if variant == REFERENCE else parse_settings(variant.split(",")))
                cfg = CutConfig(preset="fast", n_x=args.size, n_y=args.size, fx=fx * (1 + offset), resolution=args.resolution,
                                **settings)
                key = cfg.stretch_settings()
                if key not in knits:
                    knits[key] = stretch(key)
                knit = knits[key]
                t = time.perf_counter()
                run = cut(knit, cfg.dynamics_settings())
                row = {"variant": variant, "fx_nominal": fx, "member": k, "fx_ini": knit.fx_ini, "dt_s": run.sim.dt_s}
                try:
                    r = analyse(propagate(run))
                    row.update(v=r.v_lad_over_cb, n_lad=r.n_lad_over_ny, fx_fin=r.fx_fin, steps=r.steps, error="")
                except (Interpenetration, SimulationBlowUp) as e:  # too soft for this tension: a result too
                    row.update(v=np.nan, n_lad=np.nan, fx_fin=np.nan, steps=run.sim.steps, error=str(e))
                rows.append({**row, "wall_s": time.perf_counter() - t})
                print(f"{variant:>50s} f_x {knit.fx_ini:6.3f}: dt {row['dt_s']:.3e} s, v {row['v']:.4f} "
                      f"n_lad/n_y {row['n_lad']:.3f} f_x^fin {row['fx_fin']:.3f} ({rows[-1]['wall_s']:.0f} s) "
                      f"{row['error']}", flush=True)
                save_rows(csv, rows)
    table(pd.DataFrame(rows))


def table(df: pd.DataFrame) -> None:
    print("\n| variant | f_x^ini | knits | dt [s] | steps | wall | v_lad/c_b | paired change of v | n_lad/n_y "
          "| change | f_x^fin | change |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for fx, g in df.groupby("fx_nominal"):
        ref = g[g.variant == REFERENCE].set_index("member")
        for variant, h in g.groupby("variant", sort=False):
            h = h.set_index("member")
            cells = []
            for col in ("v", "n_lad", "fx_fin"):
                change = (h[col] - ref[col].reindex(h.index)) / ref[col].reindex(h.index)
                se = change.std(ddof=1) / np.sqrt(change.count()) if change.count() > 1 else float("nan")
                cells.append(f"{h[col].mean():.3f} | {change.mean():+.1%} +- {se:.1%}")
            failed = int(h.v.isna().sum())
            variant = f"{variant} ({failed} failed, see error)" if failed else variant
            print(f"| {variant} | {fx:g} | {len(h)} | {h.dt_s.mean():.2e} | {h.steps.mean():.0f} | "
                  f"{h.wall_s.mean():.0f} s | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
