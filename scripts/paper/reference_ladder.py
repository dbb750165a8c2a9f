"""The converged reference of the laddering knit: observables against the resolution, over ensembles of knits.

For each target tension f_x^ini and each resolution (nodes per stitch), an ensemble of
knits (force-control targets 0.5 % apart, as in knitlad/studies/ensemble.py) is stretched and
cut with the default dynamics. Every observable is kept per run: f_x^ini, the measured
l_x/l0 at that tension, v_lad/c_b, n_lad/n_y, f_x^fin, the last f_x sample, the step
count and the wall time. One Numba thread per run (run two of these at once on two cores,
never one run on two threads beside another).

    python scripts/paper/reference_ladder.py [--size 16] [--tensions 1.58 4 13.6] [--resolutions 24 48 96]
                                       [--members 3] [--out docs/reference]
    ... --sagitta 11 --implicit-axial --loss-factor 0.03 --air    # under the physical dissipations
                                                                   (docs/dissipation.md)

Writes ``<out>/ladder<size>.csv`` after every run (resumable: finished runs are skipped).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from knitlad.experiments.config import CutConfig  # noqa: E402
from knitlad.fabric.observers import Interpenetration  # noqa: E402
from knitlad.experiments.laddering import analyse, cut, propagate
from knitlad.fabric.preparation import stretch  # noqa: E402
from knitlad.engine.simulation import SimulationBlowUp  # noqa: E402
from knitlad.fabric.measure import front_arrivals  # noqa: E402

from knitlad.studies.ensemble import resumed_rows, save_rows, target_offsets  # noqa: E402


KEY = ("fx_nominal", "resolution", "member", "variant")  # one row per run: merged with other writers of the file


def front_arrivals_ms(result) -> str:
    """When the followed front first reached 1, 2, ... stitches above the cut [ms after the cut], ';'-joined:
    the raw record that v_lad and the step statistics of scripts/paper/front_steps.py are read from."""
    return ";".join(f"{t * 1e3:.4f}" for t in front_arrivals(result.times_s, result.front_up))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=16, help="knit size N for N x N")
    p.add_argument("--tensions", type=float, nargs="+", default=[1.58, 4.0, 13.6])
    p.add_argument("--resolutions", type=int, nargs="+", default=[24, 48, 96])
    p.add_argument("--members", type=int, default=3, help="knits per point (targets 0.5 %% apart)")
    p.add_argument("--member-offset", type=int, default=0, help="first member index (to add members later)")
    p.add_argument("--total-members", type=int, default=None,
                   help="ensemble size the offsets are spread over (default: --members)")
    p.add_argument("--sagitta", type=float, default=0.0, help="the contact's sagitta correction, R in d (0: none)")
    p.add_argument("--implicit-axial", action="store_true", help="implicit axial springs in the laddering")
    p.add_argument("--loss-factor", type=float, default=0.0, help="the yarn's material damping (0: none)")
    p.add_argument("--air", action="store_true", help="air drag in the laddering")
    p.add_argument("--out", default="docs/reference")
    p.add_argument("--need-arrivals", action="store_true",
                   help="rerun finished runs that lack the front's arrival times (runs are deterministic)")
    args = p.parse_args()
    variant = f"sagitta {args.sagitta:g}" + (" implicit" if args.implicit_axial else "") if args.sagitta or \
        args.implicit_axial else "plain"
    if args.loss_factor or args.air:  # the physical dissipations: docs/dissipation.md
        variant += (f" loss {args.loss_factor:g}" if args.loss_factor else "") + (" air" if args.air else "")
    csv, rows = resumed_rows(args.out, f"ladder{args.size}")
    done = {(r["fx_nominal"], r["resolution"], r["member"], r.get("variant") if isinstance(r.get("variant"), str)
             else "plain") for r in rows
            if not args.need_arrivals or isinstance(r.get("arrivals_ms"), str) or isinstance(r.get("error"), str)}
    new = []
    total = args.total_members or args.members
    offsets = target_offsets(total)
    for k in range(args.member_offset, args.member_offset + args.members):
        for fx in args.tensions:
            for res in args.resolutions:
                if (fx, res, k, variant) in done:
                    continue
                cfg = CutConfig(n_x=args.size, n_y=args.size, fx=fx * (1 + offsets[k]), resolution=res, knit_seed=k,
                                sagitta_radius=args.sagitta, implicit_axial=args.implicit_axial,
                                loss_factor=args.loss_factor, air_drag=args.air)
                t0 = time.perf_counter()
                knit = stretch(cfg.stretch_settings())
                t1 = time.perf_counter()
                try:
                    result = analyse(propagate(cut(knit, cfg.dynamics_settings())))
                except (Interpenetration, SimulationBlowUp) as error:  # a failed run is a result too: kept, not retried
                    new.append({"fx_nominal": fx, "resolution": res, "member": k, "variant": variant, "fx_target": cfg.fx,
                                 "fx_ini": knit.fx_ini, "lx_over_l0": knit.lx_over_l0, "error": str(error),
                                 "stretch_s": t1 - t0, "date": time.strftime("%Y-%m-%d")})
                    save_rows(csv, new, KEY)
                    print(f"f_x {fx:5.2f} res {res:3d} member {k}: failed: {error}", flush=True)
                    continue
                row = {"fx_nominal": fx, "resolution": res, "member": k, "variant": variant, "fx_target": cfg.fx,
                       "fx_ini": result.fx_ini, "lx_over_l0": result.lx_over_l0, "ly_over_l0": result.ly_over_l0,
                       "v_lad_over_cb": result.v_lad_over_cb, "n_lad_over_ny": result.n_lad_over_ny,
                       "fx_fin": result.fx_fin, "fx_last": result.fx_series[-1] if result.fx_series else float("nan"),
                       "stop_reason": result.stop_reason, "reached_edge": result.reached_edge,
                       **{k: v for k, v in result.energy_record().items() if k.startswith("dissipated")
                          or k == "ledger_residual"},
                       "arrivals_ms": front_arrivals_ms(result),
                       "steps": result.steps, "nodes": result.nodes,
                       "stretch_s": t1 - t0, "ladder_s": time.perf_counter() - t1,
                       "date": time.strftime("%Y-%m-%d")}
                new.append(row)
                save_rows(csv, new, KEY)  # only this process's runs: merged with the file, whoever else writes it
                print(f"{variant}: f_x {fx:5.2f} res {res:3d} member {k}: f_x^ini {row['fx_ini']:.3f} l_x {row['lx_over_l0']:.4f} "
                      f"v {row['v_lad_over_cb']:.3f} n {row['n_lad_over_ny']:.3f} fin {row['fx_fin']:.3f} "
                      f"({row['ladder_s']:.0f} s, {row['steps']} steps)", flush=True)


if __name__ == "__main__":
    main()
