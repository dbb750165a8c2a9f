"""The laddering threshold f_x^thr(K) from sweeps over natural curvature K and f_x^ini.

    python scripts/paper/threshold.py runs/threshold16 [runs/threshold16_mu0 ...] [--png docs/threshold16.png]

Reads each sweep's summary (``knitlad sweep configs/threshold16.yaml``). A run "does not
ladder" when its damage is below 0.1 n_y on the paper's 42 x 42 knit, 4.2 cells: counted in
cells, so that the criterion carries over to a smaller knit, where the cut alone undoes 1 to 2
cells (0.06 to 0.12 n_y on 16 x 16). For each (K, mu): f_x^thr is bracketed between the
highest f_x^ini that does not ladder and the lowest at or above which every run ladders; it is quoted as the middle of the
bracket, +- half its width. Beside it: the paper's hypothesis f_x^thr = K, and for the
ladders that stopped inside the fabric (not at an edge course) f_x^fin, which the
experiments find equal to f_x^thr (Fig. 3f). Prints markdown tables; draws n_lad/n_y and
f_x^fin against f_x^ini per K.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

NO_LADDER_CELLS = 0.1 * 42  # fewer undone cells: the knit did not ladder (n_lad/n_y < 0.1 on 42 x 42)


def threshold(g: pd.DataFrame) -> tuple[float, float, float]:
    """(lower, upper, middle) of the bracket of f_x^thr in one (K, mu) series."""
    g = g.sort_values("fx_ini")
    held = g[g.n_lad < NO_LADDER_CELLS].fx_ini
    laddered = g[g.n_lad >= NO_LADDER_CELLS].fx_ini
    lower = held.max() if len(held) else 0.0
    above = laddered[laddered > lower]
    upper = above.min() if len(above) else math.inf
    return lower, upper, 0.5 * (lower + upper) if math.isfinite(upper) else math.nan


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("sweeps", nargs="+", help="sweep output folders (with summary.csv)")
    p.add_argument("--png", default=None, help="figure to write")
    p.add_argument("--friction-png", default=None, help="f_x^thr against mu per K, with the fits, to write here")
    args = p.parse_args()
    df = pd.concat([pd.read_csv(Path(s) / "summary.csv") for s in args.sweeps], ignore_index=True)
    df = df[df.status == "ok"].copy()
    df["natural_curvature"] = df["natural_curvature"].fillna(0.0)
    print("| K | mu | runs | f_x^thr bracket | f_x^thr | hypothesis f_x^thr = K | f_x^fin of ladders arrested inside (f_x^ini) |")
    print("|---|---|---|---|---|---|---|")
    for (K, mu), g in df.groupby(["natural_curvature", "mu"]):
        lower, upper, mid = threshold(g)
        if not math.isfinite(upper):
            mid = math.nan  # no run laddered: the threshold lies above the scan
        inside = g[(g.n_lad >= NO_LADDER_CELLS) & (~g.reached_edge.astype(bool))]
        fin = ", ".join(f"{r.fx_fin:.2f} ({r.fx_ini:.2f})" for r in inside.sort_values("fx_ini").itertuples()) or "none"
        width = f"+- {0.5 * (upper - lower):.2f}" if math.isfinite(upper) else ""
        print(f"| {K:g} | {mu:g} | {len(g)} | {lower:.2f} to {upper:.2f} | {mid:.2f} {width} | {K:g} | {fin} |")
    print("\n| K | mu | f_x^ini | n_lad (cells) | n_lad/n_y | v_lad/c_b | f_x^fin | reached edge | stop |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in df.sort_values(["natural_curvature", "mu", "fx_ini"]).itertuples():
        print(f"| {r.natural_curvature:g} | {r.mu:g} | {r.fx_ini:.2f} | {r.n_lad:.0f} | {r.n_lad_over_ny:.2f} | {r.v_lad_over_cb:.3f} | "
              f"{r.fx_fin:.2f} | {bool(r.reached_edge)} | {r.stop_reason} |")
    if df.mu.nunique() > 2:
        friction_table(df, args.friction_png)
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
        for (K, mu), g in df.groupby(["natural_curvature", "mu"]):
            g = g.sort_values("fx_ini")
            label = f"K = {K:g}" + (f", mu = {mu:g}" if mu != 0.4 else "")
            a.plot(g.fx_ini, g.n_lad_over_ny, "o-" if mu != 0 else "s--", label=label)
            b.plot(g.fx_ini, g.fx_fin, "o-" if mu != 0 else "s--", label=label)
        lim = max(df.fx_ini.max(), 1.0)
        b.plot([0, lim], [0, lim], "k:", lw=0.8, label="f_x^fin = f_x^ini")
        a.axhline(NO_LADDER_CELLS / df.n_y.max(), color="k", lw=0.8, ls=":")
        a.set(xlabel="f_x^ini", ylabel="n_lad / n_y", title="damage (Fig. 3e)")
        b.set(xlabel="f_x^ini", ylabel="f_x^fin", title="tension after the ladder (Fig. 3f)")
        a.legend(fontsize=8)
        b.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)
        print(f"\nwrote {args.png}")


def brackets(df: pd.DataFrame) -> pd.DataFrame:
    """One row per (K, mu) with a finite bracket: K, mu, lower, upper, middle, half width."""
    rows = []
    for (K, mu), g in df.groupby(["natural_curvature", "mu"]):
        lower, upper, mid = threshold(g)
        if math.isfinite(upper):
            rows.append({"K": K, "mu": mu, "lower": lower, "upper": upper, "mid": mid, "half": 0.5 * (upper - lower)})
    return pd.DataFrame(rows)


def weighted_line(x: np.ndarray, y: np.ndarray, sigma: np.ndarray) -> tuple[float, float, float]:
    """(intercept, slope, chi^2 per degree of freedom) of y = a + b x, weights 1/sigma^2."""
    w = 1.0 / sigma**2
    A = np.column_stack([np.ones_like(x), x]) * np.sqrt(w)[:, None]
    coef = np.linalg.lstsq(A, y * np.sqrt(w), rcond=None)[0]
    chi2 = float(np.sum(w * (y - coef[0] - coef[1] * x) ** 2))
    return float(coef[0]), float(coef[1]), chi2 / max(len(x) - 2, 1)


def friction_table(df: pd.DataFrame, png: str | None) -> None:
    """f_x^thr against mu per K: a straight line f0 + b mu and a capstan f0 e^(theta mu) (a line in
    log f), each fitted to the brackets' middles weighted by their half widths; and each fit's
    prediction beside each bracket (a bracket the fit misses is said)."""
    b = brackets(df)
    print("\n| K | fit | f_x^thr at mu = 0 | slope (b, or theta) | chi^2/dof | brackets missed |")
    print("|---|---|---|---|---|---|")
    fits = {}
    for K, g in b.groupby("K"):
        if len(g) < 3:
            continue
        x, y, sig = g.mu.to_numpy(), g.mid.to_numpy(), np.maximum(g.half.to_numpy(), 1e-3)
        a0, b0, c0 = weighted_line(x, y, sig)
        la, lb, lc = weighted_line(x, np.log(np.maximum(y, 1e-3)), sig / np.maximum(y, 1e-3))
        for name, f in (("line f0 + b mu", lambda m: a0 + b0 * m), ("capstan f0 e^(theta mu)", lambda m: np.exp(la + lb * m))):
            pred = f(x)
            missed = [f"mu {m:g}: {p:.2f} vs {lo:.2f}-{hi:.2f}" for m, p, lo, hi in zip(x, pred, g.lower, g.upper)
                      if not lo <= p <= hi]
            at0, slope, chi = (a0, b0, c0) if name.startswith("line") else (math.exp(la), lb, lc)
            print(f"| {K:g} | {name} | {at0:.2f} | {slope:.2f} | {chi:.2f} | {'; '.join(missed) or 'none'} |")
        fits[K] = ((a0, b0), (la, lb))
    if png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(4.8, 3.6))
        for K, g in b.groupby("K"):
            line = ax.errorbar(g.mu, g.mid, yerr=g.half, fmt="o", capsize=3, label=f"$K$ = {K:g}")
            if K in fits:
                m = np.linspace(0, g.mu.max(), 50)
                (a0, b0), (la, lb) = fits[K]
                ax.plot(m, a0 + b0 * m, "-", color=line[0].get_color(), lw=0.8)
                ax.plot(m, np.exp(la + lb * m), ":", color=line[0].get_color(), lw=0.8)
            ax.axhline(K, color=line[0].get_color(), ls="--", lw=0.6)
        ax.set_xlabel(r"$\mu$")
        ax.set_ylabel(r"$f_x^{\mathrm{thr}}$")
        ax.set_title("threshold against friction (16 x 16, default preset)\n"
                     "— line, ··· capstan, -- hypothesis $f_x^{thr} = K$", fontsize=8)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(png, dpi=200)
        print(f"\nwrote {png}")


if __name__ == "__main__":
    main()
