"""How does the laddering depend on the time step? Paired runs over an ensemble of knits.

Each knit of an ensemble (force-control targets a fraction of a percent apart, so
the run-to-run scatter is sampled) is stretched once and cut at every time-step
factor (``CutConfig.dt_safety``, fraction of the stability limit). The change of
v_lad, n_lad/n_y and f_x^fin against the smallest factor is averaged over the
ensemble with its standard error. ``--set name=value`` changes a laddering
setting for every run (to test a suspected cause: ``--set contact_damping_ratio=0``).

    python scripts/step_factor.py [--size 16] [--tensions 13.6] [--members 3]
        [--factors 0.9 0.7 0.5 0.35 0.175] [--set name=value ...] [--out runs/step_factor]

Writes ``<out>/step_factor.csv`` (resumable) and prints a markdown table.
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


def parse_settings(pairs: list[str]) -> dict:
    out = {}
    for pair in pairs:
        name, _, value = pair.partition("=")
        out[name] = type(CutConfig.model_fields[name].default)(value) if value not in ("true", "false") else value == "true"
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ensemble_arguments(p, tensions=[13.6], members=3, out="runs/step_factor")
    p.add_argument("--factors", type=float, nargs="+", default=[0.9, 0.7, 0.5, 0.35, 0.175])
    p.add_argument("--resolution", type=int, default=24, help="nodes per stitch")
    p.add_argument("--set", nargs="*", default=[], dest="settings", help="name=value laddering settings")
    args = p.parse_args()
    settings = parse_settings(args.settings)
    label = ",".join(args.settings) or "as configured"
    csv, rows = resumed_rows(args.out, "step_factor")
    done = {(r["variant"], r["fx_nominal"], r["member"], r["dt_safety"]) for r in rows}
    offsets = target_offsets(args.members)
    for fx in args.tensions:
        for k, offset in enumerate(offsets):
            todo = [f for f in args.factors if (label, fx, k, f) not in done]
            if not todo:
                continue
            cfg = CutConfig(preset="fast", n_x=args.size, n_y=args.size, fx=fx * (1 + offset), resolution=args.resolution, **settings)
            knit = stretch(cfg.stretch_settings())
            for factor in todo:
                t = time.perf_counter()
                r = analyse(propagate(cut(knit, cfg.model_copy(update={"dt_safety": factor}).dynamics_settings())))
                rows.append({"variant": label, "fx_nominal": fx, "member": k, "fx_ini": knit.fx_ini,
                             "dt_safety": factor, "v": r.v_lad_over_cb, "n_lad": r.n_lad_over_ny, "fx_fin": r.fx_fin,
                             "steps": r.steps, "wall_s": time.perf_counter() - t})
                print(f"{label} f_x {knit.fx_ini:6.3f} factor {factor:5.3f}: v {r.v_lad_over_cb:.4f} "
                      f"n_lad/n_y {r.n_lad_over_ny:.3f} f_x^fin {r.fx_fin:.3f} ({rows[-1]['wall_s']:.0f} s)", flush=True)
                save_rows(csv, rows)
    df = pd.DataFrame(rows)
    print("\n| variant | f_x^ini | factor | knits | v_lad/c_b | paired change of v | n_lad/n_y | f_x^fin |")
    print("|---|---|---|---|---|---|---|---|")
    for (variant, fx), g in df.groupby(["variant", "fx_nominal"]):
        ref = g[g.dt_safety == g.dt_safety.min()].set_index("member")
        for factor, h in g.groupby("dt_safety"):
            h = h.set_index("member")
            change = (h.v - ref.v.reindex(h.index)) / ref.v.reindex(h.index)
            se = change.std(ddof=1) / np.sqrt(change.count()) if change.count() > 1 else float("nan")
            print(f"| {variant} | {fx:g} | {factor:g} | {len(h)} | {h.v.mean():.3f} | {change.mean():+.1%} +- {se:.1%} "
                  f"| {h.n_lad.mean():.2f} | {h.fx_fin.mean():.2f} |")


if __name__ == "__main__":
    main()
