"""The experiments, each with one entry that serves both the command line and sweeps.

An entry names the experiment's config, its runner and its summary columns once. A runner takes the
validated config, the output options, a folder where stretched knits are kept and shared (None: stretch
in memory) and a progress callback ``progress(stage, fraction)`` (or None), runs the experiment, and returns
a :class:`Finished`: the result, its summary (a dict of scalars), the writer of its run file, and the writer
of the tables and pictures the command line puts beside that file. A sweep's job writes the run file alone
(``<job>.h5``, with the job's record: id, status, config); `knitlad <experiment>` writes it and its companions.
To add an experiment: its module in :mod:`knitlad.experiments`, a pydantic config in
:mod:`knitlad.experiments.config`, a runner here and one entry in ``EXPERIMENTS``: the entry makes
``knitlad <name>`` (:func:`knitlad.cli.experiment_command`) and ``scene: <name>`` in sweeps; a command with lines
of its own is written in :mod:`knitlad.cli` and still runs the entry. An entry whose results name a column its
summary does not keep is refused at import, naming it.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from pydantic import BaseModel

from knitlad.engine.units import si_twin_meanings, si_twins
from knitlad.experiments.config import (
    CutConfig,
    CycleConfig,
    DiagramConfig,
    LoopConfig,
    ResistanceConfig,
    SnagConfig,
    StitchConfig,
    TensileConfig,
)


@dataclass(frozen=True)
class Experiment:
    """An experiment's one entry: a sweep runs it (its name is the sweep config's ``scene:``) and the command line
    runs it through the same ``run``."""

    config: type[BaseModel]
    run: Callable  # (config, output options, knit folder, progress) -> Finished
    summary_keys: tuple[str, ...]  # the results a sweep's summary table shows, in order
    description: str
    shared_work: Callable | None = None  # config -> key of work that jobs with the same key share
    results: dict[str, tuple[str, str]] = dataclasses.field(default_factory=dict)  # key -> (unit, meaning)

    def __post_init__(self) -> None:
        stray = [key for key in self.results if key not in self.summary_keys]
        if stray:
            raise ValueError(f"experiment {self.description.split(':')[0]}: results {', '.join(stray)} are not among "
                             "its summary_keys (the columns its summary keeps)")


def no_companions(path: Path) -> tuple[Path, ...]:
    return ()


@dataclass(frozen=True)
class Finished:
    """One finished run of an experiment: what a sweep's job and the command line both take from it."""

    result: Any
    summary: dict
    write: Callable[[Path, dict], Path]  # (path, record) -> the run file, the record among its attributes
    beside: Callable[[Path], tuple[Path, ...]] = no_companions  # run file -> the tables and pictures beside it


def stretch_of(cfg: CutConfig) -> str:
    """Laddering jobs with the same stretch settings share one stretched knit."""
    from knitlad.io.knit_cache import stretch_key

    return stretch_key(cfg.stretch_settings())


def prepared_knit(cfg: CutConfig, folder: Path | None, progress=None):
    """(the stretched knit of ``cfg``, whether it was read): kept in ``folder/stretched`` and reused by the runs
    that share its settings (:mod:`knitlad.io.knit_cache`), or stretched in memory without a folder."""
    from knitlad.fabric.preparation import stretch
    from knitlad.io.knit_cache import cached_stretch

    if folder is None:
        return stretch(cfg.stretch_settings(), progress), False
    return cached_stretch(cfg.stretch_settings(), Path(folder) / "stretched", stretch, progress)


def _compression(output) -> str | None:
    return None if output.compression == "none" else output.compression


def _ladder_companions(ladder, path: Path) -> tuple[Path, ...]:
    """A ladder's ParaView file beside its run file and its spatio-temporal diagram."""
    from knitlad.io.xdmf import write_xdmf
    from knitlad.viz.plots import spatio_temporal_diagram

    return write_xdmf(path), spatio_temporal_diagram(ladder, path.with_name("spatio_temporal.png"))


def run_ladder_job(cfg: CutConfig, output, folder: Path | None = None, progress=None) -> Finished:
    """The laddering experiment (`knitlad cut`); its file holds the frames and series (:mod:`knitlad.io.hdf5`).
    A sweep over the dynamics stretches once (:func:`prepared_knit`)."""
    import time

    from knitlad.io.hdf5 import write_ladder_result
    from knitlad.experiments.laddering import analyse, cut, propagate, require_memory, require_tension

    require_memory(cfg.memory_estimate_bytes(), f"a {cfg.n_x} x {cfg.n_y} knit at {cfg.resolution} nodes per stitch")
    t0 = time.perf_counter()
    knit, reused = prepared_knit(cfg, folder, progress)
    if reused:  # the stretch cost this job only the reading
        knit = dataclasses.replace(knit, wall_s=time.perf_counter() - t0)
    require_tension(knit)  # a compressed knit's "ladder" is no result: the job fails, saying why
    result = analyse(propagate(cut(knit, cfg.dynamics_settings()), progress=progress))
    if not output.frames:
        result.frames, result.frame_times_s = [], []

    def write(path: Path, record: dict) -> Path:
        return write_ladder_result(path, result, compression=_compression(output),
                                   attrs={**record, "stretch_reused": reused})

    return Finished(result, {**result.summary(), "stretch_reused": reused}, write,
                    lambda path: _ladder_companions(result, path))


def run_cycle_job(cfg: CycleConfig, output, folder: Path | None = None, progress=None, **checkpoints) -> Finished:
    """Protocol B (`knitlad cycle`): its file holds the readings and, if cut, the ladder; beside it the readings'
    table and Fig. 4a. ``checkpoints``: :func:`knitlad.experiments.cycling.run_protocol_b`'s ``after_leg``,
    ``keep`` and ``resume`` (the command line's)."""
    from knitlad.experiments.cycling import run_protocol_b
    from knitlad.io.hdf5 import write_cycle_result

    knit = None if folder is None else prepared_knit(cfg, folder, progress)[0]
    cycle, ladder = run_protocol_b(cfg.settings(), cfg.cycle_settings(), progress=progress,
                                   knit=knit, **checkpoints)
    summary = {**cycle.summary(), **({f"cut_{k}": v for k, v in ladder.summary().items()} if ladder else {})}
    summary = with_si(summary, cfg.material(), cfg.n_y, CYCLE_RESULTS)
    if ladder is not None and not output.frames:
        ladder.frames, ladder.frame_times_s = [], []

    def write(path: Path, record: dict) -> Path:
        return write_cycle_result(path, cycle, ladder, cfg.model_dump(), compression=_compression(output),
                                  attrs=record)

    def beside(path: Path) -> tuple[Path, ...]:
        from knitlad.viz.plots import cycle_curve_plot

        return (write_cycle_table(path.with_suffix(".csv"), cycle.readings),
                cycle_curve_plot(cycle.readings, cfg.n_x, cfg.settings().material.stitch_length, cfg.fx_thr,
                                 cycle.delta_l_over_l0, path.with_suffix(".png")))

    return Finished((cycle, ladder), summary, write, beside)


def write_cycle_table(path: Path, readings) -> Path:
    """Protocol B's readings (cycle, leg: 1 loading, 0 hold, -1 unloading, t [s], box l_x/l0, f_x) as CSV."""
    from knitlad.io.summary import write_table

    return write_table(path, readings, ("cycle", "leg", "t_s", "box_lx_over_l0", "fx"))


def run_tensile_job(cfg: TensileConfig, output, folder: Path | None = None, progress=None) -> Finished:
    """The tensile test (`knitlad tensile`): its file holds the readings (:func:`knitlad.io.hdf5.write_tensile_result`);
    beside it their table and the force-displacement loops."""
    import pandas as pd

    from knitlad.experiments.tensile import COLUMNS, LEG_NAMES, RESULTS_COLUMNS, TESTER_COLUMNS, run_tensile
    from knitlad.io.hdf5 import write_tensile_result

    result = run_tensile(prepared_knit(cfg, folder, progress)[0], cfg.tensile_settings(), cfg.dynamics_settings(),
                         progress)

    def write(path: Path, record: dict) -> Path:
        return write_tensile_result(path, result, cfg.model_dump(), attrs=record)

    def beside(path: Path) -> tuple[Path, ...]:
        from knitlad.io.summary import write_table
        from knitlad.viz.plots import tensile_curve_plot, tester_curve_plot

        tester = pd.DataFrame(result.tester_readings(), columns=list(TESTER_COLUMNS))
        tester["cycle"] = tester["cycle"].astype(int)
        tester["leg"] = tester["leg"].map(LEG_NAMES)
        return (write_table(path.with_suffix(".csv"), result.readings, COLUMNS),
                tensile_curve_plot(result.readings, path.with_suffix(".png")),
                write_table(path.with_name(path.stem + "_tester.csv"), tester, TESTER_COLUMNS),
                write_table(path.with_name(path.stem + "_results.csv"), pd.DataFrame(result.tester_results()),
                            RESULTS_COLUMNS),
                tester_curve_plot(tester, result.along_x, path.with_name(path.stem + "_tester.png")))

    return Finished(result, result.summary(), write, beside)


def run_snag_job(cfg: SnagConfig, output, folder: Path | None = None, progress=None) -> Finished:
    """A snag (`knitlad snag`): its file holds the pull-out curve and, after a break, the ladder
    (:func:`knitlad.io.hdf5.write_snag_result`); beside it the curve's table and picture, and the ladder's."""
    from knitlad.experiments.snag import snag
    from knitlad.io.hdf5 import write_snag_result

    knit = prepared_knit(cfg, folder, progress)[0]
    result = snag(knit, cfg.dynamics_settings(), cfg.snag_settings(), progress)
    if result.ladder is not None and not output.frames:
        result.ladder.frames, result.ladder.frame_times_s = [], []

    def write(path: Path, record: dict) -> Path:
        return write_snag_result(path, result, knit.settings.material, cfg.model_dump(),
                                 compression=_compression(output), attrs=record)

    def beside(path: Path) -> tuple[Path, ...]:
        import numpy as np

        from knitlad.io.summary import write_table
        from knitlad.viz.plots import snag_curve_plot

        curve = (write_table(path.with_suffix(".csv"), np.column_stack([result.pull_m * 1e3, result.force_N]),
                             ("pull_mm", "force_N")),
                 snag_curve_plot(result.pull_m, result.force_N, path.with_suffix(".png"), result.broke))
        return curve + (() if result.ladder is None else _ladder_companions(result.ladder, path))

    return Finished(result, with_si(result.summary(), knit.settings.material, cfg.n_y, SNAG_RESULTS), write, beside)


def run_resistance_job(cfg: ResistanceConfig, output, folder: Path | None = None, progress=None) -> Finished:
    """A ladder-resistance test (`knitlad resistance`): its file holds the cut series, the snag's curve and
    the pictured ladder's run file, with its one-page report drawn beside it (``<file>_report.png``, in a
    sweep too: the report is the test's product); the command line adds the series' table."""
    from knitlad.experiments.resistance import run_resistance
    from knitlad.io.hdf5 import write_resistance_result

    knits = {}

    def stretch_for(one):  # the snag and the cut at its tension share one stretched knit
        key = (one.fx, one.lx)
        if key not in knits:
            knits[key] = prepared_knit(one, folder, progress)[0]
        return knits[key]

    result = run_resistance(cfg, stretch_for, progress)

    def write(path: Path, record: dict) -> Path:
        write_resistance_result(path, result, result.cuts[0].settings.stretch.material, cfg.model_dump(),
                                compression=_compression(output), attrs=record)
        draw_resistance_report(result, path, path.with_name(f"{path.stem}_report.png"))
        return path

    def beside(path: Path) -> tuple[Path, ...]:
        from knitlad.io.summary import write_table

        return (write_table(path.with_suffix(".csv"), result.table(), (
            "fx_target", "fx_ini", "n_lad_over_ny", "released_over_ny", "v_lad_over_cb", "fx_fin_crossed",
            "reached_edge")), path.with_name(f"{path.stem}_report.png"))

    return Finished(result, with_si(result.summary(), cfg.material(), cfg.n_y, RESISTANCE_RESULTS), write, beside)


def draw_resistance_report(result, h5: Path, png: Path) -> Path:
    """The report of ``result`` with a front view of the last frame of the ladder its file ``h5`` holds."""
    import tempfile

    from knitlad.viz.plots import resistance_report
    from knitlad.viz.render import Run, render_run

    if result.pictured() is None:
        return resistance_report(result, png)
    run, f = Run.open(h5)
    last = float(run.times_s[-1])
    f.close()
    with tempfile.TemporaryDirectory() as tmp:
        picture = render_run(h5, tmp, times_s=[last], views=("front",), size=(1400, 700))[-1]
        return resistance_report(result, png, picture)


def with_si(summary: dict, material, threads: int, results: dict[str, tuple[str, str]]) -> dict:
    """``summary`` and, beside each result in the paper's units, its SI twin (:func:`knitlad.engine.units.si_twin`)
    for ``material`` on ``threads`` threads."""
    return {**summary, **si_twins(summary, material, threads, results)}


def si_columns(keys: tuple[str, ...], results: dict[str, tuple[str, str]], threads: str):
    """(summary keys, results) with the SI twins of the results in the paper's units, before the wall times."""
    twins = si_twin_meanings(results, threads)
    cut = next((k for k, key in enumerate(keys) if key in ("wall_s", "job_wall_s")), len(keys))
    return keys[:cut] + tuple(twins) + keys[cut:], {**results, **twins}


def _attributes_only(result, results: dict[str, tuple[str, str]] | None = None) -> Finished:
    """A reduced model's result, and a writer of a file of attributes (summary with its SI twins for one thread,
    settings, scales)."""
    from knitlad.io.hdf5 import scale_attributes, write_record

    summary = with_si(result.summary(), result.settings.material, 1, results or {})
    settings = {k: v for k, v in dataclasses.asdict(result.settings).items() if k != "material"}
    scales = scale_attributes(result.settings.material)

    def write(path: Path, record: dict) -> Path:
        return write_record(path, {**summary, **record, "settings_json": json.dumps(settings), **scales})

    return Finished(result, summary, write)


def run_loop_job(cfg: LoopConfig, output, folder: Path | None = None, progress=None) -> Finished:
    """The single loop (`knitlad loop`): a file of attributes."""
    from knitlad.experiments.periodic_loop import run_single_loop

    return _attributes_only(run_single_loop(cfg.settings()), LOOP_RESULTS)


def run_stitch_job(cfg: StitchConfig, output, folder: Path | None = None, progress=None) -> Finished:
    """The periodised stitch (`knitlad stitch`): a file of attributes."""
    from knitlad.fabric.stitch_model import StitchRun

    return _attributes_only(StitchRun(cfg.settings()).run(), STITCH_RESULTS)


def run_diagram_job(cfg: DiagramConfig, output, folder: Path | None = None, progress=None) -> Finished:
    """One point of the configuration diagram (`knitlad diagram`): a file of attributes."""
    from knitlad.fabric.stitch_model import zero_tension_width

    return _attributes_only(zero_tension_width(cfg.settings()))


# each experiment's results, as its summary columns: (unit, meaning) (units: knitlad.studies.columns)
LADDER_RESULTS = {
    "fx_ini": ("f0", "f_x^ini: the tension per thread of the stretched knit, just before the cut"),
    "fx_fin": ("f0", "f_x^fin: the mean tension at the stop (over the last half arrest window); after an arrest the "
                     "paper's Fig. 3f, else (reached_edge, or the time limit) the tension of that moment"),
    "fx_fin_crossed": ("f0", "f_x at the stop of the courses the ladder crossed (with an undone cell)"),
    "fx_fin_intact": ("f0", "f_x at the stop of the courses it did not cross"),
    "n_lad": ("cells", "cells undone at the stop, as the paper counts them on a photograph after the arrest (with "
                       "those whose yarn has gone, the cut course's pulled out)"),
    "n_lad_over_ny": ("1", "n_lad/n_y: the damage, in columns of the knit's height (paper Fig. 3e)"),
    "n_lad_ever": ("cells", "cells undone at any time after the cut (some knit themselves again)"),
    "n_lad_rehooked": ("cells", "of n_lad_ever, the cells hooked again at the stop (intact on a photograph)"),
    "n_lad_between": ("cells", "of n_lad_ever, the cells at the stop neither hooked nor a bar (head below the "
                               "sinkers above by less than 0.25 l_y): in neither count"),
    "v_lad_over_cb": ("c_b", "v_lad/c_b as the paper reads it: the slope of the laddering column's mid-point front "
                             "(spatio-temporal diagram) from stitch v_fit_first to v_fit_last (NaN: the front ran "
                             "fewer than 3 stitches; stop_reason says why)"),
    "v_lad_first_arrival_over_cb": ("c_b", "the same fit to the cells' first arrival (head 0.25 l_y below the "
                                           "sinkers): knitlad's v_lad before 0.15"),
    "lx_over_l0": ("l0", "l_x/l0 measured on the stretched knit (not the box's: box_lx_over_l0)"),
    "ly_over_l0": ("l0", "l_y/l0 measured on the stretched knit"),
    "force_ini_N": ("N", "F_x^ini = f_x^ini n_y f0: the knit's pull before the cut"),
    "force_fin_N": ("N", "F_x^fin = f_x^fin n_y f0"),
    "force_ini_N_per_cm": ("N/cm", "F_x^ini per cm of the knit's width n_x l_x"),
    "force_fin_N_per_cm": ("N/cm", "F_x^fin per cm of the knit's width n_x l_x"),
    "v_lad_m_s": ("m/s", "v_lad = (v_lad/c_b) c_b"),
    "l0_mm": ("mm", "the stitch length l0 (the yarn per stitch)"),
    "lx_mm": ("mm", "l_x, the stitch's width (10 / l_x: wales per cm)"),
    "ly_mm": ("mm", "l_y, the stitch's height (10 / l_y: courses per cm)"),
    "loop1_column": ("index", "the column of loop (1): the needle loop beside the cut the cut thread left first "
                              "(-1: it left neither)"),
    "loop1_freed_ms": ("ms", "when the cut thread left loop (1)"),
    "up_from_1_ms": ("ms", "when the ladder up from loop (1) started (NaN: none ran)"),
    "down_from_2_3_ms": ("ms", "when the first ladder down from loops (2)/(3), the heads below the cut, started"),
    "up_from_4_5_ms": ("ms", "when the second upward ladder, from loops (4)/(5), the cut thread's next needle "
                             "loops, started (NaN: none ran)"),
    "other_ladders": ("1", "ladders no freed loop of the cut thread explains"),
    "loop_sequence": ("-", "the freed loops whose ladders ran, in the order they started ('(1), (2)/(3), (4)/(5)')"),
    "paper_order": ("-", "the ladders started in the paper's order: (1), then (2)/(3), then (4)/(5)"),
    "cut_thread_held": ("-", "the cut thread ends held in both loops (4) and (5)"),
    "hindered": ("-", "the paper's hindered laddering: ladders from (1) and (2)/(3), the cut thread held in (4) "
                      "and (5), no second upward ladder"),
    "n_lad_cut_row": ("cells", "undone cells of the cut's own course (its yarn is cut: they free no length into a "
                      "loaded course)"),
    "n_lad_immediate": ("cells", "other cells undone within 0.1 ms of the cut (its recoil, not the ladder's run)"),
    "n_lad_released": ("cells", "the rest of n_lad: cells the ladder released into loaded courses (Eq. 1's count)"),
    "n_lad_released_over_ny": ("1", "n_lad_released / n_y: the damage Eq. 1 predicts, like for like"),
    "n_lad_released_taut": ("cells", "of n_lad_released, the cells whose bar is taut at the stop (head 0.75 l_y "
                                     "below the sinkers): each released l0 - l_x, as Eq. 1 counts"),
    "n_lad_released_taut_over_ny": ("1", "n_lad_released_taut / n_y"),
    "box_lx_over_l0": ("l0", "the box's l_x/l0: the held ends' spacing over n_x l0"),
    "fx_within_tolerance": ("-", "force control: f_x^ini came within fx_tolerance of the target"),
    "peak_overlap_over_d": ("1", "the deepest yarn-yarn overlap at any step, over d"),
    "reached_edge": ("-", "the ladder reached an edge course: damage and f_x^fin are lower bounds"),
    "stop_reason": ("-", "why the run stopped: an arrest, an edge course, max_time_ms, or stop_after_stitches"),
    "laddering_column": ("index", "the column beside the cut whose front was followed"),
    "v_fit_stitches": ("stitches", "[first, last] stitches of the velocity fit, as text (v_fit_first, v_fit_last)"),
    "v_fit_first": ("stitches", "the first stitch of the velocity fit (the paper: 2)"),
    "v_fit_last": ("stitches", "the last stitch of the velocity fit (the paper: 10; fewer on a small knit)"),
    "energy_start_J": ("J", "the energy the knit stored just after the cut (elastic, contacts, kinetic)"),
    "energy_end_J": ("J", "the energy it stored at the stop"),
    "dissipated_friction_J": ("J", "energy friction took out (sliding, the tangential dashpot, springs reset)"),
    "dissipated_contact_dashpot_J": ("J", "energy the contacts' normal dashpots took out (numerical)"),
    "dissipated_axial_dashpot_J": ("J", "energy the axial dashpots took out (numerical; with implicit axial "
                                        "springs also their damping of axial waves)"),
    "dissipated_material_J": ("J", "energy the yarn's viscoelasticity took out (loss_factor > 0)"),
    "dissipated_air_J": ("J", "energy the air took out (air_drag)"),
    "dissipated_global_drag_J": ("J", "energy the global drag took out (drag_per_s > 0)"),
    "dissipated_fracture_J": ("J", "elastic energy stored in the segments a break cut away (0: no yarn broke)"),
    "owner_changes_J": ("J", "energy the union contact counting created (or, < 0, destroyed) where a contact passed "
                             "from one edge to its neighbour: booked so the ledger closes; 0 counting all pairs"),
    "ledger_residual": ("1", "the energy ledger's residual over the energy turned over: the integrator's error "
                             "(docs/dissipation.md)"),
    "nan_reasons": ("-", "why each result that is NaN is NaN: 'column: reason; ...' (empty: none is)"),
    "nodes": ("1", "nodes of the knit"),
    "steps": ("1", "time steps of the laddering"),
    "relax_steps": ("1", "FIRE steps of the stretch and its relaxation"),
    "stretch_reused": ("-", "the stretched knit came from the sweep's cache"),
    "wall_stretch_s": ("s", "wall time of the stretch"),
    "wall_propagate_s": ("s", "wall time of the laddering"),
}

CYCLE_RESULTS = {
    "fx_ini": ("f0", "f_x^ini: the tension at Delta x_max of the last cycle, where the copy is cut"),
    "lx_over_l0": ("l0", "l_x/l0 measured there"),
    "ly_over_l0": ("l0", "l_y/l0 measured there"),
    "lx_max": ("l0", "the box's l_x/l0 at Delta x_max"),
    "fx_thr": ("f0", "the threshold f_x^thr at which delta l is read (NaN: not read)"),
    "delta_l_over_l0": ("l0", "delta l/l0: the uncut twin's shortening from f_x^ini to f_x^thr (Eq. 1)"),
    "predicted_damage": ("1", "Eq. 1's n_lad/n_y = delta l/(l0 - l_x)"),
    "fx_thr_own": ("f0", "the paper's f_thr: the tension at the bars once the cut copy's ladder stopped (its f_x^fin)"),
    "delta_l_own_over_l0": ("l0", "delta l/l0 read down to fx_thr_own (Eq. 1 as the paper reads it)"),
    "predicted_damage_own": ("1", "Eq. 1's n_lad/n_y from delta_l_own_over_l0"),
    "cut_n_lad_over_ny": ("1", "the cut copy's damage n_lad/n_y"),
    "cut_fx_fin": ("f0", "the cut copy's f_x^fin"),
    "cut_fx_fin_crossed": ("f0", "the cut copy's f_x at the stop of the courses its ladder crossed"),
    "cut_reached_edge": ("-", "the cut copy's ladder reached an edge course"),
    "cut_n_lad_ever": ("cells", "the cut copy's cells undone at any time"),
    "cut_loop_sequence": ("-", "the freed loops whose ladders ran, in order (loop_sequence)"),
    "cut_up_from_4_5_ms": ("ms", "when the second upward ladder, from loops (4)/(5), started (NaN: none ran)"),
    "cut_hindered": ("-", "the paper's hindered laddering: the cut thread held in loops (4) and (5)"),
    "cut_n_lad_cut_row": ("cells", "the cut copy's undone cells of the cut course"),
    "cut_n_lad_immediate": ("cells", "the cut copy's other cells undone within 0.1 ms of the cut"),
    "cut_n_lad_released": ("cells", "the cut copy's cells released into loaded courses (Eq. 1's count)"),
    "cut_n_lad_released_over_ny": ("1", "cut_n_lad_released / n_y: the damage to set beside Eq. 1, like for like"),
    "cut_n_lad_released_taut": ("cells", "of cut_n_lad_released, the cells whose bar is taut at the stop"),
    "cut_n_lad_released_taut_over_ny": ("1", "cut_n_lad_released_taut / n_y"),
    "hold_converged": ("-", "the last hold at Delta x_max settled within hold_ms"),
    "nan_reasons": ("-", "why delta l and the predicted damage are NaN, if they are ('column: reason; ...')"),
    "cut_nan_reasons": ("-", "why a result of the cut copy's ladder is NaN ('column: reason; ...')"),
}

LOOP_RESULTS = {
    "tau_s": ("s", "tau: the time the loop took to let go after the lower row was removed"),
    "tau_contact_s": ("s", "the time until its last contact with the row above broke"),
    "v_lad_over_cb": ("c_b", "l_y/(tau c_b): the single loop's laddering velocity (paper Fig. 5c)"),
    "released": ("-", "the loop let go within max_time_ms"),
    "relax_converged": ("-", "the relaxation before the release converged"),
    "contacts_before": ("1", "touching pairs between the loop and the row above before the release"),
    "steps": ("1", "time steps of the run"),
    "nodes": ("1", "nodes of the scene"),
    "lx_over_l0": ("l0", "l_x/l0 at the start"),
    "lx_end_over_l0": ("l0", "l_x/l0 at the end"),
    "climb_over_ly": ("1", "how far the loop's head rose, over l_y"),
}

STITCH_RESULTS = {
    "fx": ("f0", "f_x of the periodised stitch (its tension per thread along the course)"),
    "fy": ("f0", "f_y, along the wale"),
    "converged": ("-", "the relaxation reached its force tolerance"),
    "max_overlap_over_d": ("1", "the deepest yarn-yarn overlap, over d"),
    "relax_steps": ("1", "FIRE steps of the relaxation"),
}

DIAGRAM_RESULTS = {
    "lx_over_l0_at_fx0": ("l0", "the width l_x/l0 at which the relaxed periodised stitch carries f_x = 0 at ly (the "
                                "configuration diagram's curve)"),
}

TENSILE_RESULTS = {
    "fx_start": ("f0", "f_x per course at the start (the knit stretched at mu = 0)"),
    "fy_start": ("f0", "f_y per column at the start"),
    "fx_top": ("f0", "f_x after the hold at the top of the loading"),
    "fy_top": ("f0", "f_y after the hold at the top"),
    "lx_top_over_l0": ("l0", "the knit's own l_x/l0 there (measured on its free courses)"),
    "ly_top_over_l0": ("l0", "the knit's own l_y/l0 there"),
    "fx_end": ("f0", "f_x after the unloading (or at the top without one)"),
    "fy_end": ("f0", "f_y after the unloading"),
    "coupling": ("1", "the loading's change of the transverse tension over the pulled one (d f_y/d f_x pulling "
                      "along x, d f_x/d f_y along y; NaN biaxial): the Poisson coupling at fixed bars"),
    "dissipated_per_stitch": ("f0 l0", "the work friction took per stitch over the closed path, the integral of "
                                       "f_x dl_x + f_y dl_y (NaN without the unloading)"),
    "hold_converged": ("-", "the hold at the top settled within hold_ms"),
    "gauge_length_mm": ("mm", "the tester's gauge: the held ends' distance at the start along the pull"),
    "width_mm": ("mm", "the strip's width across the pull (n_y l_y pulling along x)"),
    "peak_force_N": ("N", "the first cycle's largest pull, F_x = f_x n_y f0 (F_y = f_y n_x f0 along y)"),
    "peak_force_N_per_5cm": ("N/5cm", "the same per 5 cm of width"),
    "extension_at_peak_mm": ("mm", "the gauge's extension there"),
    "extension_at_peak_pct": ("%", "the same over the gauge length"),
    "initial_modulus_N_per_5cm": ("N/5cm", "the first loading's secant d(F per 5 cm)/d(strain) over its first ramp"),
    "hysteresis_energy_mJ": ("mJ", "the first cycle's hysteresis: the bars' work over its closed path, what "
                                   "friction took (NaN without the unloading)"),
    "cycles": ("1", "the loadings run"),
}

SNAG_RESULTS = {
    "snag_row": ("1", "the hooked loop's course"),
    "snag_column": ("1", "the hooked loop's column"),
    "broke": ("-", "the yarn broke before the pin's max_pull_mm"),
    "peak_force_N": ("N", "the largest force the yarn held the pin back with (the pull-out curve's peak)"),
    "pull_at_break_mm": ("mm", "the pin's travel when the yarn broke (NaN: no break)"),
    "break_tension_N": ("N", "the broken segment's tension at the break"),
    "break_row": ("1", "the course of the first break (-1: none)"),
    "break_column": ("1", "the column of the first break (-1: none)"),
    "pin_work_J": ("J", "the work the pin did on the knit until the break (or the pull's end)"),
    "friction_before_break_J": ("J", "what friction took during the pull"),
    "ladder_released_J": ("J", "the stored energy the ladder released, from the break to its stop"),
    "fx_ini": ("f0", "f_x of the stretched knit before the snag"),
    "n_lad_over_ny": ("1", "the ladder's undone cells over n_y, counted from the break"),
    "v_lad_over_cb": ("c_b", "the ladder's velocity (fit over stitches 2 to 10 above the break)"),
    "v_down_over_cb": ("c_b", "the downward front's velocity (fit over stitches 2 to 10 below the break): a broken "
                              "head frees the course below first"),
    "fx_fin": ("f0", "f_x after the ladder arrested"),
    "reached_edge": ("-", "the ladder reached an edge course"),
}

RESISTANCE_RESULTS = {
    "design_pattern": ("-", "the knit's pattern"),
    "design_band": ("-", "the run-stop band: friction, rib or garter (none: no band)"),
    "design_d_over_l0": ("1", "the yarn's diameter over the stitch length"),
    "design_mu": ("1", "the yarn-yarn friction coefficient"),
    "verdicts": ("-", "each tension's answer, held or gave way (with a band: its ladder crossed it; without: it "
                      "undid 5 cells or more; an edge reached: a lower bound)"),
    "holds_up_to": ("f0", "the highest f_x^ini that held with every lower one holding (NaN: the lowest gave way)"),
    "snag_peak_force_N": ("N", "the snag's largest pull-out force"),
    "snag_broke": ("-", "the yarn broke before the pin's max_pull_mm"),
    "snag_pull_at_break_mm": ("mm", "the pin's travel when the yarn broke (NaN: no break)"),
    "snag_n_lad_over_ny": ("1", "the snag's ladder: undone cells over n_y, counted from the break"),
    "snag_v_down_over_cb": ("c_b", "the snag's ladder: its downward front's velocity"),
    "fx_thr_below": ("f0", "the highest f_x^ini of the series whose cut did not ladder (NaN: every one did)"),
    "fx_thr_above": ("f0", "the lowest f_x^ini of the series whose cut laddered (NaN: none did)"),
    "fx_thr_arrest": ("f0", "the paper's f_x^thr: the mean f_x^fin of the cuts that laddered and arrested (NaN: none)"),
    "fx_thr_arrest_sd": ("f0", "its scatter (standard deviation over those cuts; NaN below two)"),
    "fx_thr_arrest_runs": ("1", "the cuts it is the mean of"),
    "monotonic": ("-", "no cut laddered below a tension whose cut held"),
    "n_lad_over_ny_lowest": ("1", "the damage of the cut at the lowest tension"),
    "n_lad_over_ny_highest": ("1", "the damage of the cut at the highest tension"),
    "v_lad_over_cb_highest": ("c_b", "the ladder's velocity at the highest tension"),
    "fx_fin_crossed_highest": ("f0", "f_x^fin of the courses the ladder crossed, at the highest tension"),
}

_CYCLE_KEYS, CYCLE_RESULTS_SI = si_columns((
        "fx_ini", "lx_over_l0", "ly_over_l0", "lx_max", "fx_thr", "delta_l_over_l0", "predicted_damage",
        "fx_thr_own", "delta_l_own_over_l0", "predicted_damage_own", "cut_n_lad_over_ny", "cut_fx_fin", "cut_fx_fin_crossed", "cut_reached_edge", "cut_n_lad_ever",
        "cut_loop_sequence", "cut_up_from_4_5_ms", "cut_hindered", "cut_n_lad_cut_row", "cut_n_lad_immediate",
        "cut_n_lad_released", "cut_n_lad_released_over_ny", "cut_n_lad_released_taut",
        "cut_n_lad_released_taut_over_ny", "hold_converged", "nan_reasons", "cut_nan_reasons",
        "wall_s",
        "job_wall_s"), CYCLE_RESULTS, "n_y")
_SNAG_KEYS, SNAG_RESULTS_SI = si_columns((
        "snag_row", "snag_column", "broke", "peak_force_N", "pull_at_break_mm", "break_tension_N", "break_row",
        "break_column", "pin_work_J", "friction_before_break_J", "ladder_released_J", "fx_ini", "n_lad_over_ny",
        "v_lad_over_cb", "v_down_over_cb", "fx_fin", "reached_edge", "wall_s", "job_wall_s"), SNAG_RESULTS, "n_y")
_RESISTANCE_KEYS, RESISTANCE_RESULTS_SI = si_columns((
        "design_pattern", "design_band", "design_d_over_l0", "design_mu", "verdicts", "holds_up_to",
        "snag_peak_force_N", "snag_broke",
        "snag_pull_at_break_mm", "snag_n_lad_over_ny", "snag_v_down_over_cb", "fx_thr_below", "fx_thr_above", "fx_thr_arrest",
        "fx_thr_arrest_sd", "fx_thr_arrest_runs", "monotonic",
        "n_lad_over_ny_lowest", "n_lad_over_ny_highest", "v_lad_over_cb_highest", "fx_fin_crossed_highest",
        "wall_s", "job_wall_s"), RESISTANCE_RESULTS, "n_y")
_LOOP_KEYS, LOOP_RESULTS_SI = si_columns((
        "tau_s", "tau_contact_s", "v_lad_over_cb", "released", "relax_converged", "contacts_before", "steps",
        "nodes", "lx_over_l0", "lx_end_over_l0", "climb_over_ly", "wall_s", "job_wall_s"), LOOP_RESULTS, "one thread's")
_STITCH_KEYS, STITCH_RESULTS_SI = si_columns((
        "fx", "fy", "converged", "max_overlap_over_d", "relax_steps", "wall_s", "job_wall_s"), STITCH_RESULTS, "one thread's")


EXPERIMENTS: dict[str, Experiment] = {
    "ladder": Experiment(CutConfig, run_ladder_job, (
        "fx_ini", "fx_fin", "fx_fin_crossed", "fx_fin_intact", "n_lad", "n_lad_over_ny", "n_lad_ever", "n_lad_rehooked", "n_lad_between",
        "v_lad_over_cb", "v_lad_first_arrival_over_cb", "natural_curvature", "lx_over_l0", "ly_over_l0",
        "force_ini_N", "force_fin_N", "force_ini_N_per_cm", "force_fin_N_per_cm", "v_lad_m_s", "l0_mm", "lx_mm",
        "ly_mm", "loop1_column", "loop1_freed_ms", "up_from_1_ms", "down_from_2_3_ms", "up_from_4_5_ms", "other_ladders",
        "loop_sequence", "paper_order", "cut_thread_held", "hindered", "n_lad_cut_row", "n_lad_immediate", "n_lad_released",
        "n_lad_released_over_ny", "n_lad_released_taut", "n_lad_released_taut_over_ny",
        "box_lx_over_l0", "fx_within_tolerance", "peak_overlap_over_d", "reached_edge", "stop_reason",
        "laddering_column", "v_fit_stitches", "v_fit_first", "v_fit_last", "energy_start_J", "energy_end_J", "dissipated_friction_J",
        "dissipated_contact_dashpot_J", "dissipated_axial_dashpot_J", "dissipated_material_J", "dissipated_air_J",
        "dissipated_global_drag_J", "dissipated_fracture_J", "owner_changes_J", "ledger_residual", "nan_reasons", "nodes", "steps", "relax_steps", "stretch_reused", "wall_s",
        "wall_stretch_s", "wall_propagate_s", "job_wall_s"), "`knitlad cut`: the laddering experiment", stretch_of, LADDER_RESULTS),
    "cycle": Experiment(CycleConfig, run_cycle_job, _CYCLE_KEYS, "`knitlad cycle`: protocol B, the damage prediction's loading", stretch_of, CYCLE_RESULTS_SI),
    "tensile": Experiment(TensileConfig, run_tensile_job, (
        "fx_start", "fy_start", "fx_top", "fy_top", "lx_top_over_l0", "ly_top_over_l0", "fx_end", "fy_end", "coupling",
        "dissipated_per_stitch", "hold_converged", "gauge_length_mm", "width_mm", "peak_force_N", "peak_force_N_per_5cm",
        "extension_at_peak_mm", "extension_at_peak_pct", "initial_modulus_N_per_5cm", "hysteresis_energy_mJ", "cycles",
        "wall_s", "job_wall_s"),
        "`knitlad tensile`: the fabric's tensile test", stretch_of, TENSILE_RESULTS),
    "snag": Experiment(SnagConfig, run_snag_job, _SNAG_KEYS,
        "`knitlad snag`: a pin pulls a loop out until the yarn breaks; the ladder follows", stretch_of, SNAG_RESULTS_SI),
    "resistance": Experiment(ResistanceConfig, run_resistance_job, _RESISTANCE_KEYS,
        "`knitlad resistance`: a snag, then the cut at a series of tensions: a knit design's ladder resistance",
        stretch_of, RESISTANCE_RESULTS_SI),
    "loop": Experiment(LoopConfig, run_loop_job, _LOOP_KEYS,
        "`knitlad loop`: the single-loop model", results=LOOP_RESULTS_SI),
    "stitch": Experiment(StitchConfig, run_stitch_job, _STITCH_KEYS,
        "`knitlad stitch`: the periodised stitch", results=STITCH_RESULTS_SI),
    "diagram": Experiment(DiagramConfig, run_diagram_job, ("lx_over_l0_at_fx0", "wall_s", "job_wall_s"),
                          "`knitlad diagram`: the width at which the periodised stitch carries f_x = 0, at l_y",
                          results=DIAGRAM_RESULTS),
}
