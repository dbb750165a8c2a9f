"""Laddering velocity against friction on the fabric: the paper's Eq. 2 and Fig. 5c, from knits instead of a loop.

    python scripts/paper/velocity_friction.py runs/velocity24_mu [--png docs/velocity_friction.png] [--csv FILE]

Reads a sweep over (mu, f_x^ini) of straight-yarn knits (``docs/reference/velocity24_mu.yaml``). Per mu:
* the front's velocity v_lad/c_b (the summary's fit of the front against time) and, from the laddering
  column's record, tau: the median time between the undoings of successive cells above the cut, with
  l_y/(tau c_b) beside v_lad/c_b (the paper's v = l_y/tau, measured inside the fabric);
* a power law v = a f^b through the points (least squares in logs; b = 1/2 is the inertial law the paper
  gives at mu = 0, v/c_b = 0.34 sqrt(f_x); b = 1 is its frictional law, Eq. 2) with the standard error of b;
* Eq. 2's friction scaling: v(mu = 0.4)/v(mu = 0.8) at each f_x^ini, 2^(1/2) = 1.41 if v ~ mu^(-1/2).
Prints markdown tables; draws v_lad/c_b against f_x^ini per mu with 0.34 sqrt(f_x).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import h5py
import numpy as np
import pandas as pd

PAPER_INERTIAL = 0.34  # v_lad/c_b = 0.34 sqrt(f_x) at mu = 0 (paper, Fig. 5c)


def cell_times(h5: Path) -> tuple[np.ndarray, float, float]:
    """(times [s] at which the cells of the laddering column above the cut were undone, in order up the
    column; l_y [m]; c_b [m/s]) from a job's file."""
    with h5py.File(h5, "r") as f:
        t = f["series/time"][()]
        cells = f["series/laddering_column_cells"][()]  # (n_times, n_y)
        settings = json.loads(f.attrs["settings_json"])
        l_y = float(f.attrs["ly_over_l0"]) * float(f.attrs["scale_l0_m"])
        c_b = float(f.attrs["scale_c_b_m_per_s"])
    cut = settings["stretch"]["n_y"] // 2
    times = []
    for row in range(cut + 1, cells.shape[1]):
        undone = np.nonzero(cells[:, row])[0]
        if not len(undone):
            break  # the front stopped below this row
        times.append(t[undone[0]])
    return np.array(times), l_y, c_b


def tau_s(times: np.ndarray) -> float:
    """Median time between successive undoings (NaN with fewer than three cells)."""
    gaps = np.diff(np.sort(times))
    return float(np.median(gaps)) if len(gaps) >= 2 else math.nan


def power_law(f: np.ndarray, v: np.ndarray) -> tuple[float, float, float]:
    """(a, b, standard error of b) of v = a f^b, least squares in logs."""
    x, y = np.log(f), np.log(v)
    A = np.column_stack([np.ones_like(x), x])
    coef, res, *_ = np.linalg.lstsq(A, y, rcond=None)
    dof = len(x) - 2
    s2 = float(res[0]) / dof if dof > 0 and len(res) else math.nan
    cov = s2 * np.linalg.inv(A.T @ A)
    return math.exp(coef[0]), float(coef[1]), math.sqrt(cov[1, 1]) if np.isfinite(s2) else math.nan


def table(sweep: Path) -> pd.DataFrame:
    df = pd.read_csv(sweep / "summary.csv")
    df = df[df.status == "ok"].copy()
    taus, from_tau = [], []
    for r in df.itertuples():
        times, l_y, c_b = cell_times(sweep / "jobs" / f"{r.job_id}.h5")
        tau = tau_s(times)
        taus.append(tau)
        from_tau.append(l_y / tau / c_b if tau > 0 else math.nan)
    df["tau_ms"] = np.array(taus) * 1e3
    df["ly_over_tau_cb"] = from_tau
    return df.sort_values(["mu", "fx_ini"])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("sweep", help="sweep output folder")
    p.add_argument("--png", default=None)
    p.add_argument("--csv", default=None, help="write the per-run table here")
    args = p.parse_args()
    df = table(Path(args.sweep))
    cols = ["mu", "fx_ini", "n_lad", "reached_edge", "v_lad_over_cb", "v_fit_stitches", "tau_ms", "ly_over_tau_cb",
            "fx_fin"]
    if args.csv:
        df[cols].to_csv(args.csv, index=False, float_format="%.5g")
    print("| mu | f_x^ini | n_lad (cells) | reached edge | v_lad/c_b (front fit) | tau [ms] | l_y/(tau c_b) | f_x^fin |")
    print("|---|---|---|---|---|---|---|---|")
    for r in df.itertuples():
        print(f"| {r.mu:g} | {r.fx_ini:.2f} | {r.n_lad:.0f} | {bool(r.reached_edge)} | {r.v_lad_over_cb:.3f} | "
              f"{r.tau_ms:.3f} | {r.ly_over_tau_cb:.3f} | {r.fx_fin:.2f} |")
    print("\n| mu | v from | fit v = a f^b: a | b +- se | v at f_x = 4 (fit) | 0.34 sqrt(f_x) at 4 |")
    print("|---|---|---|---|---|---|")
    for mu, g in df.groupby("mu"):
        for column, name in (("v_lad_over_cb", "front fit"), ("ly_over_tau_cb", "l_y/tau")):
            h = g[np.isfinite(g[column]) & (g[column] > 0)]
            if len(h) < 3:
                continue
            a, b, se = power_law(h.fx_ini.to_numpy(), h[column].to_numpy())
            print(f"| {mu:g} | {name} | {a:.3f} | {b:.2f} +- {se:.2f} | {a * 4 ** b:.3f} | {PAPER_INERTIAL * 2:.3f} |")
    print("\n| f_x (nominal) | v(mu 0)/v(mu 0.4), front / l_y/tau | v(mu 0.4)/v(mu 0.8), front / l_y/tau | "
          "Eq. 2: v ~ mu^(-1/2): 1.41 |")
    print("|---|---|---|---|")
    for fx, g in df.groupby("fx"):
        v, w = g.set_index("mu").v_lad_over_cb, g.set_index("mu").ly_over_tau_cb

        def ratio(series, a, b):
            return f"{series[a] / series[b]:.2f}" if a in series and b in series else "-"

        print(f"| {fx:g} | {ratio(v, 0.0, 0.4)} / {ratio(w, 0.0, 0.4)} | {ratio(v, 0.4, 0.8)} / {ratio(w, 0.4, 0.8)} | 1.41 |")
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(4.6, 3.5))
        for mu, g in df.groupby("mu"):
            line, = ax.plot(g.fx_ini, g.v_lad_over_cb, "o-", ms=4, label=rf"$\mu$ = {mu:g}")
            ax.plot(g.fx_ini, g.ly_over_tau_cb, "x", color=line.get_color(), ms=5)
        f = np.linspace(0, float(df.fx_ini.max()), 100)
        ax.plot(f, PAPER_INERTIAL * np.sqrt(f), "k--", lw=0.8, label=r"$0.34\sqrt{f_x}$ (paper, $\mu$ = 0)")
        ax.set_xlabel(r"$f_x^{\mathrm{ini}}$")
        ax.set_ylabel(r"$v_{\mathrm{lad}}/c_b$ (o: front fit, x: $l_y/\tau$)")
        ax.set_title("laddering velocity on the fabric (24 x 24, default preset)", fontsize=9)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(args.png, dpi=200)
        print(f"\nwrote {args.png}")


if __name__ == "__main__":
    main()
