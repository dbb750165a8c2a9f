"""The authors' engine's drag against the paper's own ceiling and its DER points (preset crassous2023).

    python scripts/paper/authors_drag.py runs/authors_drag16 [runs/authors_drag16_ensemble] [--der runs/authors_der42 ...] [--single-loop OUT.csv]

The ceiling: the paper reports the frictionless ladder's v_lad = beta sqrt(f_x), which a strong drag destroys (a
dragged loop slows, and at the end stays hooked). So the drag its DER points carry is at most the largest that keeps
the frictionless v_lad within CEILING_CHANGE of the undragged one at every tension: read from the sweep's mu = 0
rows, knit by knit against lambda = 0 (one stretched knit per tension, shared by every lambda: a paired change),
with the lambda where the change reaches CEILING_CHANGE interpolated linearly between the two lambdas around it.
``--single-loop``: the same on the single loop (tails, 140 nodes per stitch, mu = 0), run here, written as CSV.
``--der``: the two DER points (mean +- one standard deviation over knits) against the paper's. Prints markdown.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.io.summary import mean_sd

CEILING_CHANGE = 0.10  # the paper's beta sqrt(f) law kept within 10 %
PAPER_DER = {1.58: 0.176, 15.67: 1.05}  # the paper's DER v_lad/c_b, 42 x 42, mu 0.4 (Fig. 3c)


def drag_changes(frame: pd.DataFrame, mu: float = 0.0, column: str = "v_lad_over_cb") -> pd.DataFrame:
    """Per nominal f_x and lambda: ``column`` and its change against lambda = 0 at the same f_x (same knit)."""
    rows = frame[(frame.status == "ok") & (frame.mu == mu)].copy()
    rows["drag_lambda"] = rows.drag_lambda.fillna(0.0)
    # a knit is its target and its seed (a run without one: the knit as stretched)
    rows["knit"] = list(zip(rows.fx, rows.knit_seed.fillna(-1) if "knit_seed" in rows else [-1] * len(rows)))
    base = rows[rows.drag_lambda == 0.0].set_index("knit")[column]
    rows["change"] = rows[column] / rows.knit.map(base) - 1.0
    # an ensemble's members (their own knit, the target 0.5 % apart) are one point: their nominal target
    rows["point"] = rows.fx_nominal.fillna(rows.fx) if "fx_nominal" in rows else rows.fx
    keep = ["point", "fx", "drag_lambda", column, "change"]
    return rows[keep].sort_values(["point", "drag_lambda", "fx"]).reset_index(drop=True)


def ceiling(changes: pd.DataFrame, limit: float = CEILING_CHANGE) -> tuple[float, float]:
    """(largest lambda tried whose mean change over knits stays within ``limit`` at every point, the lambda where
    the worst point's reaches ``limit``, linear between the lambdas tried; inf if none does)."""
    mean = changes.groupby(["point", "drag_lambda"]).change.mean().abs()
    worst = mean.groupby("drag_lambda").max().sort_index()
    within = worst.index[(worst <= limit).to_numpy() & (worst.cummax() <= limit).to_numpy()]
    largest = float(within.max())
    above = worst[worst.index > largest]
    if above.empty:
        return largest, np.inf
    l1, c1, l2, c2 = largest, float(worst[largest]), float(above.index[0]), float(above.iloc[0])
    return largest, l1 + (limit - c1) * (l2 - l1) / (c2 - c1)


def der_points(frame: pd.DataFrame) -> pd.DataFrame:
    """Per DER point: knits, v_lad/c_b mean and standard deviation, the paper's value and the ratio."""
    ok = frame[frame.status == "ok"].copy()
    nominal = ok.fx_nominal if "fx_nominal" in ok else ok.fx
    ok["point"] = [min(PAPER_DER, key=lambda p: abs(p - f)) for f in nominal.fillna(ok.fx)]
    out = ok.groupby(["drag_lambda", "point"]).v_lad_over_cb.agg(["count", "mean", "std"]).reset_index()
    out["paper"] = out.point.map(PAPER_DER)
    out["ratio"] = out["mean"] / out.paper
    return out


def single_loop(path: str) -> pd.DataFrame:
    """The single loop (tails, the preset's 140 nodes per stitch, mu = 0) at f_x 4 and 13.6 against lambda."""
    from knitlad.engine.dissipation import authors_drag_per_s
    from knitlad.engine.units import NYLON
    from knitlad.experiments.config import LoopConfig
    from knitlad.experiments.periodic_loop import run_single_loop

    rows = []
    for fx in (4.0, 13.6):
        for lam in (0.0, 1e-4, 3e-4, 1e-3):
            cfg = LoopConfig(fx=fx, mu=0.0, geometry="tails", preset="crassous2023")
            r = run_single_loop(cfg.settings(drag_per_s=authors_drag_per_s(lam, NYLON)))
            rows.append(dict(fx=fx, mu=0.0, drag_lambda=lam, drag_per_s=authors_drag_per_s(lam, NYLON),
                             resolution=cfg.resolution, v_lad_over_cb=r.v_lad_over_cb, tau_us=r.tau_s * 1e6,
                             released=r.released, status="ok"))
    table = pd.DataFrame(rows)
    table.to_csv(path, index=False)
    return table


def markdown(changes: pd.DataFrame, title: str) -> str:
    """One row per point and lambda, over its knits."""
    from knitlad.engine.dissipation import authors_drag_per_s
    from knitlad.engine.units import NYLON

    lines = [f"| {title}: f_x | lambda | gamma [1/s] | knits | v_lad/c_b | change [%] |", "|---|---|---|---|---|---|"]
    for (point, lam), g in changes.groupby(["point", "drag_lambda"]):
        lines.append(f"| {point:g} | {lam:g} | {authors_drag_per_s(lam, NYLON):.3g} | {len(g)} | "
                     f"{mean_sd(g.v_lad_over_cb, '.3f', '.3f')} | {mean_sd(g.change, '+.1f', '.1f', 100)} |")
    return "\n".join(lines)


def read(run: str) -> pd.DataFrame:
    path = Path(run)
    return pd.read_csv(path / "summary.csv" if path.is_dir() else path)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("sweep", nargs="+", help="the 16 x 16 lambda sweeps (their folders or summary CSVs)")
    p.add_argument("--der", nargs="*", default=[], help="42 x 42 DER sweeps (folders or summary CSVs)")
    p.add_argument("--single-loop", help="run the single loop and write its table here")
    args = p.parse_args()
    sweeps = pd.concat([read(r) for r in args.sweep], ignore_index=True)
    fabric = drag_changes(sweeps)
    print(markdown(fabric, "fabric 16 x 16, mu 0"))
    largest, reached = ceiling(fabric)
    print(f"\nfabric: within {CEILING_CHANGE:.0%} up to lambda {largest:g}; the change reaches it at {reached:.3g}")
    with_friction = drag_changes(sweeps, mu=0.4)
    print("\n" + markdown(with_friction, "fabric 16 x 16, mu 0.4"))
    if args.single_loop:
        loop = drag_changes(single_loop(args.single_loop))
        print("\n" + markdown(loop, "single loop, mu 0"))
        largest, reached = ceiling(loop)
        print(f"\nsingle loop: within {CEILING_CHANGE:.0%} up to lambda {largest:g}; reaches it at {reached:.3g}")
    if args.der:
        points = der_points(pd.concat([read(r) for r in args.der], ignore_index=True))
        print("\n| lambda | f_x^ini | knits | v_lad/c_b | paper's DER | ratio |\n|---|---|---|---|---|---|")
        for _, r in points.iterrows():
            sd = f" +- {r['std']:.3f}" if r["count"] > 1 else " (1 run)"
            print(f"| {r.drag_lambda:g} | {r.point:g} | {r['count']} | {r['mean']:.3f}{sd} | {r.paper} | {r.ratio:.2f} |")


if __name__ == "__main__":
    main()
