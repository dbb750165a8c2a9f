"""The paper's two DER points under each dissipation (docs/dissipation.md): which assumption each point needs.

The paper's own DER gives v_lad/c_b = 1.05 at f_x^ini 15.67 and 0.176 at 1.58 (42 x 42, mu 0.4, d/l0 1/70,
straight yarn; l_y/l0 = 0.25 for the 42 x 42 crosses of Fig. 5a). Each point is laddered under each variant:

    none          friction and the numerical dashpots only (the default)
    material      the Nylon's viscoelasticity, loss factor 0.03 at 3.1 kHz
    air           still air
    both          material and air
    drag <g>      the authors' global drag -g m v [1/s] (not physics)
    d/l0 1/60     the public engine's yarn (its own stretched knits)
    k x0.5, k x2  the contact stiffness halved and doubled (their own stretched knits)

Paired ensembles: member k of a point is stretched once (force-control targets 0.5 % apart,
knitlad/studies/ensemble.py) and cut under every variant that keeps its knit. A run stops once a front has run
``--stop-after`` stitches (the velocity is fitted from stitch 2 to 10). Runs are shared out between
``--shards`` processes (one per core, one Numba thread each), each taking whole knits; rows go to
``<out>/attribution<size>.csv`` after every run (resumable).

    python scripts/paper/dissipation_attribution.py --shard 0 --shards 2 &
    python scripts/paper/dissipation_attribution.py --shard 1 --shards 2 &
"""

from __future__ import annotations

import argparse
import os
import subprocess
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from knitlad.engine.simulation import SimulationBlowUp  # noqa: E402
from knitlad.experiments.config import CutConfig  # noqa: E402
from knitlad.experiments.protocol import analyse, cut, propagate, stretch  # noqa: E402
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
    "d/l0 1/60": ({"d_over_l0": 1 / 60}, {}),
    "k x0.5": ({"contact_force_f0": 10.0}, {}),
    "k x2": ({"contact_force_f0": 40.0}, {}),
}


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def groups(points: list[float], members: list[int], variants: list[str]) -> list[tuple]:
    """(point, member, the stretch's changes, the variants laddered from that knit), in a fixed order."""
    out = []
    for fx, n in zip(points, members):
        for k in range(n):
            by_stretch: dict[str, list[str]] = {}
            for v in variants:
                by_stretch.setdefault(repr(sorted(VARIANTS[v][0].items())), []).append(v)
            for names in by_stretch.values():
                out.append((fx, k, n, VARIANTS[names[0]][0], names))
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=42)
    p.add_argument("--points", type=float, nargs="+", default=[15.67, 1.58], help="target f_x^ini of each point")
    p.add_argument("--members", type=int, nargs="+", default=[1, 3], help="knits per point (paired ensemble)")
    p.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    p.add_argument("--preset", default="default")
    p.add_argument("--ly", type=float, default=0.25)
    p.add_argument("--stop-after", type=int, default=12, help="stop once a front has run this many stitches")
    p.add_argument("--shard", type=int, default=0)
    p.add_argument("--shards", type=int, default=1)
    p.add_argument("--out", default="docs/reference")
    args = p.parse_args()
    csv, rows = resumed_rows(args.out, f"attribution{args.size}")
    done = {(r["fx_nominal"], r["member"], r["variant"], r["preset"]) for r in rows}
    code = commit()
    for g, (fx, k, n, stretch_changes, names) in enumerate(groups(args.points, args.members, args.variants)):
        if g % args.shards != args.shard:
            continue
        todo = [v for v in names if (fx, k, v, args.preset) not in done]
        if not todo:
            continue
        base = CutConfig(n_x=args.size, n_y=args.size, fx=fx * (1 + target_offsets(n)[k]), ly=args.ly,
                         preset=args.preset, stop_after_stitches=args.stop_after, **stretch_changes)
        t0 = time.perf_counter()
        knit = stretch(base.stretch_settings())
        stretch_s = time.perf_counter() - t0
        for variant in todo:
            cfg = base.replace(**VARIANTS[variant][1])
            row = {"fx_nominal": fx, "member": k, "variant": variant, "preset": args.preset, "fx_target": cfg.fx,
                   "ly_target": args.ly, "fx_ini": knit.fx_ini, "lx_over_l0": knit.lx_over_l0,
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
                "ledger_residual")})
            row["ladder_s"] = time.perf_counter() - t1
            row["time_ms"] = result.times_s[-1] * 1e3 if result.times_s else float("nan")
            rows.append(row)
            save_rows(csv, rows, KEY)
            print(f"{variant:10s} f_x {fx:5.2f} member {k}: f_x^ini {knit.fx_ini:.3f} v {row['v_lad_over_cb']:.3f} "
                  f"({row['ladder_s']:.0f} s, {row['steps']} steps, {s['stop_reason']})", flush=True)


if __name__ == "__main__":
    main()
