"""The paper's two DER points under each dissipation (docs/dissipation.md): which assumption each point needs.

The paper's own DER gives v_lad/c_b = 1.05 at f_x^ini 15.67 and 0.176 at 1.58 (42 x 42, mu 0.4, d/l0 1/70,
straight yarn; l_y/l0 = 0.25 for the 42 x 42 crosses of Fig. 5a). Each point is laddered under each variant:

    none          friction and the numerical dashpots only (the default)
    material      the Nylon's viscoelasticity, loss factor 0.03 at 3.1 kHz
    air           still air
    both          material and air
    drag <g>      the authors' global drag -g m v [1/s] (not physics); 6000, 8000 and 10000 run when named
    d/l0 1/60     the public engine's yarn (its own stretched knits)
    k x0.5, k x2  the contact stiffness halved and doubled (their own stretched knits)
    ly 0.302      the other l_y of the paper's 42 x 42 crosses (Fig. 5a)
    twist         the yarns carry twist, so friction also turns them (ly 0.302 and twist run when named)

Paired ensembles: member k of a point is one knit (force-control targets 0.5 % apart,
knitlad/studies/ensemble.py) cut under every dissipation variant that keeps its knit; the model's
sensitivities (``SENSITIVITY``) on the first knit only. A run stops once a front has run
``--stop-after`` stitches (the velocity is fitted from stitch 2 to 10). Runs are dealt out in turn between
``--shards`` processes (one per core, one Numba thread each), each stretching the knits of its runs (the
stretch is deterministic: the same knit in each); rows go to ``<out>/attribution<size>.csv`` after every run
(resumable).

    python scripts/paper/dissipation_attribution.py --shard 0 --shards 2 &
    python scripts/paper/dissipation_attribution.py --shard 1 --shards 2 &
    python scripts/paper/dissipation_attribution.py --table      # the table of docs/dissipation.md
"""

from __future__ import annotations

import argparse
import os
import subprocess
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from knitlad.engine.simulation import SimulationBlowUp  # noqa: E402
from knitlad.experiments.config import CutConfig  # noqa: E402
from knitlad.experiments.laddering import analyse, cut, propagate
from knitlad.fabric.preparation import stretch  # noqa: E402
from knitlad.fabric.observers import Interpenetration  # noqa: E402
from knitlad.studies.ensemble import resumed_rows, save_rows, target_offsets  # noqa: E402

KEY = ("fx_nominal", "member", "variant", "preset")
# variant -> (changes to the stretch, changes to the dynamics)
VARIANTS = {
    "none": ({}, {}),
    "material": ({}, {"loss_factor": 0.03}),
    "air": ({}, {"air_drag": True}),
    "both": ({}, {"loss_factor": 0.03, "air_drag": True}),
    "drag 1000": ({}, {"drag_per_s": 1000.0}),
    "drag 2000": ({}, {"drag_per_s": 2000.0}),
    "drag 3000": ({}, {"drag_per_s": 3000.0}),
    "drag 6000": ({}, {"drag_per_s": 6000.0}),
    "drag 8000": ({}, {"drag_per_s": 8000.0}),
    "drag 10000": ({}, {"drag_per_s": 10000.0}),  # the order of the public example's second drag (0.01 per axial-wave time)
    "d/l0 1/60": ({"d_over_l0": 1 / 60}, {}),
    "k x0.5": ({"contact_force_f0": 10.0}, {}),
    "k x2": ({"contact_force_f0": 40.0}, {}),
    "ly 0.302": ({"ly": 0.302}, {}),
    "twist": ({}, {"twist": True}),
}


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


ASKED = ("ly 0.302", "twist", "drag 6000", "drag 8000", "drag 10000")  # run only when named (--variants)
# the model's sensitivities (not dissipations): on the first knit of each point only
SENSITIVITY = ("drag 1000", "d/l0 1/60", "k x0.5", "k x2", "ly 0.302", "twist")


def runs(points: list[float], members: list[int], variants: list[str], shard: int, shards: int) -> list[tuple]:
    """This shard's runs, (point, member, members, variant), knit by knit: the runs of one knit (one stretch)
    are dealt out in turn between the shards (each stretches it: the stretch is deterministic, so both get the
    same knit), so the shards end together. The sensitivities run on member 0 only."""
    out, turn = [], 0
    for fx, n in zip(points, members):
        for k in range(n):
            by_stretch: dict[str, list[str]] = {}
            for v in variants:
                if k == 0 or v not in SENSITIVITY:
                    by_stretch.setdefault(repr(sorted(VARIANTS[v][0].items())), []).append(v)
            for names in by_stretch.values():
                for v in names:
                    if turn % shards == shard:
                        out.append((fx, k, n, v))
                    turn += 1
    return out


PAPER = {15.67: 1.05, 1.58: 0.176}  # the paper's DER v_lad/c_b at its two points


def table(csv) -> str:
    """The attribution table (markdown): per variant and point, the mean v_lad/c_b over the knits (+- its
    standard error where there are several), the paired change against "none" on the same knits, and the
    ratio to the paper's DER value."""
    import pandas as pd

    df = pd.read_csv(csv)
    df = df[df["v_lad_over_cb"].notna()]
    lines = ["| variant | preset | " + " | ".join(f"f_x^ini {fx}: v_lad/c_b (knits) | paired change | / paper "
                                                for fx in PAPER) + " |",
             "|---|---|" + "---|---|---|" * len(PAPER)]
    for (variant, preset), g in df.groupby(["variant", "preset"], sort=False):
        cells = []
        for fx, paper in PAPER.items():
            h = g[g["fx_nominal"] == fx]
            if not len(h):
                cells += ["", "", ""]
                continue
            v = h["v_lad_over_cb"]
            se = f" +- {v.std(ddof=1) / len(v) ** 0.5:.3f}" if len(v) > 1 else ""
            base = df[(df["variant"] == "none") & (df["preset"] == preset) & (df["fx_nominal"] == fx)]
            pairs = h.merge(base, on="member", suffixes=("", "_none"))
            change = (pairs["v_lad_over_cb"] / pairs["v_lad_over_cb_none"] - 1.0) * 100
            ch = (f"{change.mean():+.0f} %" + (f" +- {change.std(ddof=1) / len(change) ** 0.5:.0f}" if len(change) > 1
                                               else "")) if variant != "none" and len(change) else ""
            cells += [f"{v.mean():.3f}{se} ({len(v)})", ch, f"{v.mean() / paper:.2f}"]
        lines.append(f"| {variant} | {preset} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=42)
    p.add_argument("--points", type=float, nargs="+", default=[15.67, 1.58], help="target f_x^ini of each point")
    p.add_argument("--members", type=int, nargs="+", default=[1, 3], help="knits per point (paired ensemble)")
    p.add_argument("--variants", nargs="+", default=[v for v in VARIANTS if v not in ASKED], choices=list(VARIANTS))
    p.add_argument("--preset", default="default")
    p.add_argument("--ly", type=float, default=0.25)
    p.add_argument("--stop-after", type=int, default=12, help="stop once a front has run this many stitches")
    p.add_argument("--shard", type=int, default=0)
    p.add_argument("--shards", type=int, default=1)
    p.add_argument("--out", default="docs/reference")
    p.add_argument("--table", action="store_true", help="print the table of the runs done, and stop")
    args = p.parse_args()
    csv, rows = resumed_rows(args.out, f"attribution{args.size}")
    if args.table:
        print(table(csv))
        return
    done = {(r["fx_nominal"], r["member"], r["variant"], r["preset"]) for r in rows}
    code = commit()
    knit, knit_key, stretch_s = None, None, 0.0
    for fx, k, n, variant in runs(args.points, args.members, args.variants, args.shard, args.shards):
        if (fx, k, variant, args.preset) in done:
            continue
        base = CutConfig(n_x=args.size, n_y=args.size, fx=fx * (1 + target_offsets(n)[k]), knit_seed=k,
                         preset=args.preset, stop_after_stitches=args.stop_after,
                         **{"ly": args.ly, **VARIANTS[variant][0]})
        if knit_key != base.stretch_settings():  # a new knit; the runs of one knit come together
            t0 = time.perf_counter()
            knit, knit_key = stretch(base.stretch_settings()), base.stretch_settings()
            stretch_s = time.perf_counter() - t0
        cfg = base.replace(**VARIANTS[variant][1])
        row = {"fx_nominal": fx, "member": k, "variant": variant, "preset": args.preset, "fx_target": cfg.fx,
               "ly_target": cfg.ly, "fx_ini": knit.fx_ini, "lx_over_l0": knit.lx_over_l0,
               "ly_over_l0": knit.ly_over_l0, "resolution": cfg.resolution, "stretch_s": stretch_s,
               "commit": code, "date": time.strftime("%Y-%m-%d")}
        t1 = time.perf_counter()
        try:
            result = analyse(propagate(cut(knit, cfg.dynamics_settings())))
        except (Interpenetration, SimulationBlowUp) as error:  # a failed run is a result too: kept
            rows.append({**row, "error": str(error)})
            save_rows(csv, rows, KEY)
            print(f"{variant:10s} f_x {fx:5.2f} member {k}: failed: {error}", flush=True)
            continue
        s = result.summary()
        row.update({name: s[name] for name in (
            "v_lad_over_cb", "n_lad_over_ny", "fx_fin", "stop_reason", "reached_edge", "steps", "nodes",
            "energy_start_J", "energy_end_J", "dissipated_friction_J", "dissipated_contact_dashpot_J",
            "dissipated_axial_dashpot_J", "dissipated_material_J", "dissipated_air_J", "dissipated_global_drag_J",
            "ledger_residual", "ladders_up", "ladders_down")})
        row["ladder_s"] = time.perf_counter() - t1
        row["time_ms"] = result.times_s[-1] * 1e3 if result.times_s else float("nan")
        rows.append(row)
        save_rows(csv, rows, KEY)
        print(f"{variant:10s} f_x {fx:5.2f} member {k}: f_x^ini {knit.fx_ini:.3f} v {row['v_lad_over_cb']:.3f} "
              f"({row['ladder_s']:.0f} s, {row['steps']} steps, {s['stop_reason']})", flush=True)

if __name__ == "__main__":
    main()
