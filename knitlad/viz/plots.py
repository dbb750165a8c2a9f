"""Figures: the spatio-temporal diagram of a ladder (paper, Fig. 3b,d and Fig. 7) and a sweep's
summary plots (n_lad/n_y, f_x^fin and v_lad/c_b against f_x^ini: Fig. 3e, 3f, 5a).

Every figure is written atomically (temporary file, then rename).
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.io.atomic import atomic_path


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


FORMATS = ("png", "pdf", "svg")  # what `knitlad plot --format` writes
PNG_DPI = 200

# the paper's symbols, rendered (matplotlib's mathtext), for the columns of a summary table
SYMBOL = {
    "fx": r"$f_x$", "fy": r"$f_y$", "fx_ini": r"$f_x^{\mathrm{ini}}$", "fx_fin": r"$f_x^{\mathrm{fin}}$",
    "n_lad_over_ny": r"$n_{\mathrm{lad}}/n_y$", "v_lad_over_cb": r"$v_{\mathrm{lad}}/c_b$", "mu": r"$\mu$",
    "lx": r"$l_x/l_0$", "ly": r"$l_y/l_0$", "natural_curvature": r"$K$", "resolution": "nodes per stitch",
}


def symbol(column: str) -> str:
    """The rendered symbol of a summary column (the column's name if it has none)."""
    return SYMBOL.get(column, column)


def _save(fig, path: Path) -> Path:
    """Write ``fig`` to ``path`` in the format its suffix names (PNG at PNG_DPI), atomically."""
    with atomic_path(path, suffix=path.suffix) as tmp:
        fig.savefig(tmp, format=path.suffix.lstrip(".") or "png", dpi=PNG_DPI)
    _pyplot().close(fig)
    return path


def draw_spatio_temporal(times_s, front_up, front_down, column_history, cut_row: int, title: str, path,
                         column: int | None = None) -> Path:
    """Laddered cells of the laddering column (grey) against time, with the two fronts."""
    from matplotlib.patches import Patch

    plt = _pyplot()
    path = Path(path)
    t_ms = np.asarray(times_s) * 1e3
    fig, ax = plt.subplots(figsize=(5, 3.5))
    if len(column_history):
        cells = np.asarray(column_history, dtype=float).T
        ax.imshow(cells, origin="lower", aspect="auto", cmap="Greys", vmin=0, vmax=1.5,
                  extent=(t_ms[0], t_ms[-1], -0.5, cells.shape[0] - 0.5) if t_ms.size > 1 else None)
    ax.plot(t_ms, cut_row + np.asarray(front_up), color="tab:red", lw=1.2, label="front (up)")
    ax.plot(t_ms, cut_row - np.asarray(front_down), color="tab:blue", lw=1.2, label="front (down)")
    ax.axhline(cut_row, color="k", lw=0.5, ls=":", label="the cut course")
    where = f"column {column}" if column is not None else "the laddering column"
    handles, labels = ax.get_legend_handles_labels()
    handles.append(Patch(facecolor="0.45", edgecolor="none"))
    labels.append(f"cell undone ({where})")
    ax.set_xlabel("time since the cut [ms]")
    ax.set_ylabel(f"course (stitch) index, {where}")
    ax.set_title(title, fontsize=9)
    ax.legend(handles, labels, fontsize=7, loc="upper left")
    fig.tight_layout()
    return _save(fig, path)


def _title(fx_ini: float, v: float) -> str:
    ini = f"{symbol('fx_ini')} = {fx_ini:.2f}"
    return f"{ini}, {symbol('v_lad_over_cb')} = {v:.3f}" if np.isfinite(v) else ini


def spatio_temporal_diagram(result, path: str | Path) -> Path:
    """The diagram of a :class:`knitlad.experiments.laddering.LadderResult`."""
    return draw_spatio_temporal(result.times_s, result.front_up, result.front_down, result.column_history,
                                result.settings.stretch.n_y // 2, _title(result.fx_ini, result.v_lad_over_cb), path,
                                column=result.laddering_column)


def spatio_temporal_from_file(h5_path: str | Path, path: str | Path) -> Path:
    """The diagram of a run stored by :func:`knitlad.io.hdf5.write_ladder_result`."""
    import h5py

    from knitlad.io.hdf5 import read_attrs, run_settings

    settings = run_settings(read_attrs(h5_path))
    with h5py.File(h5_path, "r") as f:
        s = f["series"]
        hist = s["laddering_column_cells"][()] if "laddering_column_cells" in s else []
        column = int(f.attrs["laddering_column"]) if "laddering_column" in f.attrs else None
        return draw_spatio_temporal(s["time"][()], s["front_up"][()], s["front_down"][()], hist,
                                    settings["n_y"] // 2, _title(float(f.attrs["fx_ini"]), float(f.attrs["v_lad_over_cb"])),
                                    path, column=column)


def column_midline_diagram(h5_path: str | Path, path: str | Path) -> Path:
    """The paper's spatio-temporal diagram (Fig. 3b,d; the appendix's simulation figure): the y of
    the yarn crossing the middle line of the laddering column against time, from the frames."""
    import h5py

    from knitlad.io.hdf5 import read_attrs

    attrs = read_attrs(h5_path)
    with h5py.File(h5_path, "r") as f:
        if "series/midline" in f:  # every observation's mid-line heights, and the front v_lad is fitted to
            return _midline_tracks(attrs, f["series/time"][()], f["series/midline"][()], f["series/front_up"][()],
                                   f["series/front_y"][()], path)
        x = f["frames/positions"][()]
        t_ms = f["frames/time"][()] * 1e3
        centres = f["cells/centres"][()]
    column = int(attrs["laddering_column"])
    x_mid = centres[0, column, 0]
    l_x = float(attrs["box_lx_over_l0"]) * float(attrs["scale_l0_m"])
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for k in range(len(t_ms)):
        near = np.abs(x[k, :, 0] - x_mid) < 0.04 * l_x
        ax.plot(np.full(near.sum(), t_ms[k]), 1e3 * x[k, near, 1], "k.", ms=1.2)
    ax.set_xlabel("time since the cut [ms]")
    ax.set_ylabel("yarn's $y$ on the column's mid-line [mm]")  # short: a longer one was clipped
    ax.set_title(_title(float(attrs["fx_ini"]), float(attrs["v_lad_over_cb"])) + f", column {column}", fontsize=9)
    fig.tight_layout()
    return _save(fig, Path(path))


def _midline_tracks(attrs: dict, t_s, heights, front_up, front_y, path) -> Path:
    """Each course's height on the laddering column's mid-line against time (the paper's spatio-temporal
    diagram), the front (the first course past the ladder's reach) and the line v_lad is its slope of, over the
    fit's stitches."""
    l0_mm = float(attrs["scale_l0_m"]) * 1e3
    t_ms = np.asarray(t_s) * 1e3
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(t_ms, np.asarray(heights) * l0_mm, "k-", lw=0.5)
    ax.plot(t_ms, np.asarray(front_y) * l0_mm, "-", color="tab:blue", lw=1.2, label="front (first course past it)")
    first, last = int(attrs.get("v_fit_first", 2)), int(attrs.get("v_fit_last", 10))
    up = np.asarray(front_up)
    fit = np.zeros(up.shape, dtype=bool)
    if up.size and up.max() >= last:  # from the front's arrival at stitch first to its arrival at last (front_speed)
        fit[int(np.argmax(up >= first)):int(np.argmax(up >= last)) + 1] = True
    fit &= np.isfinite(front_y)
    if fit.sum() >= 2 and np.isfinite(float(attrs["v_lad_over_cb"])):
        slope, intercept = np.polyfit(t_ms[fit], np.asarray(front_y)[fit] * l0_mm, 1)
        ax.plot(t_ms[fit], slope * t_ms[fit] + intercept, "r-", lw=2, alpha=0.7,
                label=f"stitches {first}-{last}: its slope is $v_{{lad}}$")
        ax.legend(fontsize=7, loc="lower right")
    ax.set_xlabel("time since the cut [ms]")
    ax.set_ylabel("yarn's $y$ on the column's mid-line [mm]")
    ax.set_title(_title(float(attrs["fx_ini"]), float(attrs["v_lad_over_cb"]))
                 + f", column {int(attrs['laddering_column'])}", fontsize=9)
    fig.tight_layout()
    return _save(fig, Path(path))


def tension_history_plot(h5_path: str | Path, path: str | Path) -> Path:
    """f_x through the whole run, as the paper's force-time curves (appendix): the stretch at mu = 0
    (its relaxed readings, against FIRE steps), then the laddering after the cut, against time."""
    import h5py

    with h5py.File(h5_path, "r") as f:
        for needed in ("stretch", "series/time", "series/fx"):
            if needed not in f:
                raise KeyError(f"/{needed}")
        steps, box, fx_stretch = (f[f"stretch/{k}"][()] for k in ("relax_steps", "box_lx_over_l0", "fx"))
        t_ms, fx = f["series/time"][()] * 1e3, f["series/fx"][()]
    plt = _pyplot()
    if not (steps.size and steps.max() > steps.min()):  # one periodised stitch, tiled: no history of the knit's
        fig, right = plt.subplots(figsize=(5.5, 3.2))
        right.set_ylabel(symbol("fx"))
        right.text(0.98, 0.96, f"stretched at $\\mu$ = 0 as one periodised stitch, tiled\n(no history of the knit's "
                   f"own), box {symbol('lx')} = {box[-1] if box.size else np.nan:.3f}", transform=right.transAxes,
                   ha="right", va="top", fontsize=7)
        _laddering_tension(right, t_ms, fx, fx_stretch)
        fig.tight_layout()
        return _save(fig, Path(path))
    fig, (left, right) = plt.subplots(1, 2, figsize=(7.5, 3.2), sharey=True,
                                      gridspec_kw={"width_ratios": [1, 1.3]})
    left.set_ylabel(symbol("fx"))
    left.plot(steps / 1e3, fx_stretch, "k.-", ms=2, lw=0.6)  # a stretch of the whole knit: its relaxed readings
    left.set_xlabel(r"stretch at $\mu$ = 0: FIRE steps [$10^3$]")
    if box.max() > box.min():
        twin = left.twiny()
        twin.set_xlim(box.min(), box.max())
        twin.set_xlabel(f"box {symbol('lx')}", fontsize=8)
    _laddering_tension(right, t_ms, fx, fx_stretch)
    fig.tight_layout()
    return _save(fig, Path(path))


def _laddering_tension(ax, t_ms, fx, fx_stretch) -> None:
    ax.plot(t_ms, fx, "tab:red", lw=1.0, label=f"{symbol('fx')} after the cut")
    ax.set_xlabel("time since the cut [ms]")
    ax.axhline(fx_stretch[-1] if fx_stretch.size else np.nan, color="k", ls=":", lw=0.7, label=symbol("fx_ini"))
    ax.legend(fontsize=7, loc="lower left")


# the energy ledger's channels drawn, stacked, and their labels (knitlad.engine.dissipation.EnergyLedger)
LEDGER_STACK = (("friction", "friction"), ("contact_dashpot", "contact dashpots (numerical)"),
                ("axial_dashpot", "axial dashpots (numerical)"), ("material", "the yarn's viscoelasticity"),
                ("air", "air"), ("global_drag", "global drag (the paper's engine)"), ("kinetic", "kinetic, now"))


def energy_ledger_plot(h5_path: str | Path, path: str | Path) -> Path:
    """Where the ladder's energy goes: the elastic energy the cut released (the stored energy at the cut less
    the potential energy now), and stacked beneath it what took it, from the run file's ledger
    (``/ledger``): friction, the dashpots, the material, the air, the drag, and the kinetic energy now. The
    gap between the line and the stack is the ledger's residual, the integrator's error."""
    import h5py

    with h5py.File(h5_path, "r") as f:
        if "ledger" not in f:
            raise KeyError("/ledger (a run file of knitlad before 0.6.0)")
        g = f["ledger"]
        t_ms = f["series/time"][()] * 1e3
        series = {k: g[k][()] * 1e3 for k in g}  # mJ
    released = series["start"] - (series["stored"] - series["kinetic"]) + series["work_in"]
    layers = [(label, series[k]) for k, label in LEDGER_STACK if np.any(series[k])]
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.0, 3.6))
    ax.stackplot(t_ms, *[v for _, v in layers], labels=[label for label, _ in layers], alpha=0.85)
    ax.plot(t_ms, released, "k-", lw=1.2, label="elastic energy released (and work put in)")
    last = series["residual"][-1] / series["turnover"][-1] if series["turnover"][-1] > 0 else 0.0
    ax.set_xlabel("time since the cut [ms]")
    ax.set_ylabel("energy [mJ]")
    ax.set_title(f"where the ladder's energy goes (residual at the stop: {100 * last:.2f} %)", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return _save(fig, Path(path))


PAPER_DER_VELOCITY = ((1.58, 0.176), (15.67, 1.05))  # 42 x 42, mu = 0.4, l_y/l0 = 0.25 (paper, Fig. 7)
EXPERIMENTS_VELOCITY_SLOPE = 0.1  # the experiments' v_lad/c_b ~ 0.1 f_x^ini (paper, Fig. 5a and eq. 1)
DAMAGE_CLASSES = (0.2, 1.0, 2.0)  # the paper's classes of n_lad/n_y (Fig. 3e): < 0.2, 0.2-1, 1-2, >= 2

SUMMARY_PLOTS = {
    # file stem: (y column, paper figure)
    "damage_vs_fx": ("n_lad_over_ny", "Fig. 3e"),
    "fx_fin_vs_fx_ini": ("fx_fin", "Fig. 3f"),
    "velocity_vs_fx": ("v_lad_over_cb", "Fig. 5a"),
}


def loop_velocity_plot(df, path: str | Path) -> Path:
    """Single-loop sweeps (paper Fig. 5c): v_lad/c_b against f_x, one series per mu, and 0.34 sqrt(f_x)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(4.5, 3.4))
    for mu, g in df.groupby("mu", sort=True):
        g = g.sort_values("fx")
        released = g["released"].astype(bool)
        line, = ax.plot(g["fx"][released], g["v_lad_over_cb"][released], "o-", ms=4, label=f"{symbol('mu')} = {mu}")
        if (~released).any():  # still hooked at the end of the run: v_lad = 0, not part of the curve
            ax.plot(g["fx"][~released], 0 * g["fx"][~released], "x", color=line.get_color())
    f = np.linspace(0, float(df["fx"].max()), 100)
    ax.plot(f, 0.34 * np.sqrt(f), "k--", lw=0.8, label=r"$0.34\sqrt{f_x}$ (paper, $\mu$ = 0)")
    return _labelled(fig, ax, symbol("fx"), symbol("v_lad_over_cb"),
                     f"single loop: {symbol('v_lad_over_cb')} against {symbol('fx')} (paper Fig. 5c)", path)


def _labelled(fig, ax, xlabel: str, ylabel: str, title: str, path: str | Path) -> Path:
    """Axis labels, title and legend (if anything is labelled), then save."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    if ax.get_legend_handles_labels()[1]:
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, Path(path))


def zero_tension_curve_plot(df, d_over_l0: float, path: str | Path) -> Path:
    """The f_x = 0 curve of the periodised stitch: l_y/l0 against l_x/l0 (f_x > 0 to its right)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(4.2, 3.6))
    ax.plot(df["lx_over_l0_at_fx0"], df["ly_over_l0"], "k-o", ms=3, label=f"$f_x$ = 0, $d/l_0$ = {d_over_l0:.4g}")
    return _labelled(fig, ax, symbol("lx"), symbol("ly"), "periodised stitch: $f_x$ > 0 right of the curve", path)


def summary_plots(df, out_dir: str | Path, fmt: str = "png") -> list[Path]:
    """One figure per entry of SUMMARY_PLOTS (laddering jobs: one series per value of the swept
    l_y/l0, mu, resolution and K), and the single-loop velocity plot for loop jobs; ``fmt``: one of FORMATS."""
    plt = _pyplot()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ok = df[df["status"] == "ok"]
    paths = []
    if "scene" in ok and (ok["scene"] == "loop").any():
        paths.append(loop_velocity_plot(ok[ok["scene"] == "loop"], out / f"loop_velocity_vs_fx.{fmt}"))
        ok = ok[ok["scene"] != "loop"]
    if "scene" in ok and (ok["scene"] == "cycle").any():
        paths.append(damage_prediction_plot(ok[ok["scene"] == "cycle"], out / f"damage_vs_prediction.{fmt}"))
    if "scene" in ok:
        ok = ok[ok["scene"] == "ladder"]  # stitch sweeps: the table says it all
    if not len(ok):
        return paths
    keys = [k for k in ("ly", "mu", "resolution", "natural_curvature") if k in ok and ok[k].nunique() > 1] or [None]
    groups = ok.groupby(keys if keys != [None] else (lambda _: ""), sort=True)
    x = symbol("fx_ini")
    for stem, (column, figure) in SUMMARY_PLOTS.items():
        ended = run_ends(ok, velocity=column == "v_lad_over_cb")
        fig, ax = plt.subplots(figsize=(4.8, 3.6))
        for key, g in groups:
            g = g.sort_values("fx_ini")
            key = key if isinstance(key, tuple) else (key,)
            legend = ", ".join(f"{symbol(k)} = {v}" for k, v in zip(keys, key) if k is not None) or "knitlad"
            if "fx_nominal" in g and g["fx_nominal"].notna().all():  # an ensemble: each point's mean and its s.e.
                distinct = g[g["same_knit_as"] < 0] if "same_knit_as" in g else g  # a collapsed member counts once
                stats = distinct.groupby("fx_nominal").agg(x=("fx_ini", "mean"), y=(column, "mean"),
                                                           se=(column, "sem"), n=(column, "count"))
                collapsed = len(g) - len(distinct)
                label = f"{legend}: mean of {int(stats['n'].max())} knits +- s.e." + (
                    f" ({collapsed} member{'s' * (collapsed != 1)} the same knit as another)" if collapsed else "")
                line = ax.errorbar(stats["x"], stats["y"], yerr=stats["se"].fillna(0.0), fmt="D-", ms=5, lw=0.8,
                                   capsize=3, label=label)[0]
                ax.plot(g["fx_ini"], g[column], ".", ms=3, color=line.get_color(), alpha=0.5)
                continue
            line, = ax.plot(g["fx_ini"], g[column], "-", lw=0.8, label=legend)
            for how, marker, fill in RUN_END_MARKERS:  # how each run ended, drawn apart
                sub = g[ended.loc[g.index] == how]
                if len(sub):
                    err = None
                    if column == "v_lad_over_cb":
                        preset = sub["preset"] if "preset" in sub else pd.Series("default", index=sub.index)
                        err = sub[column].abs() * preset.map(PRESET_VLAD_ERROR).fillna(0.2)
                    ax.errorbar(sub["fx_ini"], sub[column], yerr=err, fmt=marker, ms=5, color=line.get_color(),
                                mfc=line.get_color() if fill else "none", capsize=2, lw=0.8)
        for how, marker, fill in RUN_END_MARKERS:  # the markers' legend, in black
            if (ended == how).any():
                ax.plot([], [], marker, color="k", mfc="k" if fill else "none", label=RUN_END_LABELS[how])
        if column == "v_lad_over_cb":
            if {"n_x", "n_y"} <= set(ok) and (ok["n_x"] == 42).all() and (ok["n_y"] == 42).all():
                px, py = zip(*PAPER_DER_VELOCITY)  # only beside knits of the same size
                ax.plot(px, py, "k+", ms=8, label=r"paper, DER 42 $\times$ 42")
            f = np.array([0.0, float(np.nanmax(ok["fx_ini"]))])
            ax.plot(f, EXPERIMENTS_VELOCITY_SLOPE * f, "k--", lw=0.8, label=f"experiments, 0.1 {x}")
        if column == "n_lad_over_ny":
            for k, level in enumerate(DAMAGE_CLASSES):  # the paper's damage classes, said in the legend
                ax.axhline(level, color="0.6", ls=":", lw=0.7,
                           label="paper's damage classes (Fig. 3e): 0.2, 1, 2" if k == 0 else None)
        if column == "fx_fin":
            lim = float(np.nanmax(ok["fx_ini"])) if len(ok) else 1.0
            ax.plot([0, lim], [0, lim], "k:", lw=0.8, label=f"{symbol('fx_fin')} = {x}")
        label = symbol(column)
        title = f"{label} against {x} (paper {figure})"
        if column == "fx_fin":  # an arrest tension only where the ladder arrested
            title = f"{symbol('fx')} at the stop (after an arrest: paper {figure})"
        elif column == "v_lad_over_cb":
            title += "\nbars: the preset's stated error (docs/accuracy.md)"
        paths.append(_labelled(fig, ax, x, label, title, out / f"{stem}.{fmt}"))
    return paths


# each preset's largest stated v_lad error against the converged reference (knitlad.fabric.presets.PRESET_HELP)
PRESET_VLAD_ERROR = {"fast": 0.14, "default": 0.18, "accurate": 0.08}
RUN_END_MARKERS = (("arrested", "o", True), ("edge", "s", False), ("time", "x", True), ("short", "^", False))
RUN_END_LABELS = {"arrested": "arrested", "edge": "reached an edge (damage: a lower bound)",
                  "time": "stopped at max_time_ms", "short": "velocity from under 5 stitches (rough)"}


def run_ends(df, velocity: bool = False):
    """How each run of a sweep table ended: arrested, edge (reached an edge course), time (max_time_ms), and
    with ``velocity`` short (a velocity fitted over fewer than 5 stitches, whatever the end)."""

    reason = df.get("stop_reason", pd.Series("", index=df.index)).astype(str)
    out = pd.Series("time", index=df.index)
    out[reason.str.startswith("no cell changed")] = "arrested"
    out[df.get("reached_edge", pd.Series(False, index=df.index)).astype(bool) | reason.str.contains("edge")] = "edge"
    if velocity and {"v_fit_first", "v_fit_last"} <= set(df):
        out[(df["v_fit_last"] - df["v_fit_first"] + 1) < 5] = "short"
    return out


def job_figure_names(df) -> dict[str, str]:
    """A file stem per job of a sweep table, from the parameters that vary between its jobs
    (``natural_curvature=1_mu=0.2_fx=3``); the job id is added where two jobs would share a stem."""
    params = [c for c in df.columns[: list(df.columns).index("status")] if c not in ("job_id", "scene")]
    varying = [c for c in params if df[c].astype(str).nunique() > 1]

    def value(v) -> str:
        return f"{v:g}" if isinstance(v, (int, float, np.number)) and not isinstance(v, bool) else str(v)

    stems = {row.job_id: "_".join(f"{c}={value(getattr(row, c))}" for c in varying) or row.job_id
             for row in df.itertuples()}
    counts = {}
    for stem in stems.values():
        counts[stem] = counts.get(stem, 0) + 1
    return {job: (stem if counts[stem] == 1 else f"{stem}_{job}") for job, stem in stems.items()}


def cycle_curve_plot(readings, n_x: int, stitch_length_m: float, fx_thr: float | None, delta_l_over_l0: float,
                     path: str | Path) -> Path:
    """Protocol B's force-displacement curve (paper, Fig. 4a): f_x against Delta x - Delta x_min [mm], one
    colour per cycle, the holds as dots; with f_x^thr, the threshold and delta l on the last unloading."""
    plt = _pyplot()
    r = np.asarray(readings)
    dx = (r[:, 3] - r[0, 3]) * n_x * stitch_length_m * 1e3
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for cycle in np.unique(r[r[:, 0] > 0, 0]).astype(int):
        rows = np.flatnonzero(r[:, 0] == cycle)
        rows = np.concatenate([[rows[0] - 1], rows])  # from where the cycle before ended
        line, = ax.plot(dx[rows], r[rows, 4], lw=1.2, label=f"cycle {cycle}")
        holds = rows[r[rows, 1] == 0]
        ax.plot(dx[holds], r[holds, 4], "o", ms=3, color=line.get_color())
    if fx_thr is not None:
        ax.axhline(fx_thr, color="0.4", ls="--", lw=0.8, label=r"$f_x^{\mathrm{thr}}$")
        if np.isfinite(delta_l_over_l0):
            top = dx.max()
            ax.annotate("", xy=(top - delta_l_over_l0 * stitch_length_m * 1e3, fx_thr), xytext=(top, fx_thr),
                        arrowprops=dict(arrowstyle="<->", color="k", lw=0.8))
            ax.text(top - 0.5 * delta_l_over_l0 * stitch_length_m * 1e3, fx_thr, r"$\delta l$", ha="center",
                    va="bottom")
    return _labelled(fig, ax, r"$\Delta x - \Delta x_{\min}$ [mm]", symbol("fx"), "protocol B", path)


def tensile_curve_plot(readings, path: str | Path) -> Path:
    """The tensile test (knitlad.experiments.tensile): f_x and f_y against the box's l_x/l0 (or l_y/l0 when only
    l_y moves), loading solid, unloading dashed, the hold a dot: the loop's area is what friction took."""
    plt = _pyplot()
    r = np.asarray(readings)
    along_y = np.ptp(r[:, 2]) == 0
    x = r[:, 3] if along_y else r[:, 2]
    fig, ax = plt.subplots(figsize=(5, 3.5))
    top = int(np.flatnonzero(r[:, 0] == 0)[0])
    for col, name in ((6, "fx"), (7, "fy")):
        line, = ax.plot(x[: top + 1], r[: top + 1, col], lw=1.2, label=symbol(name))
        ax.plot(x[top:], r[top:, col], lw=1.2, ls="--", color=line.get_color())
        ax.plot(x[top], r[top, col], "o", ms=3, color=line.get_color())
    ax.xaxis.set_major_locator(plt.MaxNLocator(5))
    return _labelled(fig, ax, r"$l_y/l_0$ of the box" if along_y else r"$l_x/l_0$ of the box",
                     r"tension per thread [$f_0$]", "tensile test (dashed: unloading)", path)


def tester_curve_plot(tester, along_x: bool, path: str | Path) -> Path:
    """The tensile test as a tester draws it: the pull per 5 cm of width against the extension in % of the gauge
    length, one colour per cycle, loading solid, unloading dashed (the loop's area is the hysteresis)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for k, (cycle, g) in enumerate(tester.groupby("cycle")):
        colour = f"C{k % 10}"
        up = g[g["leg"] != "unloading"]
        down = g[g["leg"] != "loading"]
        ax.plot(up["extension_pct"], up["force_N_per_5cm"], lw=1.2, color=colour, label=f"cycle {cycle}")
        ax.plot(down["extension_pct"], down["force_N_per_5cm"], lw=1.2, ls="--", color=colour)
    ax.xaxis.set_major_locator(plt.MaxNLocator(5))
    direction = "course (x)" if along_x else "wale (y)"
    return _labelled(fig, ax, "extension [% of the gauge length]", "force [N per 5 cm of width]",
                     f"tensile test along the {direction}, dashed: unloading", path)


def snag_curve_plot(pull_m, force_N, path: str | Path, broke: bool = False) -> Path:
    """The snag's pull-out curve (knitlad.experiments.snag): the force the yarn holds the pin back with against
    the pin's travel; a cross where the yarn broke."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5, 3.5))
    pull_mm = np.asarray(pull_m) * 1e3
    ax.plot(pull_mm, force_N, lw=1.2)
    if broke and len(pull_mm) > 1:  # the last reading is after the break: mark the one before it
        ax.plot(pull_mm[-2], np.asarray(force_N)[-2], "x", ms=8, color="C3", label="the yarn breaks")
    return _labelled(fig, ax, "pin travel [mm]", "pull-out force [N]", "snag", path)


def damage_prediction_plot(df, path: str | Path) -> Path:
    """Paper Fig. 4c: the damage of protocol B's cut, n_lad/n_y, against Eq. 1's delta l/(l0 - l_x), one
    series per l_y/l0 (or per ``series`` label, where the table has that column: sweeps compared); open
    symbols where a ladder reached an edge course (the knit too small for it)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(4.5, 3.4))
    by = "series" if "series" in df else "ly" if "ly" in df else None
    for key, g in df.groupby(by, sort=False) if by else [(None, df)]:
        label = "knitlad" if key is None else key if by == "series" else f"{symbol('ly')} = {key}"
        line, = ax.plot(g["predicted_damage"], g["cut_n_lad_over_ny"], "o", ms=5, label=label)
        edge = g[g["cut_reached_edge"].astype(bool)] if "cut_reached_edge" in g else g.iloc[:0]
        ax.plot(edge["predicted_damage"], edge["cut_n_lad_over_ny"], "o", ms=9, mfc="none", color=line.get_color())
    top = float(np.nanmax([df["predicted_damage"].max(), df["cut_n_lad_over_ny"].max(), 1.0]))
    ax.plot([0, top], [0, top], "k:", lw=0.8, label="Eq. 1")
    ax.plot([], [], "o", ms=9, mfc="none", color="0.4", label="a ladder reached an edge course")
    return _labelled(fig, ax, r"$\delta l/(l_0 - l_x)$", symbol("n_lad_over_ny"), "damage against Eq. 1 (paper Fig. 4c)",
                     path)


def final_tension_plot(df, path: str | Path) -> Path:
    """Paper Fig. 3f read where the arrest happens: f_x^fin against f_x^ini, the mean over every course, the
    courses the ladder crossed and the others (a sweep's summary table, sorted by f_x^ini)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(4.5, 3.4))
    for column, label in (("fx_fin", "every course"), ("fx_fin_crossed", "courses the ladder crossed"),
                          ("fx_fin_intact", "the others")):
        ax.plot(df["fx_ini"], df[column], "o-", ms=4, label=label)
    top = float(df["fx_ini"].max())
    ax.plot([0, top], [0, top], "k:", lw=0.8, label=f"{symbol('fx_fin')} = {symbol('fx_ini')}")
    return _labelled(fig, ax, symbol("fx_ini"), symbol("fx_fin"), "tension after arrest (paper Fig. 3f)", path)


def resistance_report(result, path: str | Path, picture: str | Path | None = None) -> Path:
    """One page of a ladder-resistance test (:class:`knitlad.experiments.resistance.ResistanceResult`): the
    design and what its numbers are worth, the snag's pull-out curve, the damage and the velocity against
    f_x^ini with the threshold bracket, and ``picture`` (a render of the ladder where it stopped), if given."""
    from knitlad.fabric.presets import PRESET_ERRORS

    plt = _pyplot()
    fig = plt.figure(figsize=(11, 8.5))
    grid = fig.add_gridspec(2, 3, height_ratios=[1, 1.15], width_ratios=[1.25, 1, 1.1])
    design, row, table = result.design, result.summary(), result.table()
    lo, hi = result.threshold_bracket()
    band = "no band" if design["band"] == "none" else f"a {design['band']} band from course {design['band_row']}"
    if np.isfinite(lo) and np.isfinite(hi):
        threshold = f"between {lo:.2f} and {hi:.2f}"
    elif np.isfinite(hi):
        threshold = f"below {hi:.2f} (every tension laddered)"
    elif np.isfinite(lo):
        threshold = f"above {lo:.2f} (no tension laddered)"
    else:
        threshold = "no cut run"
    snag_line = (f"broke after {row['snag_pull_at_break_mm']:.2f} mm" if row["snag_broke"] else "no break")
    text = [f"knit: {design['n_x']} x {design['n_y']} {design['pattern']}, {band}",
            f"yarn: d/l0 = {design['d_over_l0']:.4g}, mu = {design['mu']}",
            f"preset: {design['preset']} ({design['resolution']} nodes/stitch); its error:",
            *textwrap.wrap(PRESET_ERRORS.get(design["preset"], "not measured"), 44, initial_indent="  ",
                           subsequent_indent="  "),
            "",
            f"snag at f_x^ini {row['snag_fx_ini']:.2f}:",
            f"  peak pull-out force {row['snag_peak_force_N']:.3f} N, {snag_line}",
            *([f"threshold f_x^thr: {threshold}" + ("" if row["monotonic"] else " (not monotonic)")]
              if design["band"] == "none" else []),  # with a band the question is whether it holds
            *textwrap.wrap(f"rule: {result.rule()}", 44),
            *(f"  f_x^ini {c.fx_ini:.2f}: {v}" for c, v in zip(result.cuts, result.verdicts())),
            "one knit per tension: one run scatters",
            "  by about 20 % at low tension"]
    ax = fig.add_subplot(grid[0, 0])
    ax.axis("off")
    ax.text(0, 1, "\n".join(text), va="top", fontsize=7, family="monospace", transform=ax.transAxes)
    ax.set_title("the design", fontsize=9, loc="left")
    ax = fig.add_subplot(grid[0, 1])
    snag = result.snag
    ax.plot(np.asarray(snag.pull_m) * 1e3, snag.force_N, lw=1.2)
    if snag.broke and len(snag.pull_m) > 1:
        ax.plot(snag.pull_m[-2] * 1e3, snag.force_N[-2], "x", ms=8, color="C3", label="the yarn breaks")
        ax.legend(fontsize=7)
    ax.set_xlabel("pin travel [mm]")
    ax.set_ylabel("pull-out force [N]")
    ax.set_title("the snag", fontsize=9)
    ax = fig.add_subplot(grid[0, 2])
    edge = table[:, 6] > 0
    ax.plot(table[:, 1], table[:, 2], "o-", label=symbol("n_lad_over_ny"))
    ax.plot(table[:, 1], table[:, 3], "s--", label="released into loaded courses")
    ax.plot(table[edge, 1], table[edge, 2], "o", ms=11, mfc="none", color="0.4", label="reached an edge course")
    for f in (lo, hi):
        if np.isfinite(f):
            ax.axvline(f, color="C3", lw=0.8, ls=":")
    if np.isfinite(table[:, 4]).any():  # an axis of velocities only where a front ran far enough to fit one
        ax2 = ax.twinx()
        ax2.plot(table[:, 1], table[:, 4], "^-", color="C2")
        ax2.set_ylabel(symbol("v_lad_over_cb") + " (triangles)", color="C2")
    else:
        ax.text(0.98, 0.02, "no front ran far enough to fit a velocity", ha="right", va="bottom", fontsize=6.5,
                transform=ax.transAxes)
    ax.set_xlabel(symbol("fx_ini"))
    ax.set_ylabel("damage")
    ax.legend(fontsize=6.5, loc="upper left")
    ax.set_title("the cut against tension (dotted: the threshold's bracket)", fontsize=9)
    ax = fig.add_subplot(grid[1, :])
    ax.axis("off")
    if picture is not None:
        ax.imshow(plt.imread(str(picture)))
        gold = "" if design["band"] == "none" else "; gold: the run-stop band"
        ax.set_title(f"the ladder where it stopped (the highest tension that laddered, else the snag's{gold})", fontsize=9)
    fig.tight_layout()
    return _save(fig, Path(path))
