"""Paper Fig. 4 by protocol B: the force-displacement curve (4a) and the damage against Eq. 1 (4c).

    python scripts/paper/damage_prediction.py runs/fig4c [--csv docs/reference/fig4c_summary.csv]
                                             [--png docs/fig4c.png] [--curve docs/fig4a.png [--curve-at 0.25 0.38]]
    python scripts/paper/damage_prediction.py runs/fig4c:"fast, 16 wide" runs/fig4c_default:"default, 16 wide" \
                                             --png docs/fig4c_compared.png      # sweeps compared, one series each
    python scripts/paper/damage_prediction.py runs/eq1_ensemble16 --ensemble   # knits of one protocol together

Reads every finished job of a ``cycle`` sweep (``knitlad sweep configs/fig4c.yaml``): its readings
(``cycle/readings``) and summary. delta l is read on the uncut twin's last unloading twice: at the
sweep's f_x^thr, and at the run's own arrest tension, f_x^fin of the courses the ladder crossed (the
threshold of the model as it ran; the paper's f_x^fin = f_x^thr, Fig. 3f). The damage is given whole and as
Eq. 1 counts it: the cells released into loaded courses, and of those the cells whose bar is taut (runs of
knitlad 0.8 on). Prints a markdown table.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import h5py
import numpy as np
import pandas as pd

import knitlad as kl
from knitlad.experiments.cycling import HOLD, UNLOADING, shortening_to
from knitlad.io.hdf5 import read_attrs
from knitlad.viz.plots import cycle_curve_plot, damage_prediction_plot


def job_rows(folder: Path) -> list[dict]:
    rows = []
    for path in sorted((folder / "jobs").glob("*.h5")):
        attrs = read_attrs(path)
        if attrs.get("status") != "ok":
            continue
        config = attrs["cycle_config_json"]  # read_attrs decodes JSON attributes
        with h5py.File(path) as f:
            readings = f["cycle/readings"][()]
        last = int(readings[:, 0].max())
        start = np.flatnonzero((readings[:, 0] == last) & (readings[:, 1] == HOLD))[0]
        unloading = np.vstack([readings[start, 3:5], readings[(readings[:, 0] == last) & (readings[:, 1] == UNLOADING)][:, 3:5]])
        lx = attrs["cycle_lx_over_l0"]
        own = attrs["fx_fin_crossed"]
        dl_own = shortening_to(unloading, own, config["n_x"]) if np.isfinite(own) else np.nan
        rows.append({
            "job": path.stem, "ly": config["ly"], "lx_max": config["lx_max"], "bar_speed": config["bar_speed"],
            "fx_ini": attrs["cycle_fx_ini"], "lx_over_l0": lx, "fx_thr": config["fx_thr"],
            "delta_l_over_l0": attrs["cycle_delta_l_over_l0"], "predicted": attrs["cycle_predicted_damage"],
            "fx_fin_crossed": own, "predicted_own": dl_own / (1 - lx),
            "n_lad_over_ny": attrs["n_lad_over_ny"],
            # the damage as Eq. 1 counts it (runs of knitlad 0.8 on): released into loaded courses, and taut
            "released_over_ny": attrs.get("n_lad_released_over_ny", np.nan),
            "released_taut_over_ny": attrs.get("n_lad_released_taut_over_ny", np.nan),
            "ladders_up": attrs["ladders_up"],
            "ladders_down": attrs["ladders_down"], "reached_edge": bool(attrs["reached_edge"]),
            "stop_reason": attrs["stop_reason"], "hold_converged": bool(attrs["cycle_hold_converged"]),
            "wall_min": attrs.get("job_wall_s", np.nan) / 60, "readings": readings, "n_x": config["n_x"],
            "n_y": config["n_y"],
        })
    return rows


# the damage counted three ways, each over Eq. 1 at the run's own arrest tension
RATIOS = {"every": "n_lad_over_ny", "released": "released_over_ny", "taut": "released_taut_over_ny"}


def ensemble_table(table: pd.DataFrame) -> pd.DataFrame:
    """Knits of one protocol (the same n_y, l_y, Delta x_max, bars' speed; f_x targets a fraction of a percent
    apart) taken together: per group, the number of knits, and the mean and standard error over them of f_x^fin
    and of each count of the damage over Eq. 1 at the run's own f_x^fin (:data:`RATIOS`)."""
    keys = [k for k in ("series", "n_y", "ly", "lx_max", "bar_speed") if k in table]
    rows = []
    for group, at in table.groupby(keys):
        row = dict(zip(keys, group if isinstance(group, tuple) else (group,)), knits=len(at))
        columns = {"fx_fin_crossed": at["fx_fin_crossed"]}
        columns |= {f"{name}_over_eq1": at[col] / at["predicted_own"] for name, col in RATIOS.items()}
        for name, values in columns.items():
            row[name] = values.mean()
            row[f"{name}_se"] = values.std(ddof=1) / np.sqrt(len(values)) if len(values) > 1 else np.nan
        rows.append(row)
    return pd.DataFrame(rows)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", help="a cycle sweep's output folder, or FOLDER:LABEL for sweeps compared")
    p.add_argument("--csv", type=Path)
    p.add_argument("--png", type=Path)
    p.add_argument("--ensemble", action="store_true", help="also the knits of one protocol taken together: "
                   "mean +- standard error of f_x^fin and of the damage over Eq. 1 at it")
    p.add_argument("--curve", type=Path, help="Fig. 4a of one job (--curve-at)")
    p.add_argument("--curve-at", type=float, nargs=2, default=(0.25, 0.38), metavar=("LY", "LX_MAX"),
                   help="the job of Fig. 4a: its l_y/l0 and Delta x_max (box l_x/l0), at the fastest bars")
    args = p.parse_args()
    rows = []
    for spec in args.folders:
        folder, _, label = spec.partition(":")
        found = job_rows(Path(folder))
        if not found:
            raise SystemExit(f"{folder}: no finished cycle job")
        rows += [{**r, "series": label or Path(folder).name} for r in found]
    table = pd.DataFrame([{k: v for k, v in r.items() if k != "readings"} for r in rows])
    table = table.sort_values(["series", "ly", "lx_max", "n_y", "bar_speed"], kind="stable")
    if len(args.folders) == 1:
        table = table.drop(columns=["series"])
    shown = (["series"] if "series" in table else []) + [
        "n_y", "ly", "lx_max", "bar_speed", "fx_ini", "lx_over_l0", "delta_l_over_l0", "predicted", "fx_fin_crossed",
        "predicted_own", "n_lad_over_ny", "released_over_ny", "released_taut_over_ny", "ladders_up", "ladders_down",
        "reached_edge", "wall_min"]
    print("| " + " | ".join(shown) + " |\n|" + "---|" * len(shown))
    for _, row in table[shown].iterrows():
        print("| " + " | ".join(f"{v:.3f}" if isinstance(v, float) else str(v) for v in row) + " |")
    if args.ensemble:
        ensemble = ensemble_table(table)
        print("\n| knits | n_y | Delta x_max | f_x^fin crossed | every cell / Eq. 1 | released / Eq. 1 | taut / Eq. 1 |"
              "\n|---|---|---|---|---|---|---|")
        for _, r in ensemble.iterrows():
            cells = [f"{r[k]:.2f} +- {r[k + '_se']:.2f}" for k in ("fx_fin_crossed", "every_over_eq1",
                                                                  "released_over_eq1", "taut_over_eq1")]
            print(f"| {int(r.knits)} | {int(r.n_y)} | {r.lx_max:g} | " + " | ".join(cells) + " |")
    if args.csv:
        table.drop(columns=["job"]).to_csv(args.csv, index=False, float_format="%.5g")
    if args.png:
        plot = table.rename(columns={"predicted": "predicted_damage", "n_lad_over_ny": "cut_n_lad_over_ny",
                                     "reached_edge": "cut_reached_edge"})
        fastest = plot.groupby("series" if "series" in plot else "ly")["bar_speed"].transform("max")
        damage_prediction_plot(plot[plot["bar_speed"] == fastest], args.png)
    if args.curve:
        ly, lx_max = args.curve_at
        top = max((r for r in rows if r["ly"] == ly and r["lx_max"] == lx_max), key=lambda r: r["bar_speed"])
        cycle_curve_plot(top["readings"], top["n_x"], kl.NYLON.stitch_length, top["fx_thr"], top["delta_l_over_l0"], args.curve)


if __name__ == "__main__":
    main()
