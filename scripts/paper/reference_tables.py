"""The tables of docs/accuracy.md from the reference runs: converged values, orders, and each preset's error.

Reads ``<ref>/stitch.csv`` (scripts/paper/reference_stitch.py, the model without the sagitta
correction at 24 to 280 nodes per stitch), ``<ref>/stitch_sagitta.csv`` (the same with it)
and ``<ref>/ladder16.csv`` (scripts/paper/reference_ladder.py), and prints markdown:

* the periodised stitch's f_x at fixed (l_x, l_y) against the resolution, the reference
  (the finest resolution; its uncertainty the last increment), the observed order p of the
  last three increments (f(n) = f_inf + C n^-p), and each preset's error;
* l_x/l0 at fixed f_x (each resolution's f_x(l_x) interpolated) and the f_x = 0 curve;
* the laddering knit (16 x 16): ensemble means with their standard errors, per resolution
  and variant, and each preset's difference from the finest plain resolution.

    python scripts/paper/reference_tables.py [--ref docs/reference]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

PRESETS = {"fast": (24, "plain"), "default": (48, "sagitta 11 implicit"), "accurate": (96, "sagitta 11 implicit")}
STITCH_PRESETS = {"fast": (24, 0.0), "default": (48, 11.0), "accurate": (96, 11.0)}


def doubling_order(f24: float, f48: float, f96: float) -> tuple[float, float]:
    """(p, the Richardson limit) of f(n) = f_inf + C n^-p through 24, 48 and 96 nodes per stitch; NaN where
    the increments do not shrink with one sign."""
    d1, d2 = f48 - f24, f96 - f48
    if d1 == 0 or d2 == 0 or np.sign(d1) != np.sign(d2) or abs(d2) >= abs(d1):
        return math.nan, math.nan
    p = math.log2(d1 / d2)
    return p, f96 + d2 / (2**p - 1)


def stitch_table(df: pd.DataFrame, sag: pd.DataFrame | None) -> None:
    res = sorted(df.resolution.unique())
    finest = res[-1]
    print(f"\n### Periodised stitch: f_x at fixed (l_x, l_y), nodes per stitch {', '.join(map(str, res))}\n")
    head = " | ".join(str(r) for r in res)
    print(f"| l_y/l0 | l_x/l0 | {head} | reference | p (24-48-96) | limit of 24-48-96 | fast | default | accurate |")
    print("|---|---|" + "---|" * len(res) + "---|---|---|---|---|---|")
    for (ly, lx), g in df.groupby(["ly_over_l0", "lx_over_l0"]):
        g = g.set_index("resolution")
        f = [g.fx.get(r, math.nan) for r in res]
        ref, unc = reference_of(g, res)
        p, limit = doubling_order(*(g.fx.get(r, math.nan) for r in (24, 48, 96)))
        flags = ""
        cells = []
        for name, (r, s) in STITCH_PRESETS.items():
            src = df if s == 0 else sag
            value = math.nan
            if src is not None:
                hit = src[(src.resolution == r) & np.isclose(src.ly_over_l0, ly) & np.isclose(src.lx_over_l0, lx)]
                if len(hit):
                    value = float(hit.fx.iloc[0])
            cells.append(_error_cell(value, ref))
        print(f"| {ly:.2f} | {lx:.3f} | " + " | ".join(f"{v:.3f}" for v in f)
              + f" | {ref:.3f}{flags} +- {unc:.3f} | {p:.1f} | {limit:.3f} | " + " | ".join(cells) + " |")
    print(f"\n(reference: the finest resolution whose relaxation converged to 1e-4 f0 (up to {finest} nodes per "
          "stitch), +- its largest difference from the two next finest converged ones; p: observed order of the "
          "increments from 24 to 48 to 96 nodes per stitch, and the limit a power law in n through them gives, "
          "to be checked against the reference; nan where the increments do not shrink with one sign; preset "
          "errors relative where |f_x| > 1, else in f0)")


def reference_of(g: pd.DataFrame, res: list[int]) -> tuple[float, float]:
    """(the finest converged f_x, its largest difference from the two next finest converged ones)."""
    good = [r for r in res if r in g.index and bool(g.converged.get(r)) and math.isfinite(g.fx.get(r))]
    if len(good) < 2:
        return math.nan, math.nan
    ref = float(g.fx[good[-1]])
    return ref, max(abs(float(g.fx[r]) - ref) for r in good[-3:-1])


def _error_cell(value: float, ref: float) -> str:
    if math.isnan(value):
        return ""
    if abs(ref) > 1.0:
        return f"{(value - ref) / ref:+.1%}"
    return f"{value - ref:+.3f} f0"


def width_at(g: pd.DataFrame, fx: float) -> float:
    """l_x/l0 where the resolution's f_x(l_x) crosses ``fx`` (linear between the bracketing points); NaN if
    either of them did not relax to its tolerance."""
    g = g.sort_values("lx_over_l0")
    lx, f, ok = g.lx_over_l0.to_numpy(), g.fx.to_numpy(), g.converged.to_numpy()
    for k in range(len(lx) - 1):
        if (f[k] - fx) * (f[k + 1] - fx) <= 0 and f[k] != f[k + 1]:
            if not (ok[k] and ok[k + 1]):
                return math.nan
            return float(lx[k] + (fx - f[k]) * (lx[k + 1] - lx[k]) / (f[k + 1] - f[k]))
    return math.nan


def width_table(df: pd.DataFrame, sag: pd.DataFrame | None) -> None:
    res = sorted(df.resolution.unique())
    print("\n### Periodised stitch: l_x/l0 at fixed f_x (f_x = 0: the configuration diagram's curve)\n")
    print(f"| l_y/l0 | f_x | {' | '.join(str(r) for r in res)} | reference | p (24-48-96) | limit of 24-48-96 "
          "| fast | default | accurate |")
    print("|---|---|" + "---|" * len(res) + "---|---|---|---|---|---|")
    for ly in sorted(df.ly_over_l0.unique()):
        for fx in (0.0, 1.58, 4.0, 13.6):
            w = [width_at(df[np.isclose(df.ly_over_l0, ly) & (df.resolution == r)], fx) for r in res]
            if sum(math.isfinite(v) for v in w[-3:]) < 2 or sum(math.isfinite(v) for v in w) < len(w) - 2:
                continue  # the grid of this l_y does not bracket this tension
            good = [v for v in w if math.isfinite(v)]
            ref, unc = good[-1], max(abs(good[-1] - good[-2]), abs(good[-1] - good[-3]))
            p, limit = doubling_order(*(w[res.index(r)] if r in res else math.nan for r in (24, 48, 96)))
            cells = []
            for name, (r, s) in STITCH_PRESETS.items():
                src = df if s == 0 else sag
                value = math.nan
                if src is not None:
                    value = width_at(src[np.isclose(src.ly_over_l0, ly) & (src.resolution == r)], fx)
                cells.append("" if math.isnan(value) else f"{value - ref:+.4f}")
            print(f"| {ly:.2f} | {fx:g} | " + " | ".join(f"{v:.4f}" for v in w) + f" | {ref:.4f} +- {unc:.4f} | "
                  f"{p:.1f} | {limit:.4f} | " + " | ".join(cells) + " |")
    print("\n(preset columns: l_x/l0 of the preset minus the reference, in l0)")


OBSERVABLES = [("fx_ini", "f_x^ini"), ("lx_over_l0", "l_x/l0"), ("v_lad_over_cb", "v_lad/c_b"),
               ("n_lad_over_ny", "n_lad/n_y"), ("fx_fin", "f_x^fin")]


def ladder_table(df: pd.DataFrame) -> None:
    if "variant" not in df:
        df["variant"] = "plain"
    df["variant"] = df["variant"].fillna("plain")
    ok = df[df.get("error", pd.Series(index=df.index, dtype=object)).isna()] if "error" in df else df
    failed = len(df) - len(ok)
    print("\n### Laddering knit, 16 x 16: ensemble means +- standard error\n")
    print("| f_x (target) | variant | nodes | runs | " + " | ".join(label for _, label in OBSERVABLES)
          + " | wall [s] |")
    print("|---|---|---|---|" + "---|" * len(OBSERVABLES) + "---|")
    for (fx, variant, res), g in ok.groupby(["fx_nominal", "variant", "resolution"]):
        cells = [f"{g[c].mean():.4g} +- {g[c].std(ddof=1) / math.sqrt(len(g)):.2g}" if len(g) > 1
                 else f"{g[c].mean():.4g}" for c, _ in OBSERVABLES]
        wall = (g.stretch_s + g.ladder_s).mean()
        print(f"| {fx:g} | {variant} | {res} | {len(g)} | " + " | ".join(cells) + f" | {wall:.0f} |")
    if failed:
        print(f"\n{failed} run(s) failed (their rows hold the error).")
    plain = ok[ok.variant == "plain"]
    if plain.empty:
        return
    print("\n### Each preset against the finest plain resolution of its tension, 16 x 16\n")
    print("| f_x | reference | preset | " + " | ".join(label for _, label in OBSERVABLES[1:]) + " |")
    print("|---|---|---|" + "---|" * (len(OBSERVABLES) - 1))
    for fx, g in ok.groupby("fx_nominal"):
        finest = int(g[g.variant == "plain"].resolution.max())
        ref = g[(g.variant == "plain") & (g.resolution == finest)]
        if ref.empty:
            continue
        for name, (res, variant) in PRESETS.items():
            run = g[(g.variant == variant) & (g.resolution == res)]
            if run.empty or (res, variant) == (finest, "plain"):
                continue
            cells = []
            for c, _ in OBSERVABLES[1:]:
                diff = run[c].mean() - ref[c].mean()
                se = math.sqrt(_var_of_mean(run[c]) + _var_of_mean(ref[c]))
                if c == "lx_over_l0":
                    cells.append(f"{diff:+.4f} +- {se:.4f}")
                else:
                    cells.append(f"{diff / ref[c].mean():+.1%} +- {se / abs(ref[c].mean()):.1%}")
            print(f"| {fx:g} | {finest} x {len(ref)} | {name} ({res}) | " + " | ".join(cells) + " |")
    print("\n(l_x/l0 as a difference in l0, the others relative; +- the standard error of the difference of means)")


def _var_of_mean(x: pd.Series) -> float:
    return float(x.var(ddof=1) / len(x)) if len(x) > 1 else 0.0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ref", default="docs/reference")
    args = p.parse_args()
    ref = Path(args.ref)
    stitch = pd.read_csv(ref / "stitch.csv") if (ref / "stitch.csv").exists() else None
    sag = pd.read_csv(ref / "stitch_sagitta.csv") if (ref / "stitch_sagitta.csv").exists() else None
    if stitch is not None:
        stitch_table(stitch, sag)
        width_table(stitch, sag)
    if (ref / "ladder16.csv").exists():
        extra = [pd.read_csv(p) for p in sorted(ref.glob("ladder16_*.csv")) if "cut_overlap" not in p.name]
        ladder_table(pd.concat([pd.read_csv(ref / "ladder16.csv"), *extra], ignore_index=True))


if __name__ == "__main__":
    main()
