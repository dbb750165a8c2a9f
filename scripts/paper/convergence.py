"""Speed against error: each observable against a reference run, per solver setting.

Settings varied one at a time from a baseline (24 nodes per stitch, contact
overlap 5 % of d at 20 f0, time step 0.7 x the stability limit; this study is
why knitlad now runs the laddering dynamics at 0.35, see docs/accuracy.md):

* nodes per stitch (the yarn's discretisation);
* contact stiffness, as the overlap fraction at the design force (k_n ~ 1/fraction);
* time-step factor (fraction of the stability limit).

Observables, each with its wall time:

* ``stitch``: f_x of the periodised stitch at (l_x, l_y) = (0.35, 0.25) l0 (f_x at fixed periodicities);
* ``loop``: the single-loop v_lad/c_b at f_x = 4, mu = 0.4;
* ``knit``: on an N x N knit (default 16 x 16, ``--size 42`` for the paper's),
  mu = 0.4, force control: v_lad/c_b and n_lad/n_y at f_x^ini = 4 and 13.6.

``--parts damping``: the model's dashpots (contact, normal and tangential; the
yarn's axial one), each varied alone about the current defaults, reported as the
change against the default run (``<out>/damping.csv``). ``--parts counting``: the
same for the contact counting of the dynamics, "union" (default) against the
conservative "all_pairs" (``<out>/counting.csv``). Twist with the friction couple:
``scripts/twist_ensemble.py`` (paired runs over an ensemble of knits).

Errors are per setting: the runs that vary one setting (with the default) are
compared with the finest of them (48 nodes per stitch; overlap 2.5 % of d; time
step 0.35 x the limit): error = |value - finest| / |finest|. The observed order
in the resolution is the slope of log(error) against log(nodes per stitch) over
the points coarser than the finest.
Writes ``<out>/convergence.csv`` and prints tables (markdown).

    python scripts/paper/convergence.py [--out docs/convergence] [--size 16] [--parts stitch loop knit scatter damping counting]
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from knitlad.io.atomic import atomic_path  # noqa: E402

DEFAULT = {"nodes_per_stitch": 24, "overlap_fraction": 0.05, "dt_safety": 0.7}
STUDY = {
    "nodes_per_stitch": [16, 24, 36, 48],
    "overlap_fraction": [0.1, 0.05, 0.025],
    "dt_safety": [0.7, 0.35, 0.175],
}
FINEST = {"nodes_per_stitch": max, "overlap_fraction": min, "dt_safety": min}


def variations(static: bool = False, only: list[str] | None = None) -> list[dict]:
    """The default, then each setting varied alone (``only``: just these settings)."""
    out = [dict(DEFAULT, varied="default")]
    for key, values in STUDY.items():
        if only and key not in only:
            continue
        if static and key == "dt_safety":
            continue  # a static relaxation has no time step to vary
        for v in values:
            if v != DEFAULT[key]:
                out.append(dict(DEFAULT, **{key: v}, varied=key))
    return out


def stitch_run(cfg: dict) -> dict:
    from knitlad.experiments.config import StitchConfig
    from knitlad.fabric.stitch_model import StitchRun

    t = time.perf_counter()
    res = StitchRun(StitchConfig(preset="fast", lx=0.35, ly=0.25, resolution=cfg["nodes_per_stitch"]).settings(
        overlap_fraction=cfg["overlap_fraction"])).run()
    return {"observable": "stitch f_x (0.35, 0.25)", "value": res.fx, "wall_s": time.perf_counter() - t}


def loop_run(cfg: dict) -> dict:
    from knitlad.experiments.config import LoopConfig
    from knitlad.experiments.loop_model import LoopRun

    t = time.perf_counter()
    res = LoopRun(LoopConfig(fx=4.0, mu=0.4, resolution=cfg["nodes_per_stitch"]).settings(
        overlap_fraction=cfg["overlap_fraction"], dt_safety=cfg["dt_safety"])).run()
    return {"observable": "loop v_lad/c_b (f_x 4)", "value": res.v_lad_over_cb, "wall_s": time.perf_counter() - t}


def knit_runs(cfg: dict, size: int, tensions: list[float], nominal: float | None = None) -> list[dict]:
    """v_lad and n_lad at each target; ``nominal``: the tension named in the labels (default: the target)."""
    from knitlad.experiments.config import CutConfig
    from knitlad.experiments.laddering import run_ladder

    rows = []
    for fx in tensions:
        label = fx if nominal is None else nominal
        t = time.perf_counter()
        res = run_ladder(CutConfig(preset="fast", n_x=size, n_y=size, fx=fx, mu=0.4, max_time_ms=30.0,
                                   resolution=cfg["nodes_per_stitch"], overlap_fraction=cfg["overlap_fraction"],
                                   dt_safety=cfg["dt_safety"]).settings())
        wall = time.perf_counter() - t
        rows.append({"observable": f"knit {size}x{size} v_lad/c_b (f_x {label:g})", "value": res.v_lad_over_cb,
                     "wall_s": wall, "fx_ini": res.fx_ini})
        rows.append({"observable": f"knit {size}x{size} n_lad/n_y (f_x {label:g})", "value": res.n_lad_over_ny,
                     "wall_s": wall, "fx_ini": res.fx_ini})
    return rows


def scatter_runs(size: int, tensions: list[float], dt_safety: float = DEFAULT["dt_safety"]) -> pd.DataFrame:
    """The default setting at targets 0.5 % apart: how far a knit observable moves under a
    perturbation far below any setting's effect (laddering is a sequence of stick-slip
    events, so trajectories separate). Spread = (max - min) / mean."""
    rows = []
    for fx in tensions:
        for factor in (0.995, 1.0, 1.005):
            for r in knit_runs(dict(DEFAULT, dt_safety=dt_safety), size, [fx * factor], nominal=fx):
                rows.append(r)
                print(f"scatter  target {fx * factor:.3f}  {r['observable']:34s} {r['value']:.4f}  {r['wall_s']:.1f} s",
                      flush=True)
    df = pd.DataFrame(rows)
    return df.groupby("observable", sort=False).value.agg(
        min="min", max="max",
        mean="mean", spread=lambda v: (v.max() - v.min()) / abs(v.mean()), n="count").reset_index()


# drag_per_s: a global drag (0, the default, is the physics): 1e2 to 1e3 /s perturb the ladder
# without damping it (the scatter), 2e3 to 3e3 /s slow it at low tension only (docs/accuracy.md)
DAMPING = {"contact_damping_ratio": [0.1, 0.3, 0.6], "stretch_damping_ratio": [0.05, 0.2, 0.5],
           "drag_per_s": [1e2, 1e3, 2e3, 3e3]}
COUNTING = {"contact_counting": ["union", "all_pairs"]}


def model_runs(size: int, tensions: list[float], csv: Path, study: dict[str, list]) -> pd.DataFrame:
    """Model parameters rather than discretisation (the dashpots, the contact counting),
    each varied alone about knitlad's current defaults (CutConfig: 24 nodes/stitch,
    dynamics at 0.35 x the limit). Every one of them is a setting of the dynamics, so all runs at
    one tension ladder from one stretched knit (cut once per setting). There is no finest value to converge
    to: the change against the default run is what is reported, to be read against the
    run-to-run scatter. Resumable."""
    from knitlad.experiments.config import CutConfig
    from knitlad.experiments.laddering import analyse, cut, propagate
    from knitlad.fabric.preparation import stretch

    defaults = {name: f.default for name, f in CutConfig.model_fields.items()}
    rows = pd.read_csv(csv, dtype={"setting_value": str}).to_dict("records") if csv.exists() else []
    done = {(r["varied"], r["setting_value"], r["fx_target"]) for r in rows}
    # (varied, its value): the default run is labelled "default" (it varies nothing)
    cases = [("default", "default")] + [(k, v) for k, values in study.items() for v in values if v != defaults[k]]
    for fx in tensions:
        todo = [(key, value) for key, value in cases if (key, str(value), fx) not in done]
        if not todo:
            continue
        base = CutConfig(preset="fast", n_x=size, n_y=size, fx=fx, mu=0.4)
        knit = stretch(base.stretch_settings())
        for key, value in todo:
            t = time.perf_counter()
            dynamics = base.model_copy(update={} if key == "default" else {key: value}).dynamics_settings()
            res = analyse(propagate(cut(knit, dynamics)))
            wall = time.perf_counter() - t + knit.wall_s  # what a fresh run would cost
            rows.append({"varied": key, "setting_value": str(value), "fx_target": fx, "fx_ini": res.fx_ini,
                         "v_lad_over_cb": res.v_lad_over_cb, "n_lad_over_ny": res.n_lad_over_ny, "wall_s": wall})
            print(f"model  {key:22s} {value!s:9s}  f_x {fx:5.2f}  v {res.v_lad_over_cb:.4f}  "
                  f"n_lad/n_y {res.n_lad_over_ny:.3f}  {wall:.1f} s", flush=True)
            with atomic_path(csv) as tmp:
                pd.DataFrame(rows).to_csv(tmp, index=False)
    df = pd.DataFrame(rows)
    ref = df[df.varied == "default"].set_index("fx_target")
    for col in ("v_lad_over_cb", "n_lad_over_ny"):
        df[f"{col}_change"] = (df[col] - df.fx_target.map(ref[col])) / df.fx_target.map(ref[col]).abs()
    return df


def with_errors(df: pd.DataFrame) -> pd.DataFrame:
    """One row per (observable, setting, value of that setting) with its error against the finest value."""
    out = []
    for obs, sub in df.groupby("observable", sort=False):
        default = sub[sub.varied == "default"]
        for key, finest in FINEST.items():
            group = pd.concat([default, sub[sub.varied == key]])
            if len(group) < 2:
                continue
            ref = group[group[key] == finest(group[key])].value.iloc[0]
            g = group.assign(setting=key, reference=ref, rel_error=(group.value - ref).abs() / abs(ref))
            out.append(g.sort_values(key))
    return pd.concat(out, ignore_index=True)


def resolution_order(df: pd.DataFrame, observable: str) -> float:
    sub = df[(df.observable == observable) & (df.setting == "nodes_per_stitch") & (df.rel_error > 0)]
    if len(sub) < 2:
        return math.nan
    return float(-np.polyfit(np.log(sub.nodes_per_stitch), np.log(sub.rel_error), 1)[0])


def pareto_plot(df: pd.DataFrame, path: Path) -> None:
    """Wall time against error, one panel per observable; the default setting ringed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    observables = list(dict.fromkeys(df.observable))
    fig, axes = plt.subplots(1, len(observables), figsize=(4.2 * len(observables), 3.6), squeeze=False)
    style = {"nodes_per_stitch": ("o", "C0"), "overlap_fraction": ("s", "C1"), "dt_safety": ("^", "C2")}
    for ax, obs in zip(axes[0], observables):
        sub = df[df.observable == obs].copy()
        # each setting's finest run is its reference (error 0): drawn open, on a floor below the rest
        nonzero = sub.rel_error[sub.rel_error > 0]
        floor = (nonzero.min() if len(nonzero) else 1e-2) / 3
        sub["shown"] = sub.rel_error.where(sub.rel_error > 0, floor)
        for key, g in sub.groupby("setting"):
            marker, colour = style[key]
            ref = g.rel_error == 0
            ax.loglog(g.wall_s[~ref], g.shown[~ref], marker, color=colour, label=key.replace("_", " "))
            ax.loglog(g.wall_s[ref], g.shown[ref], marker, color=colour, mfc="none")
            for _, r in g.iterrows():
                label = f"{r[key]:g}" + (" (ref)" if r.rel_error == 0 else "")
                ax.annotate(label, (r.wall_s, r.shown), fontsize=7, xytext=(3, 3), textcoords="offset points")
        d = sub[(sub.varied == "default") & (sub.rel_error > 0)]
        ax.loglog(d.wall_s, d.shown, "o", mfc="none", ms=14, color="k", label="default (its error in each setting)")
        ax.axhline(floor * 1.5, color="0.8", lw=0.5)
        ax.set_title(obs, fontsize=9)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel("relative error (open: the reference)")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="docs/convergence")
    p.add_argument("--size", type=int, default=16, help="knit size N for N x N")
    p.add_argument("--parts", nargs="+", default=["stitch", "loop", "knit"],
                   choices=["stitch", "loop", "knit", "scatter", "damping", "counting"])
    p.add_argument("--tensions", type=float, nargs="+", default=[4.0, 13.6], help="knit: target f_x^ini values")
    p.add_argument("--resolutions", type=int, nargs="+", help="nodes per stitch to study (default 16 24 36 48)")
    p.add_argument("--dt-factors", type=float, nargs="+", help="time-step factors to study (default 0.7 0.35 0.175)")
    p.add_argument("--only", nargs="+", choices=list(STUDY), help="vary only these settings")
    p.add_argument("--scatter-dt", type=float, default=DEFAULT["dt_safety"], help="scatter: the time-step factor")
    args = p.parse_args()
    if args.resolutions:
        STUDY["nodes_per_stitch"] = args.resolutions
    if args.dt_factors:
        STUDY["dt_safety"] = args.dt_factors
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv = out / "convergence.csv"
    rows: list[dict] = []
    if csv.exists():  # resume: keep what an interrupted study finished
        rows = pd.read_csv(csv).to_dict("records")
    done = {(r["part"], r["varied"], r["nodes_per_stitch"], r["overlap_fraction"], r["dt_safety"]) for r in rows}
    for part, study in (("damping", DAMPING), ("counting", COUNTING)):
        if part not in args.parts:
            continue
        df = model_runs(args.size, args.tensions, out / f"{part}.csv", study)
        print(f"\n| {part}: varied | value | f_x target | f_x^ini | v_lad/c_b | change | n_lad/n_y | change | wall [s] |")
        print("|---|---|---|---|---|---|---|---|---|")
        for _, r in df.sort_values(["fx_target", "varied", "setting_value"]).iterrows():
            print(f"| {r.varied} | {r.setting_value} | {r.fx_target:g} | {r.fx_ini:.2f} | {r.v_lad_over_cb:.3f} | "
                  f"{r.v_lad_over_cb_change:+.1%} | {r.n_lad_over_ny:.3f} | {r.n_lad_over_ny_change:+.1%} | {r.wall_s:.0f} |")
        return
    if "scatter" in args.parts:
        spread = scatter_runs(args.size, args.tensions, args.scatter_dt)
        suffix = "" if args.scatter_dt == DEFAULT["dt_safety"] else f"_dt{args.scatter_dt:g}"
        spread.assign(dt_safety=args.scatter_dt).to_csv(out / f"scatter{suffix}.csv", index=False)
        print(spread.to_string(index=False))
        return
    for part in args.parts:
        for cfg in variations(static=(part == "stitch"), only=args.only):
            key = (part if part != "knit" else f"knit{args.size}", cfg["varied"], cfg["nodes_per_stitch"],
                   cfg["overlap_fraction"], cfg["dt_safety"])
            if key in done:
                continue
            if part == "stitch":
                new = [stitch_run(cfg)]
            elif part == "loop":
                new = [loop_run(cfg)]
            else:
                new = knit_runs(cfg, args.size, args.tensions)
            for r in new:
                r.update(part=key[0], **cfg)
                rows.append(r)
                print(f"{key[0]:8s} {cfg['varied']:17s} n={cfg['nodes_per_stitch']:2d} ov={cfg['overlap_fraction']:.3f} "
                      f"dt={cfg['dt_safety']:.2f}  {r['observable']:34s} {r['value']:.4f}  {r['wall_s']:.1f} s", flush=True)
            with atomic_path(csv) as tmp:
                pd.DataFrame(rows).to_csv(tmp, index=False)
    df = with_errors(pd.DataFrame(rows))
    df.to_csv(out / "errors.csv", index=False)
    pareto_plot(df, out / "pareto.png")
    for obs, sub in df.groupby("observable", sort=False):
        print(f"\n### {obs} (observed order in nodes/stitch {resolution_order(df, obs):.2f})\n")
        print("| varied | nodes/stitch | overlap / d | dt factor | value | error vs finest of its setting | wall [s] |")
        print("|---|---|---|---|---|---|---|")
        for _, r in sub.iterrows():
            print(f"| {r.setting} | {r.nodes_per_stitch} | {r.overlap_fraction:g} | {r.dt_safety:g} | {r.value:.4f} | "
                  f"{r.rel_error:.1%} | {r.wall_s:.1f} |")


if __name__ == "__main__":
    main()
