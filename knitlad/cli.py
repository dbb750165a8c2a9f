"""Command line: ``knitlad cut``, ``render``, ``movie``, ``sweep``, ``plot``, ``stitch``, ``diagram``, ``loop``, ``demo``, ``scales``.

The options of ``cut``, ``loop`` and ``stitch`` are the fields of their pydantic
configs (:mod:`knitlad.experiments.config`: default, unit and description declared once).
Bad input gets one line on stderr naming the option and why, and exit code 2,
before anything runs.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import math
import os
import shutil
import signal
import sys
import time
import types
import typing
from pathlib import Path

import typer
from rich.markup import escape as rich_escape

from knitlad.experiments import config as _config
from knitlad.experiments.config import cli_option, one_line

# rich's option tables cut long flag names short on a narrow terminal (`--contact-damping-r…` at 80 columns):
# there the help is click's plain text, which wraps the help under each name written out whole
RICH_HELP = shutil.get_terminal_size(fallback=(120, 24)).columns >= 110

app = typer.Typer(
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode="rich" if RICH_HELP else None,
    no_args_is_help=True,
    help="knitlad: discrete elastic rods with frictional contact, for the laddering of knitted fabric.",
)


class Terminated(KeyboardInterrupt):
    """SIGTERM during a run: handled as Ctrl-C, said as "terminated", exit 143."""


def _on_sigterm(signum, frame):
    raise Terminated()


def _print_version(value: bool) -> None:
    if value:
        from knitlad import __version__

        typer.echo(f"knitlad {__version__}")
        raise typer.Exit()


@app.callback()
def _root(version: bool = typer.Option(False, "--version", callback=_print_version, is_eager=True,
                                       help="Print the version and exit.")) -> None:
    """knitlad: discrete elastic rods with frictional contact, for the laddering of knitted fabric."""


def fail(message: str) -> None:
    """One-line error, exit code 2, no traceback."""
    typer.echo(f"knitlad: error: {message}", err=True)
    raise typer.Exit(code=2)


@app.command()
def demo(
    nodes: int = typer.Option(41, help="Nodes along the cantilever (>= 6)."),
) -> None:
    """Rod demo: a clamped Nylon cantilever against beam theory (a few seconds)."""
    if nodes < 6:
        fail(f"--nodes must be >= 6, got {nodes}")
    from knitlad.experiments.demo import cantilever_demo

    t = time.perf_counter()
    typer.echo(f"Nylon cantilever, 20 mm, {nodes} nodes (first run compiles the kernels, ~30 s)")
    rows = cantilever_demo(n_nodes=nodes)
    typer.echo(f"{'check':45s} {'knitlad':>12s} {'theory':>12s} {'rel. error':>10s}")
    for r in rows:
        err = abs(r["knitlad"] / r["theory"] - 1) if r["theory"] == r["theory"] else float("nan")
        err_s = f"{err:10.2e}" if err == err else " " * 10
        theory_s = f"{r['theory']:12.5g}" if r["theory"] == r["theory"] else " " * 12
        typer.echo(f"{r['check']:45s} {r['knitlad']:12.5g} {theory_s} {err_s}  [{r['unit']}]")
    typer.echo(f"wall time {time.perf_counter() - t:.1f} s")


@app.command()
def scales(yarn: typing.Optional[str] = typer.Option(None, "--yarn", help=(
               "a yarn file (configs/yarns/; knitlad.experiments.yarn); default: the paper's Nylon")),
           stitch_length_mm: typing.Optional[float] = typer.Option(None, "--stitch-length-mm", help=(
               "the knit's stitch length l0 [mm]; default: 9.74 mm for the paper's Nylon"))) -> None:
    """Print the material and the paper's scales (f0, c_b, ...) in SI units: the paper's Nylon, or your yarn at your
    stitch length."""
    from knitlad.engine.units import Scales
    from knitlad.experiments.config import StitchConfig

    options = {k: v for k, v in {"yarn": yarn, "stitch_length_mm": stitch_length_mm}.items() if v is not None}
    cfg = validated(StitchConfig, options)
    for key, value in Scales(cfg.material()).as_attributes().items():
        typer.echo(f"{key:20s} {value:.6g}")
    typer.echo(f"{'d_over_l0':20s} {cfg.d_over_l0:.6g}")


@app.command()
def columns(scene: str = typer.Argument("ladder", help="the experiment: ladder, cycle, tensile, snag, resistance, "
                                                       "loop, stitch or diagram")) -> None:
    """Print what each column of a sweep's summary.csv means, with its unit (a sweep writes the same table
    beside it as summary_columns.csv)."""
    from knitlad.studies.columns import column_dictionary
    from knitlad.studies.registry import EXPERIMENTS

    if scene not in EXPERIMENTS:
        fail(f"scene: one of {', '.join(EXPERIMENTS)}, got {scene!r}")
    rows = column_dictionary(scene)
    width = max(len(name) for name, _, _ in rows)
    for name, unit, meaning in rows:
        typer.echo(f"{name:{width}s}  [{unit}]  {meaning}")


class _StageProgress:
    """A progress line per stage of a run on stderr (:class:`~knitlad.io.progress.ProgressLine`): the stretch's
    share of its target, then the ladder's reach or its time limit, whichever is further."""

    def __init__(self) -> None:
        self.stage, self.line = None, None

    def __call__(self, stage: str, fraction: float) -> None:
        from knitlad.io.progress import ProgressLine

        if stage != self.stage:
            self.close(finished=True)  # the next stage starts when the last one is done
            self.stage, self.line = stage, ProgressLine(f"{stage:10s}", 1.0, "%")
        self.line.update(fraction)

    def close(self, finished: bool = False) -> None:
        """End the line; ``finished``: the stage ended as it should (a ladder stopping early is done)."""
        if self.line is not None:
            if finished:
                self.line.update(1.0)
            self.line.close()
        self.stage, self.line = None, None


class _CountProgress:
    """A progress line over a count known once the work starts (frames of a movie, images of a render)."""

    def __init__(self, label: str, unit: str) -> None:
        self.label, self.unit, self.line = label, unit, None

    def __call__(self, done: int, total: int) -> None:
        from knitlad.io.progress import ProgressLine

        if self.line is None:
            self.line = ProgressLine(self.label, total, self.unit)
        self.line.update(done)

    def close(self) -> None:
        if self.line is not None:
            self.line.close()
            self.line = None


def _option_type(annotation):
    """The command-line type of a config field's annotation (a Literal is read as text, pydantic checks it)."""
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    if typing.get_origin(annotation) is typing.Literal:
        return str
    if args and typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return _option_type(args[0])
    from pydantic import BaseModel

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return str  # a yarn: its file's path
    return annotation


# the help's option groups: what the experiment is, how long and how it is recorded, and the rest (the model
# and its numerics), so that a first reader finds the few settings of the physics first
EXPERIMENT_PANEL, OUTPUT_PANEL, MODEL_PANEL = "The experiment", "Run length and output", "Model and numerics"
EXPERIMENT_FIELDS = ("preset", "fx", "lx", "ly", "mu", "natural_curvature", "memory_peak_ratio", "geometry", "columns")
OUTPUT_FIELDS = ("max_time_ms", "arrest_ms", "observe_every_us", "frame_every_us")


def option_panel(field: str) -> str:
    """The help group of a config field."""
    if field in EXPERIMENT_FIELDS:
        return EXPERIMENT_PANEL
    return OUTPUT_PANEL if field in OUTPUT_FIELDS else MODEL_PANEL


def config_options(model, exclude: tuple[str, ...] = ()):
    """Give a command one option per field of the pydantic config ``model`` (its default, unit and
    description are the field's: declared once, in :mod:`knitlad.experiments.config`).

    The command receives ``options``: the fields given on the command line (None for those
    not given, so the config's defaults apply). A bad value is one line naming the option, exit 2.
    """

    def decorate(func):
        own = [p for p in inspect.signature(func).parameters.values() if p.name != "options"]
        derived = []
        # a setting of the presets' tables defaults to the chosen preset's value, not to the field's
        by_preset = set(model.preset_fields()) if hasattr(model, "preset_fields") else set()
        for name, f in model.model_fields.items():
            if name in exclude:
                continue
            flag = cli_option(model, name)
            typ = _option_type(f.annotation)
            shown = f.default is not None and not f.is_required()  # a required field has no default to show
            default = f" [default: {f.default}]" if shown else ""
            if shown and name in by_preset:  # the default, and the presets that set another value
                others = {p: t[name] for p, t in model.PRESETS.items() if name in t and t[name] != f.default}
                default = f" [default: {f.default}" + "".join(f"; {p}: {v}" for p, v in others.items()) + "]"
            # units and defaults are in [brackets], which rich reads as markup unless escaped
            text = f.description + default + (" [required]" if f.is_required() else "")
            help_text = rich_escape(text) if RICH_HELP else text
            decls = [f"{flag}/--no-{flag[2:]}"] if typ is bool else [flag]
            derived.append(inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, annotation=typing.Optional[typ],
                                             default=typer.Option(None, *decls, help=help_text, show_default=False,
                                                                 rich_help_panel=option_panel(name))))

        @functools.wraps(func)
        def command(**kwargs):
            # a field the command takes its own way (diagram's repeated --ly) is its parameter, not an option
            options = {name: kwargs.pop(name) for name in list(kwargs) if name in model.model_fields
                       and name not in exclude}
            return func(options={k: v for k, v in options.items() if v is not None}, **kwargs)

        params = own + derived
        command.__signature__ = inspect.Signature(params)
        command.__annotations__ = {p.name: p.annotation for p in params}
        del command.__wrapped__  # typer must read the new signature, not the function's own
        return command

    return decorate


def validated(model, options: dict, names: dict | None = None):
    """The config ``model(**options)``; a bad value is one line naming the option, exit 2."""
    from pydantic import ValidationError

    try:
        return model(**options)
    except ValidationError as e:
        def option(field: str) -> str:
            return (names or {}).get(field) or (cli_option(model, field) if field in model.model_fields else field)

        text = one_line(e, where=option)
        if text.startswith("config: "):  # a rule across fields names the field it is about first, if any
            named, _, rest = text.removeprefix("config: ").partition(": ")
            text = f"{option(named)}: {rest}" if named in model.model_fields and rest else text.removeprefix("config: ")
        fail(text)


STITCHES_HELP = "Fabric size: N (N x N) or NXxNY; default: the experiment's config's n_x x n_y (cut 42, others 16)."


def _knit_run(model, options: dict, stitches: str | None, default_fx: float | None, out: str | None, name: str):
    """A knit experiment's validated config and output folder, every check made before any compute (a run
    of hours must not end on a full memory or an unwritable folder): --stitches, the config (force control
    to ``default_fx``, if given, when neither --fx nor --lx is), the memory, the folder (default
    runs/<name>-<time>)."""
    from knitlad.io.folders import FolderError, writable_folder
    from knitlad.experiments.laddering import KnitTooLarge, require_memory

    if stitches is None:  # the config's size
        stitches = f"{model.model_fields['n_x'].default}x{model.model_fields['n_y'].default}"
    try:
        n_x, n_y = _config.parse_stitches(stitches)
    except ValueError as e:
        fail(f"--stitches: {e}")
    if default_fx is not None and all(options.get(k) is None for k in ("fx", "lx", "wales_per_cm")):
        options["fx"] = default_fx
    cfg = validated(model, {**options, "n_x": n_x, "n_y": n_y}, {"n_x": "--stitches", "n_y": "--stitches"})
    out_dir = Path(out) if out else Path("runs") / time.strftime(f"{name}-%Y%m%d-%H%M%S")
    try:
        require_memory(cfg.memory_estimate_bytes(), f"--stitches {n_x}x{n_y} at --resolution {cfg.resolution}")
        writable_folder(out_dir)
    except (KnitTooLarge, FolderError) as e:
        fail(str(e) if isinstance(e, KnitTooLarge) else f"--out {e}")
    return cfg, out_dir


def _earlier_run(name: str, *files: str):
    """The refusal (for :func:`_prologue`'s ``holds``) of a folder holding any of ``files`` of an earlier ``name``
    run."""
    def holds(folder: Path, _cfg) -> str | None:
        earlier = [p for p in files if (folder / p).exists()]
        return f"holds an earlier {name} run ({', '.join(earlier)}); choose another folder" if earlier else None

    return holds


@contextlib.contextmanager
def _prologue(name: str, model, options: dict, stitches: str | None, default_fx: float | None, out: str | None,
              holds=None):
    """Every experiment command's start, said once: the config and --out checked before any compute
    (:func:`_knit_run`, or the config alone for a model without a knit), the refusal of a folder holding an earlier
    run (``holds(out_dir, cfg)`` returns the refusal's text or None; by default a ``<name>.h5`` there is refused),
    the folder's lock for the whole command (a second run into it is refused, whatever command it is), the compile
    notice and the stage progress. Yields (config, folder, progress). A folder the command made and left empty is
    removed when it stops early."""
    from knitlad.io.folders import FolderError, FolderLock, writable_folder

    made = not (Path(out).exists() if out else False)
    if "n_x" in model.model_fields:
        cfg, out_dir = _knit_run(model, options, stitches, default_fx, out, name)
    else:
        cfg = validated(model, options)
        out_dir = Path(out) if out else Path("runs") / time.strftime(f"{name}-%Y%m%d-%H%M%S")
        try:
            writable_folder(out_dir)
        except FolderError as e:
            fail(f"--out {e}")
    refusal = (holds or _earlier_run(name, f"{name}.h5"))(out_dir, cfg)
    if refusal:
        fail(f"--out {out_dir}: {refusal}")
    lock = FolderLock(out_dir)  # a second run into this folder would mix its files with this one's
    try:
        lock.acquire()
    except FolderError as e:
        fail(f"--out {e}")
    try:
        _say_if_compiling()
        yield cfg, out_dir, _StageProgress()
    except typer.Exit:
        lock.release()
        if made and out_dir.is_dir() and not any(out_dir.iterdir()):
            out_dir.rmdir()
        raise
    finally:
        lock.release()


@app.command()
@config_options(_config.CutConfig, exclude=("n_x", "n_y"))
def cut(
    stitches: str = typer.Option(None, "--stitches", help=STITCHES_HELP, rich_help_panel=EXPERIMENT_PANEL),
    out: str = typer.Option(None, "--out", help="Output folder (HDF5 + PNG); default runs/cut-<time>.", rich_help_panel=OUTPUT_PANEL),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as one JSON object.", rich_help_panel=OUTPUT_PANEL),
    overwrite: bool = typer.Option(False, "--overwrite", rich_help_panel=OUTPUT_PANEL, help="Replace the earlier run in --out (its files, renders "
                                   "and movies are removed once this run is written)."),
    options: dict = None,
) -> None:
    """The laddering experiment: stretch at mu = 0, relax, switch friction on, cut a loop, follow the ladder.

    Without --fx or --lx, force control to f_x^ini = 13.6 (the paper's Fig. 3c,d).
    """

    def holds(folder: Path, _cfg) -> str | None:
        earlier = earlier_run_outputs(folder)
        return None if not earlier or overwrite else (
            f"holds an earlier run ({', '.join(p.name for p in earlier[:4])}{', ...' if len(earlier) > 4 else ''}); "
            "--overwrite replaces it")

    with _prologue("cut", _config.CutConfig, options, stitches, 13.6, out, holds) as (cfg, out_dir, progress):
        earlier = earlier_run_outputs(out_dir)
        finished = _experiment_or_exit(lambda: _experiment("ladder", cfg, progress=progress), progress, cfg=cfg)
        progress.close(finished=True)
        result, summary = finished.result, finished.summary
        try:
            # written beside the earlier run first, then put in its place: on a full disk the earlier run stays whole
            h5, png = _replace_run_outputs(out_dir, finished, earlier)
        except OSError as e:  # a full disk or a file-size limit: keep the summary, say it in one line
            kept = _keep_summary(out_dir, summary) if not earlier else None
            typer.echo(_json(summary))
            typer.echo(f"knitlad: run finished but its files could not be written ({e}); "
                       + ("the earlier run in --out is left as it was; " if earlier else "")
                       + f"the summary is {'in ' + str(kept) if kept else 'printed above'}", err=True)
            raise typer.Exit(1)
        except KeyboardInterrupt as e:  # Ctrl-C or SIGTERM while writing: nothing half-written is left
            how, code = ("terminated", 143) if isinstance(e, Terminated) else ("interrupted", 130)
            typer.echo(f"knitlad: {how} while writing the run; " + ("the earlier run in --out is left as it was"
                                                                  if earlier else "nothing written"), err=True)
            raise typer.Exit(code)
    _report_cut(cfg, result, summary, json_out, h5, png, out_dir)


def _damage_line(parts: dict) -> str:
    taut = "" if parts.get("n_lad_released_taut", -1) < 0 else f", {parts['n_lad_released_taut']} of them taut"
    return (f"{parts['n_lad_released']} released by the ladder into loaded courses (Eq. 1's count: "
            f"{parts['n_lad_released_over_ny']:.3f} n_y{taut}), {parts['n_lad_cut_row']} of the cut row, "
            f"{parts['n_lad_immediate']} undone with the cut (0.1 ms)")


def _report_cut(cfg, result, summary: dict, json_out: bool, h5: Path, png: Path, out_dir: Path) -> None:
    """What `cut` prints once its run is written: the summary as JSON, or as lines with their caveats."""
    n_x, n_y = cfg.n_x, cfg.n_y
    if not result.fx_within_tolerance:
        typer.echo(
            f"knitlad: warning: f_x^ini = {result.fx_ini:.3f} is not within {100 * cfg.fx_tolerance:g} % of the "
            f"target {cfg.fx} (the relaxed tension could not be matched); the run went on from there",
            err=True,
        )
    if json_out:
        typer.echo(_json(summary))
        return
    speed = f"(v_lad = {summary['v_lad_m_s']:.3g} m/s)  " if math.isfinite(result.v_lad_over_cb) else ""
    typer.echo(
        f"{n_x} x {n_y} {cfg.pattern}, mu = {cfg.mu}, {cfg.resolution} nodes/stitch ({result.nodes} nodes)\n"
        f"  f_x^ini     = {result.fx_ini:.3f}  (F_x = {summary['force_ini_N']:.4g} N, "
        f"{summary['force_ini_N_per_cm']:.4g} N/cm of width)\n"
        f"  f_x^fin     = {result.fx_fin:.3f}{_fin_caveat(result)}\n    per course: {result.fx_fin_crossed:.3f} crossed by the ladder, {result.fx_fin_intact:.3f} not\n"
        f"  n_lad/n_y   = {result.n_lad_over_ny:.3f}  ({result.n_lad} cells undone at the stop; {_ever_line(result)})\n"
        f"    of them {_damage_line(result.damage_record())}\n"
        f"  loops       = {_loop_line(result)}\n"
        f"  v_lad/c_b   = {result.v_lad_over_cb:.3f}  {speed}{_velocity_caveat(result)}\n"
        f"  l_x/l0, l_y/l0 = {result.lx_over_l0:.3f}, {result.ly_over_l0:.3f}  (l_x, l_y = {summary['lx_mm']:.3g}, "
        f"{summary['ly_mm']:.3g} mm at l0 = {summary['l0_mm']:.4g} mm)\n"
        f"  stop: {result.stop_reason}\n"
        f"  wall time   = {summary['wall_s']:.1f} s (stretch {result.wall_s.get('stretch', 0):.1f} s, propagate {result.wall_s.get('propagate', 0):.1f} s)\n"
        f"  wrote {h5}, {h5.with_suffix('.xdmf').name} (ParaView) and {png.name}; pictures: knitlad render {out_dir}"
    )


@app.command()
@config_options(_config.CycleConfig, exclude=("n_x", "n_y"))
def cycle(
    stitches: str = typer.Option(None, "--stitches", help=STITCHES_HELP, rich_help_panel=EXPERIMENT_PANEL),
    out: str = typer.Option(None, "--out", help="Output folder; default runs/cycle-<time>.", rich_help_panel=OUTPUT_PANEL),
    resume: bool = typer.Option(False, "--resume", rich_help_panel=OUTPUT_PANEL, help="Continue the run that was "
                                "stopped in --out (Ctrl-C, a killed job) from its last finished leg, with the same "
                                "settings: the curve is the same to the bit."),
    options: dict = None,
) -> None:
    """Protocol B (paper Fig. 4a): cycle the knit with friction on between Delta x_min and --lx-max, cut a
    copy at Delta x_max of the last cycle, read delta l on the uncut twin's unloading (with --fx-thr).

    Without --fx or --lx, Delta x_min holds the knit at f_x = 0.68 (the experiments'). Writes cycle.csv
    (the force-displacement readings), cycle.png (Fig. 4a), cycle.h5 (readings, and the ladder of the cut).
    """
    restart: list = []

    def holds(folder: Path, config) -> None:  # an earlier run is refused, or resumed with --resume (one line if not)
        restart.append(_cycle_restart(folder, config, resume))

    with _prologue("cycle", _config.CycleConfig, options, stitches, 0.68, out, holds) as (cfg, out_dir, progress):
        _cycle(cfg, out_dir, progress, restart[0])


def _cycle(cfg, out_dir: Path, progress, restart) -> None:
    """`knitlad cycle` once its folder is checked and locked: protocol B, its files, its lines."""
    from knitlad.io.hdf5 import write_arrays
    from knitlad.studies.registry import write_cycle_table

    n_x, n_y = cfg.n_x, cfg.n_y
    unwritten: list[str] = []

    def keep_readings(readings) -> None:  # after each leg: a run stopped early keeps its curve, a full disk says so
        try:
            write_cycle_table(out_dir / "cycle.csv", readings)
        except OSError as e:
            unwritten.append(str(e))

    def keep_checkpoint(arrays) -> None:  # after each leg: where --resume goes on from
        try:
            write_arrays(out_dir / CYCLE_CHECKPOINT, arrays, {"config_json": cfg.model_dump_json()})
        except OSError as e:
            unwritten.append(str(e))

    finished = _experiment_or_exit(
        lambda: _experiment("cycle", cfg, out_dir, progress, after_leg=keep_readings, keep=keep_checkpoint,
                            resume=restart),
        progress, kept=f"the readings so far are in {out_dir / 'cycle.csv'} (if a leg had ended); "
                       f"knitlad cycle ... --out {out_dir} --resume goes on from the last leg", cfg=cfg)
    progress.close(finished=True)
    result, ladder = finished.result
    l0 = cfg.settings().material.stitch_length
    h5, csv, png = _files_or_exit(lambda: _write_experiment(finished, out_dir / "cycle.h5"), finished.summary)
    (out_dir / CYCLE_CHECKPOINT).unlink(missing_ok=True)  # finished: nothing to resume, nor to re-stretch
    shutil.rmtree(out_dir / "stretched", ignore_errors=True)
    typer.echo(
        f"{n_x} x {n_y} {cfg.pattern}, protocol B: {cfg.cycles} cycles at mu = {cfg.mu}, bars at {cfg.bar_speed:g} m/s, "
        f"{cfg.resolution} nodes/stitch\n"
        f"  Delta x_max - Delta x_min = {(cfg.lx_max - result.lx_min) * n_x * l0 * 1e3:.3f} mm "
        f"(box l_x/l0 {result.lx_min:.4f} -> {cfg.lx_max:.4f})\n"
        f"  at Delta x_max: f_x^ini = {result.fx_ini:.3f}, l_x/l0 = {result.lx_over_l0:.4f}, l_y/l0 = {result.ly_over_l0:.4f}"
        f"{'' if result.hold_converged else ' (the hold did not settle within --hold-ms)'}")
    if cfg.fx_thr is not None and "delta_l_over_l0" in result.nan_reasons():
        typer.echo(f"  delta l: not read ({result.nan_reasons()['delta_l_over_l0']})")
    elif cfg.fx_thr is not None:
        typer.echo(f"  delta l = {result.delta_l_over_l0 * l0 * 1e3:.3f} mm to f_x^thr = {cfg.fx_thr:g}: "
                   f"predicted n_lad/n_y = delta l/(l0 - l_x) = {result.predicted_damage:.3f}")
    if not math.isnan(result.delta_l_own_over_l0):
        typer.echo(f"  read as the paper reads it, to its own f_x^fin = {result.fx_thr_own:.3f}: delta l = "
                   f"{result.delta_l_own_over_l0 * l0 * 1e3:.3f} mm, predicted n_lad/n_y = {result.predicted_damage_own:.3f}")
    if ladder is not None:
        typer.echo(f"  cut: n_lad/n_y = {ladder.n_lad_over_ny:.3f} ({ladder.n_lad} cells), f_x^fin = {ladder.fx_fin:.3f} "
                   f"(crossed courses {ladder.fx_fin_crossed:.3f}), stop: {ladder.stop_reason}\n"
                   f"  {_loop_line(ladder)}")
    typer.echo(f"  wall time {result.wall_s:.1f} s; wrote {h5}, {csv.name}, {png.name}")


CYCLE_CHECKPOINT = "cycle.checkpoint.h5"  # where an unfinished cycle run stands (knitlad.experiments.cycling)


def _cycle_restart(out_dir: Path, cfg, resume: bool) -> dict | None:
    """The checkpoint ``--resume`` goes on from (None for a new run), or a one-line refusal: a folder holding a
    finished or an interrupted run without --resume, --resume where nothing was stopped, or with other settings."""
    import json

    from knitlad.io.hdf5 import read_arrays

    checkpoint = out_dir / CYCLE_CHECKPOINT
    earlier = [name for name in ("cycle.h5", "cycle.csv", "cycle.png") if (out_dir / name).exists()]
    if not resume:
        if earlier or checkpoint.exists():  # cycle.csv alone is an interrupted run's readings: kept too
            hint = "; --resume continues it" if checkpoint.exists() and "cycle.h5" not in earlier else ""
            fail(f"--out {out_dir}: holds an earlier cycle run ({', '.join(earlier or [CYCLE_CHECKPOINT])}); "
                 f"choose another folder{hint}")
        return None
    if "cycle.h5" in earlier:
        fail(f"--resume: the run in {out_dir} has finished (cycle.h5); nothing to continue")
    if not checkpoint.exists():
        fail(f"--resume: no stopped run in {out_dir} (no {CYCLE_CHECKPOINT}: none was made, or no leg had ended)")
    from knitlad.experiments.cycling import check_cycle_checkpoint

    try:
        arrays, attrs = read_arrays(checkpoint)
        theirs = json.loads(attrs.get("config_json", "{}"))
        check_cycle_checkpoint(arrays, cfg.cycles)
    except OSError as e:
        fail(f"--resume: {checkpoint} cannot be read ({e}); start the run again in another folder")
    except (ValueError, TypeError) as e:  # JSONDecodeError is a ValueError
        fail(f"--resume: {checkpoint} is damaged ({str(e).splitlines()[0]}); start the run again in another folder")
    if attrs.get("config_json") != cfg.model_dump_json():
        changed = sorted(k for k, v in cfg.model_dump(mode="json").items() if theirs.get(k) != v)
        fail(f"--resume: the stopped run had other settings ({', '.join(changed) or 'unreadable'}); give the same "
             "ones, or use another folder")
    return arrays


@app.command()
@config_options(_config.TensileConfig, exclude=("n_x", "n_y", *_config.TensileConfig.UNUSED))
def tensile(
    stitches: str = typer.Option(None, "--stitches", help=STITCHES_HELP, rich_help_panel=EXPERIMENT_PANEL),
    out: str = typer.Option(None, "--out", help="Output folder; default runs/tensile-<time>.", rich_help_panel=OUTPUT_PANEL),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as one JSON object.", rich_help_panel=OUTPUT_PANEL),
    options: dict = None,
) -> None:
    """The fabric's tensile test: the knit stretched at mu = 0, then with friction on pulled to --lx-max
    and/or --ly-max, held, and brought back; f_x and f_y read after every ramp.

    Without --fx or --lx, the knit starts at f_x = 0.68 (the experiments' holding tension). Writes
    tensile.csv (the readings in the paper's units), tensile_tester.csv (force in N and N per 5 cm against the
    extension in mm and %), tensile_results.csv (per cycle: peak force, initial modulus, hysteresis in mJ),
    tensile.png, tensile_tester.png and tensile.h5.
    """
    holds = _earlier_run("tensile", "tensile.h5", "tensile.csv", "tensile_tester.csv", "tensile_results.csv")
    with _prologue("tensile", _config.TensileConfig, options, stitches, 0.68, out, holds) as (cfg, out_dir, progress):
        finished = _experiment_or_exit(lambda: _experiment("tensile", cfg, progress=progress), progress, cfg=cfg)
        progress.close(finished=True)
        result, summary = finished.result, finished.summary
        _files_or_exit(lambda: _write_experiment(finished, out_dir / "tensile.h5"), summary)
    if json_out:
        typer.echo(_json(summary))
        return
    typer.echo(
        f"{cfg.n_x} x {cfg.n_y} {cfg.pattern}, tensile test at mu = {cfg.mu}, bars at {cfg.bar_speed:g} m/s, "
        f"{cfg.resolution} nodes/stitch\n"
        f"  start: f_x = {summary['fx_start']:.3f}, f_y = {summary['fy_start']:.3f}\n"
        f"  top:   f_x = {summary['fx_top']:.3f}, f_y = {summary['fy_top']:.3f} at l_x/l0 = "
        f"{summary['lx_top_over_l0']:.4f}, l_y/l0 = {summary['ly_top_over_l0']:.4f}"
        f"{'' if summary['hold_converged'] else ' (the hold did not settle within --hold-ms)'}\n"
        f"  end:   f_x = {summary['fx_end']:.3f}, f_y = {summary['fy_end']:.3f}; friction took "
        f"{summary['dissipated_per_stitch']:.4f} f0 l0 per stitch; coupling {summary['coupling']:.3f}\n"
        f"  as a tester reads it (gauge {summary['gauge_length_mm']:.1f} mm, width {summary['width_mm']:.1f} mm): peak "
        f"{summary['peak_force_N']:.3g} N = {summary['peak_force_N_per_5cm']:.3g} N/5cm at "
        f"{summary['extension_at_peak_mm']:.2f} mm ({summary['extension_at_peak_pct']:.1f} %), initial modulus "
        f"{summary['initial_modulus_N_per_5cm']:.3g} N/5cm, hysteresis {summary['hysteresis_energy_mJ']:.3g} mJ"
        f"{'' if summary['cycles'] == 1 else ' (first cycle; every cycle: tensile_results.csv)'}\n"
        f"  wall time {result.wall_s:.1f} s; wrote {out_dir}/tensile.csv, tensile_tester.csv, tensile_results.csv, "
        f"tensile.h5, tensile.png, tensile_tester.png")


@app.command()
@config_options(_config.SnagConfig, exclude=("n_x", "n_y"))
def snag(
    stitches: str = typer.Option(None, "--stitches", help=STITCHES_HELP, rich_help_panel=EXPERIMENT_PANEL),
    out: str = typer.Option(None, "--out", help="Output folder; default runs/snag-<time>.", rich_help_panel=OUTPUT_PANEL),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as one JSON object.", rich_help_panel=OUTPUT_PANEL),
    options: dict = None,
) -> None:
    """A snag: a pin behind one loop's head pulls it out of the stretched knit until the yarn breaks, then the
    ladder runs from the break.

    Without --fx or --lx, force control to f_x^ini = 4. Writes snag.csv and snag.png (the pull-out curve) and,
    after a break, the ladder as `cut` does (ladder.h5, ladder.xdmf, spatio_temporal.png).
    """
    holds = _earlier_run("snag", "snag.h5", "snag.csv")
    with _prologue("snag", _config.SnagConfig, options, stitches, 4.0, out, holds) as (cfg, out_dir, progress):
        finished = _experiment_or_exit(lambda: _experiment("snag", cfg, progress=progress), progress, cfg=cfg)
        progress.close(finished=True)
        result, summary = finished.result, finished.summary
        _files_or_exit(lambda: _write_experiment(finished, out_dir / "snag.h5"), summary)
    if json_out:
        typer.echo(_json(summary))
        return
    head = (f"{cfg.n_x} x {cfg.n_y} {cfg.pattern} at f_x^ini = {summary['fx_ini']:.3f}" if result.ladder else
            f"{cfg.n_x} x {cfg.n_y} {cfg.pattern}") + f", pin at {cfg.snag_speed:g} m/s behind the loop of course " \
        f"{summary['snag_row']}, column {summary['snag_column']}, mu = {cfg.mu}, {cfg.resolution} nodes/stitch"
    if not result.broke:
        typer.echo(f"{head}\n  no break within {cfg.max_pull_mm:g} mm: peak pull-out force "
                   f"{summary['peak_force_N']:.4f} N; the pin put in {summary['pin_work_J']:.3e} J\n"
                   f"  wall time {result.wall_s:.1f} s; wrote {out_dir}/snag.h5, snag.csv, snag.png")
        return
    typer.echo(
        f"{head}\n"
        f"  the yarn broke at {summary['break_tension_N']:.3f} N after {summary['pull_at_break_mm']:.3f} mm "
        f"(course {summary['break_row']}, column {summary['break_column']}); peak pull-out force "
        f"{summary['peak_force_N']:.4f} N\n"
        f"  energy: the pin put in {summary['pin_work_J']:.3e} J (friction took {summary['friction_before_break_J']:.3e}"
        f" J of it); the ladder released {summary['ladder_released_J']:.3e} J\n"
        f"  ladder: n_lad/n_y = {summary['n_lad_over_ny']:.3f}, v_lad/c_b = {_speed_words(summary, 'v_lad_over_cb')} up, "
        f"{_speed_words(summary, 'v_down_over_cb')} down, "
        f"f_x^fin = {summary['fx_fin']:.3f}{' (reached an edge course)' if summary['reached_edge'] else ''}\n"
        f"  wall time {result.wall_s:.1f} s; wrote {out_dir}/snag.h5 (the curve and the ladder: knitlad render "
        f"{out_dir}/snag.h5), snag.xdmf, snag.csv, snag.png, spatio_temporal.png")


@app.command()
@config_options(_config.ResistanceConfig, exclude=("n_x", "n_y"))
def resistance(
    stitches: str = typer.Option(None, "--stitches", help=STITCHES_HELP, rich_help_panel=EXPERIMENT_PANEL),
    out: str = typer.Option(None, "--out", help="Output folder; default runs/resistance-<time>.", rich_help_panel=OUTPUT_PANEL),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as one JSON object.", rich_help_panel=OUTPUT_PANEL),
    options: dict = None,
) -> None:
    """A ladder-resistance test of a knit design: a snag at --fx (default 4), then the paper's cut at each of
    --tensions (default 2, 4 and 8); the threshold is bracketed by the series.

    The design is the knit's --pattern, its band (--band, --band-row), --d-over-l0 and --mu. Writes
    resistance.h5 (the series, the snag's curve, the pictured ladder's run file), resistance.csv (the series)
    and resistance_report.png (one page: the design, the snag, damage and velocity against tension, the
    threshold, the ladder where it stopped).
    """
    with _prologue("resistance", _config.ResistanceConfig, options, stitches, 4.0, out) as (cfg, out_dir, progress):
        finished = _experiment_or_exit(lambda: _experiment("resistance", cfg, progress=progress), progress, cfg=cfg)
        progress.close(finished=True)
        result, summary = finished.result, finished.summary
        _files_or_exit(lambda: _write_experiment(finished, out_dir / "resistance.h5"), summary)
    if json_out:
        typer.echo(_json(summary))
        return
    lo, hi = result.threshold_bracket()
    lines = [f"{cfg.n_x} x {cfg.n_y} {cfg.pattern}"
             + ("" if cfg.band_row is None else f" with a {cfg.band} band from course {cfg.band_row}")
             + f", d/l0 = {cfg.d_over_l0:.4g}, mu = {cfg.mu}, {cfg.resolution} nodes/stitch",
             f"  snag at f_x^ini {summary['snag_fx_ini']:.2f}: peak pull-out force {summary['snag_peak_force_N']:.3f} N, "
             + (f"broke after {summary['snag_pull_at_break_mm']:.2f} mm, n_lad/n_y {summary['snag_n_lad_over_ny']:.2f}"
                if summary["snag_broke"] else "no break")]
    for row, c, verdict in zip(result.table(), result.cuts, result.verdicts()):
        released = c.damage_record()["n_lad_released"]
        speed = f"v_lad/c_b {row[4]:.3f}" if math.isfinite(row[4]) else "no front long enough to fit a speed"
        lines.append(f"  cut at f_x^ini {row[1]:.2f}: {verdict}: {c.n_lad} cells undone ({row[2]:.2f} n_y; "
                     f"{released} released into loaded courses), {speed}, f_x^fin crossed {row[5]:.2f}")
    lines.append(f"  rule: {result.rule()}")
    held = summary["holds_up_to"]
    lines.append("  the design " + (f"holds up to f_x^ini {held:.2f}" if math.isfinite(held) else
                                    "gives way at the lowest tension tried")
                 + ("" if summary["monotonic"] else " (the series is not monotonic)"))
    if cfg.band_row is None:
        lines.append("  threshold (onset): " + _bracket_words(lo, hi))
    thr = result.arrest_threshold()
    if thr["runs"]:
        lines.append(f"  f_x^thr as the paper reads it (mean f_x^fin after the arrest): {thr['fx_thr']:.2f}"
                     + (f" +- {thr['fx_thr_sd']:.2f}" if thr["runs"] > 1 else "") + f" over {thr['runs']} cut"
                     + "s" * (thr["runs"] != 1))
    lines.append(f"  wall time {result.wall_s:.1f} s; wrote {out_dir}/resistance.h5, resistance.csv, "
                 "resistance_report.png")
    typer.echo("\n".join(lines))


def _speed_words(summary: dict, key: str) -> str:
    """A velocity of the summary, or why there is none (a front too short to fit), never "nan"."""
    value = summary.get(key, math.nan)
    return f"{value:.3f}" if not math.isnan(value) else "none (its front ran too few stitches to fit)"


def _bracket_words(lo: float, hi: float) -> str:
    """The onset bracket in words: between two tensions, or one side open, never "nan"."""
    if math.isnan(lo) and math.isnan(hi):
        return "not bracketed (no cut ran)"
    if math.isnan(lo):
        return f"below {hi:.2f} (every cut laddered)"
    if math.isnan(hi):
        return f"above {lo:.2f} (no cut laddered)"
    return f"between {lo:.2f} and {hi:.2f}"


def _files_or_exit(write, summary: dict):
    """``write()``'s result; on an OSError (a full disk) the summary on stdout, the failure in one line, exit 1."""
    try:
        return write()
    except OSError as e:
        typer.echo(_json(summary))
        typer.echo(f"knitlad: run finished but its files could not be written ({e}); the summary is printed above",
                   err=True)
        raise typer.Exit(1)


@app.command()
@config_options(_config.LoopConfig)
def loop(
    json_out: bool = typer.Option(False, "--json", help="Print the summary as one JSON object."),
    options: dict = None,
) -> None:
    """Single-loop model of the paper's Fig 5b: a loop under tension f_x lets go of the row above once the row below is removed.

    None of its geometries reproduces the paper's Fig 5c (docs/single_loop.md); the fabric's own v_lad against f_x and mu is in docs/paper_claims.md (knitlad sweep docs/reference/velocity24_mu.yaml).
    """

    cfg = validated(_config.LoopConfig, options)
    try:
        finished = _experiment("loop", cfg)
    except RuntimeError as e:
        typer.echo(f"knitlad: run failed: {e}", err=True)
        raise typer.Exit(1)
    result, summary = finished.result, finished.summary
    if json_out:
        typer.echo(_json(summary))
        return
    if result.released:
        typer.echo(f"single loop ({cfg.geometry}), f_x = {cfg.fx}, mu = {cfg.mu}: released after tau = {result.tau_s * 1e6:.1f} us, "
                   f"v_lad/c_b = {result.v_lad_over_cb:.3f} (wall {summary['wall_s']:.2f} s)")
    else:
        typer.echo(f"single loop ({cfg.geometry}), f_x = {cfg.fx}, mu = {cfg.mu}: still hooked after {cfg.max_time_ms} ms "
                   f"(v_lad = 0; wall {summary['wall_s']:.2f} s)")


@app.command()
@config_options(_config.StitchConfig)
def stitch(
    json_out: bool = typer.Option(False, "--json", help='Print {"fx": ..., "fy": ...} and the rest as JSON.'),
    options: dict = None,
) -> None:
    """Periodised jersey stitch: tensions per thread f_x, f_y at imposed (l_x, l_y), relaxed at mu = 0."""

    cfg = validated(_config.StitchConfig, options)
    settings = cfg.settings()
    try:
        result = _experiment("stitch", cfg).result
    except ValueError as e:
        typer.echo(f"knitlad: run failed: {e}", err=True)
        raise typer.Exit(1)
    if json_out:
        typer.echo(_json(result.summary()))
    else:
        m = settings.material
        typer.echo(f"periodised {cfg.pattern} stitch at l_x/l0 = {cfg.lx}, l_y/l0 = {cfg.ly} "
                   f"(d/l0 = {m.diameter / m.stitch_length:.4g}, {cfg.resolution} nodes/stitch): f_x = {result.fx:.4f}, f_y = {result.fy:.4f}"
                   f"{'' if result.converged else ' (relaxation NOT converged)'}  [{result.wall_s:.2f} s]")
    if not result.converged:  # its tensions are no equilibrium's: a failed run, whatever was printed
        typer.echo("knitlad: run failed: the stitch's relaxation did not converge, so f_x and f_y are not the "
                   "tensions of an equilibrium (a finer resolution, or a yarn of this d/l0 does not knit)", err=True)
        raise typer.Exit(1)


@app.command()
@config_options(_config.DiagramConfig, exclude=("ly",))
def diagram(
    options: dict,
    ly: list[float] = typer.Option(None, "--ly", help="l_y/l0 values (repeat the option); default 0.20 to 0.30."),
    out: str = typer.Option("runs/diagram", "--out", help="Folder for fx0_curve.csv and fx0_curve.png."),
) -> None:
    """The f_x = 0 curve of the periodised stitch in the (l_x/l0, l_y/l0) plane (paper, configuration diagram);
    rib's lies below the search's 0.22 l0 (docs/patterns.md)."""
    import pandas as pd

    from knitlad.io.atomic import atomic_path
    from knitlad.io.folders import FolderError, writable_folder
    from knitlad.viz.plots import zero_tension_curve_plot

    values = ly or [0.20, 0.22, 0.24, 0.26, 0.28, 0.30]
    configs = [validated(_config.DiagramConfig, {**options, "ly": v}) for v in values]
    try:  # before any compute
        out_dir = writable_folder(out)
    except FolderError as e:
        fail(f"--out {e}")
    rows = []
    for cfg in configs:
        try:
            lx0 = _experiment("diagram", cfg).summary["lx_over_l0_at_fx0"]
        except ValueError as e:
            typer.echo(f"knitlad: {e}", err=True)
            lx0 = float("nan")
        rows.append({"ly_over_l0": cfg.ly, "lx_over_l0_at_fx0": lx0})
        typer.echo(f"l_y/l0 = {cfg.ly:.3f}: f_x = 0 at l_x/l0 = {lx0:.4f}")
    df = pd.DataFrame(rows)
    with atomic_path(out_dir / "fx0_curve.csv") as tmp:
        df.to_csv(tmp, index=False)
    # the yarn's own d/l0 (1/70, the paper's rounded value, means its Nylon: 0.01437), as `stitch` prints it
    material = configs[0].settings().material
    png = zero_tension_curve_plot(df, material.diameter / material.stitch_length, out_dir / "fx0_curve.png")
    typer.echo(f"wrote {out_dir / 'fx0_curve.csv'} and {png}")


def _check_sweep_options(executor: str, scheduler: str | None, workers: int | None, max_jobs: int) -> None:
    if executor not in ("pool", "dask"):
        fail(f"--executor: must be pool or dask, got {executor!r}")
    if scheduler and executor != "dask":
        fail("--scheduler: only with --executor dask")
    if workers is not None and workers < 1:
        fail(f"--workers: must be >= 1, got {workers}")
    if executor == "dask":
        try:
            import distributed  # noqa: F401
        except ImportError:
            fail("--executor dask: needs the optional extra (pip install 'knitlad[dask]')")
    if max_jobs < 1:
        fail(f"--max-jobs: must be >= 1, got {max_jobs}")


def _sweep_backend(executor: str, scheduler: str | None, cluster: str | None, executor_given: bool = False):
    """(executor, scheduler): with --cluster, Dask on the batch cluster its file describes (a ClusterConfig)."""
    if cluster is None:
        return executor, scheduler
    if scheduler:
        fail("--cluster: not with --scheduler (the cluster brings its own)")
    if executor != "dask" and executor_given:
        fail(f"--cluster: runs the jobs on Dask, not with --executor {executor}")
    from knitlad.studies.cluster import load_cluster
    from knitlad.studies.sweep import SweepError

    try:
        return "dask", load_cluster(cluster)
    except SweepError as e:
        fail(str(e))


def _list_jobs(cfg, jobs, scheduler) -> None:
    """--dry-run: each job's id and swept values, and a batch cluster's worker script."""
    from knitlad.studies.sweep import SweepError

    for job in jobs:
        typer.echo(f"{job.id}  " + " ".join(f"{k}={job.params[k]}" for k in cfg.sweep.axes))
    typer.echo(f"{len(jobs)} jobs")
    if scheduler is not None and not isinstance(scheduler, str):
        try:
            typer.echo(f"each of {scheduler.jobs} workers is submitted as:\n{scheduler.job_script()}")
        except SweepError as e:
            fail(str(e))


@app.command()
def sweep(
    config: str = typer.Argument(..., help="Sweep config (YAML); see configs/ and knitlad.studies.sweep."),
    out: str = typer.Option(None, "--out", help="Output folder; default runs/<config name>."),
    executor: str = typer.Option(None, "--executor", help="pool (processes on this machine, the default) or dask."),
    scheduler: str = typer.Option(None, "--scheduler", help="Dask scheduler address (default: a local cluster)."),
    cluster: str = typer.Option(None, "--cluster", help="A batch cluster to start for the sweep (YAML: kind, jobs, "
                                "options of dask-jobqueue; configs/cluster/); implies --executor dask."),
    workers: int = typer.Option(None, "--workers", help="Parallel jobs (default: all cores), one Numba thread each."),
    force: bool = typer.Option(False, "--force", help="Rerun jobs that already have a result."),
    retry_failed: bool = typer.Option(False, "--retry-failed", help="Rerun jobs recorded as failed."),
    rerun_stale: bool = typer.Option(False, "--rerun-stale", help="Rerun finished jobs whose file another knitlad "
                                     "(version or commit) made; by default they are kept and counted."),
    dry_run: bool = typer.Option(False, "--dry-run", help="Validate and list the jobs, run nothing."),
    max_jobs: int = typer.Option(10_000, "--max-jobs", help="Refuse a sweep of more jobs than this."),
    render: bool = typer.Option(False, "--render", help="Render each finished ladder job (<out>/renders/<id>/)."),
) -> None:
    """Run a sweep: one job per point of the config, in a process pool or on a Dask cluster.

    Finished jobs are skipped when the command is run again; the summary table
    (summary.csv) always matches the job files, also after a crash or Ctrl-C.
    Exit code 0: every job done; 1: some job failed (this time or before); 2: bad
    input; 130: interrupted (Ctrl-C); 143: terminated (SIGTERM).
    """
    from pathlib import Path

    from knitlad.studies.sweep import SweepError, load_sweep

    executor, scheduler = _sweep_backend(executor or "pool", scheduler, cluster, executor_given=executor is not None)
    _check_sweep_options(executor, scheduler, workers, max_jobs)
    try:
        cfg, jobs = load_sweep(config, max_jobs=max_jobs)
    except SweepError as e:
        fail(str(e))
    out_dir = Path(out) if out else Path("runs") / Path(config).stem
    if dry_run:
        _list_jobs(cfg, jobs, scheduler)
        return
    from knitlad.io.folders import FolderError, FolderLock, writable_folder
    from knitlad.studies.runner import SchedulerError, connect, run_sweep

    if isinstance(scheduler, str):
        try:
            connect(scheduler).close()  # before anything starts: an unreachable scheduler is one line
        except SchedulerError as e:
            fail(str(e))
    try:  # and so is a folder that cannot be used, or is in use
        FolderLock(writable_folder(out_dir)).check_free()
    except FolderError as e:
        fail(f"--out {e}")
    typer.echo(f"{len(jobs)} jobs -> {out_dir} ({executor}{f', cluster {cluster}' if cluster else ''})", err=True)
    _say_if_compiling()
    try:
        outcome = run_sweep(jobs, out_dir, executor=executor, workers=workers, scheduler=scheduler, force=force,
                            retry_failed=retry_failed, config_text=Path(config).read_text(), rerun_stale=rerun_stale)
    except (FolderError, SchedulerError, SweepError) as e:
        fail(str(e))
    summary = out_dir / "summary.csv"
    if outcome.interrupted:
        how = "terminated" if outcome.terminated else "interrupted"
        typer.echo(f"knitlad: {how}; {outcome.ran} jobs finished this time, summary in {summary}; "
                   "run the same command again to go on", err=True)
        raise typer.Exit(143 if outcome.terminated else 130)
    typer.echo(f"{outcome.ran} jobs run ({outcome.failed} failed), {outcome.skipped} already done; summary: {summary}")
    if outcome.stale:
        from knitlad.io.provenance import code_identity

        typer.echo(f"knitlad: {len(outcome.stale)} finished jobs were made by another knitlad than this one "
                   f"({code_identity()}), kept (the summary's knitlad_code column); --rerun-stale runs them again",
                   err=True)
    if render:
        _render_jobs(out_dir, [row["job_id"] for row in outcome.rows.values()
                               if row["status"] == "ok" and row["scene"] == "ladder"])
    failed = outcome.failed_rows
    if failed:
        for row in failed:
            typer.echo(f"  failed {row['job_id']}: {row['error']}", err=True)
        typer.echo(f"knitlad: {len(failed)} of {len(outcome.rows)} jobs failed; rerun with --retry-failed to run "
                   "them again", err=True)
        raise typer.Exit(1)


def _sweep_table(folder):
    """The sweep's table, checked against its job files: (rows to plot, problems found).

    With the sweep's config (``sweep.yaml``, written by the sweep) the rows are rebuilt from
    the job files, the truth; a summary that lacks rows, or lists as done a job whose file is
    missing or not its own, is a problem said in one line each."""
    from pathlib import Path

    import pandas as pd

    from knitlad.io.summary import read_summary
    from knitlad.studies.runner import job_path, summary_row, trusted_attrs
    from knitlad.studies.sweep import SweepError, load_sweep

    folder = Path(folder)
    problems = []
    try:
        summary = read_summary(folder)
    except FileNotFoundError as e:
        if not (folder / "sweep.yaml").exists():
            fail(str(e))
        summary, problems = None, [f"{folder / 'summary.csv'}: missing"]
    except (ValueError, UnicodeDecodeError, pd.errors.ParserError) as e:
        if not (folder / "sweep.yaml").exists():
            fail(f"{folder / 'summary.csv'}: unreadable ({str(e).splitlines()[0]})")
        summary, problems = None, [f"{folder / 'summary.csv'}: unreadable"]
    if not (folder / "sweep.yaml").exists():
        return summary, problems
    try:
        _, jobs = load_sweep(folder / "sweep.yaml")
    except SweepError as e:
        fail(f"{folder / 'sweep.yaml'}: {e}")
    listed = {} if summary is None else {row["job_id"]: row for row in summary.to_dict("records")}
    rows = []
    for job in jobs:
        attrs, why = trusted_attrs(job_path(folder / "jobs", job), job)
        rows.append(summary_row(job, attrs))
        if summary is not None and job.id not in listed:
            problems.append(f"job {job.id}: missing from summary.csv (read from its file)")
        elif summary is not None and listed[job.id]["status"] == "ok" and attrs is None:
            problems.append(f"job {job.id}: summary.csv says done, but {why or 'it has no file'}")
    return pd.DataFrame(rows), problems


@app.command()
def plot(
    folder: str = typer.Argument(..., help="A sweep folder (with summary.csv) or a run folder (with ladder.h5)."),
    diagrams: bool = typer.Option(True, "--diagrams/--no-diagrams", help="Also draw each job's spatio-temporal diagram "
                                  "(named by the parameters that vary between the jobs)."),
    fmt: str = typer.Option("png", "--format", help="Figure format: png, pdf or svg."),
) -> None:
    """Figures of a sweep (n_lad/n_y, f_x^fin and v_lad/c_b against f_x^ini, each job's diagrams)
    or of one run (its cell and midline diagrams and renders).

    A sweep's summary is checked against the job files first; what is missing or wrong is
    said on stderr, the figures are drawn from what the files hold, and the exit code is 1.
    """
    try:
        _plot(folder, diagrams, fmt)
    except OSError as e:  # a read-only or full disk: one line, as every command says it
        typer.echo(f"knitlad: error: the figures could not be written in {folder} ({e})", err=True)
        raise typer.Exit(1)


def _plot(folder: str, diagrams: bool, fmt: str) -> None:
    """`knitlad plot` (its docstring), the figures' writing failures left to it."""
    import h5py

    from knitlad.viz.plots import (FORMATS, column_midline_diagram, energy_ledger_plot, job_figure_names,
                                   spatio_temporal_from_file, summary_plots, tensile_curve_plot,
                                   tension_history_plot)

    from knitlad.io.folders import FolderError, writable_folder

    if fmt not in FORMATS:
        fail(f"--format: one of {', '.join(FORMATS)}, got {fmt!r}")
    run = (Path(folder) / "ladder.h5").is_file()
    if run or (Path(folder) / "summary.csv").is_file():  # where the figures go must take them, before any is drawn
        try:
            writable_folder(Path(folder) / ("render" if run else "plots"))
        except FolderError as e:
            fail(f"{folder}: the figures cannot be written there ({e})")
    if run:
        from knitlad.viz.render import render_run

        h5 = _run_file(folder)
        line = _CountProgress("render", "images")
        paths, missing = [], []
        for name, draw in (("spatio_temporal", spatio_temporal_from_file), ("midline_diagram", column_midline_diagram),
                           ("tension_history", tension_history_plot), ("energy", energy_ledger_plot)):
            try:
                paths.append(draw(h5, Path(folder) / f"{name}.{fmt}"))
            except (KeyError, ValueError) as e:  # a file without that record (an older knitlad's): said, not a traceback
                missing.append(f"no {name}.{fmt}: {h5} lacks {str(e).strip(chr(39))}")
        paths += render_run(h5, Path(folder) / "render", progress=line)
        line.close()
        typer.echo(f"wrote {len(paths)} figures in {folder}")
        for why in missing:
            typer.echo(f"knitlad: {why}", err=True)
        return

    df, problems = _sweep_table(folder)
    if not (df["status"] == "ok").any():
        fail(f"{folder}: no finished job to plot yet")
    if "knitlad_code" in df:
        from knitlad.io.provenance import code_identity

        codes = sorted({str(c) for c in df.loc[df["status"] == "ok", "knitlad_code"]})
        if len(codes) > 1 or (codes and codes[0] != code_identity()):
            typer.echo(f"knitlad: warning: these results were made by {len(codes)} versions of knitlad "
                       f"({', '.join(codes)}; this one is {code_identity()}): knitlad sweep --rerun-stale makes "
                       "them again with this one", err=True)
    _say_collapsed_members(df)
    fig_dir = Path(folder) / "plots"
    paths = summary_plots(df, fig_dir, fmt)
    if diagrams:
        ladders = (df["status"] == "ok") & (df["scene"] == "ladder")
        names = job_figure_names(df[ladders])
        for job in df.loc[ladders, "job_id"]:
            try:
                paths.append(spatio_temporal_from_file(Path(folder) / "jobs" / f"{job}.h5",
                                                       fig_dir / f"{names[job]}.{fmt}"))
            except (OSError, KeyError, ValueError) as e:
                problems.append(f"job {job}: no diagram ({type(e).__name__}: {str(e).splitlines()[0]})")
        pulled = (df["status"] == "ok") & (df["scene"] == "tensile")
        names = job_figure_names(df[pulled])
        for job in df.loc[pulled, "job_id"]:  # each tensile job's loops, from its file
            try:
                with h5py.File(Path(folder) / "jobs" / f"{job}.h5", "r") as f:
                    readings = f["tensile/readings"][()]
                paths.append(tensile_curve_plot(readings, fig_dir / f"tensile_{names[job]}.{fmt}"))
            except (OSError, KeyError, ValueError) as e:
                problems.append(f"job {job}: no tensile loop ({type(e).__name__}: {str(e).splitlines()[0]})")
    typer.echo(f"wrote {len(paths)} figures in {fig_dir}")
    for line in problems:
        typer.echo(f"knitlad: {line}", err=True)
    if problems:
        raise typer.Exit(1)


def _say_collapsed_members(df) -> None:
    """A warning when ensemble members stretched to the same knit as another (their scatter measures nothing)."""
    if "same_knit_as" in df and (df["same_knit_as"].fillna(-1) >= 0).any():
        collapsed = int((df["same_knit_as"].fillna(-1) >= 0).sum())
        typer.echo(f"knitlad: warning: {collapsed} ensemble member{'s' * (collapsed != 1)} stretched to the same knit "
                   "as another member of its point (same_knit_as): counted once in the means and error bars",
                   err=True)


def _render_jobs(out_dir, job_ids: list[str]) -> None:
    """The default renders (front view) of each ladder job, in ``out_dir/renders/<id>/``."""
    from knitlad.viz.render import render_run

    for job in job_ids:
        try:
            render_run(out_dir / "jobs" / f"{job}.h5", out_dir / "renders" / job, views=("front",))
        except (OSError, KeyError, ValueError) as e:
            typer.echo(f"knitlad: job {job}: no render ({type(e).__name__}: {str(e).splitlines()[0]})", err=True)
    typer.echo(f"rendered {len(job_ids)} jobs in {out_dir / 'renders'}")


COMPILE_TIME = "about 1.5 minutes on 2 cores"  # a fresh cache, measured: docs/performance.md


def _say_if_compiling() -> None:
    """One line on stderr when Numba's cache holds no step kernel compiled from the present kernel sources: the
    first run of a fresh install, or after a kernel was edited, compiles first, and said nothing."""
    from knitlad.engine.kernels import is_compiled
    from knitlad.engine.kernels.integrate import verlet_steps

    if not is_compiled(verlet_steps):
        from knitlad.engine.compile_ahead import compile_ahead

        typer.echo(f"knitlad: compiling the kernels (the first run only: {COMPILE_TIME}, then cached)", err=True)
        compile_ahead()


MIN_FIT_STITCHES = 5  # a front fitted over fewer stitches is a rough figure


def _ever_line(result) -> str:
    """The cells undone at some time that the stop's count leaves out."""
    parts = [f"{result.n_lad_ever} undone at some time"]
    if result.n_lad_rehooked:
        parts.append(f"{result.n_lad_rehooked} hooked again")
    if result.n_lad_between:
        parts.append(f"{result.n_lad_between} neither hooked nor a bar")
    return ", ".join(parts)


def _loop_line(result) -> str:
    """The freed loops of the paper's Fig. 2d whose ladders ran, read from where the cut thread went."""
    r = result.loop_record()
    if r["loop1_column"] < 0:
        return "the cut thread left neither needle loop beside the cut: no loop freed"
    when = {"(1)": r["up_from_1_ms"], "(2)/(3)": r["down_from_2_3_ms"], "(4)/(5)": r["up_from_4_5_ms"]}
    ran = [f"{loop} at {when[loop]:.2f} ms" for loop in r["loop_sequence"].split(", ") if loop in when]
    line = ("ladders from " + ", then ".join(ran)) if ran else "no ladder ran from a freed loop"
    if r["paper_order"] and len(ran) == 3:
        line += " (the paper's sequence)"
    if r["cut_thread_held"]:
        line += "; the cut thread held in loops (4) and (5)" + (": hindered laddering" if r["hindered"] else "")
    if r["other_ladders"]:
        line += f"; {r['other_ladders']} ladder{'s' * (r['other_ladders'] != 1)} from no freed loop"
    return line


def _fin_caveat(result) -> str:
    """f_x^fin is the tension after an arrest only if the ladder arrested (Arrested stop rule)."""
    if result.stop_reason.startswith("no cell changed"):
        return "  (after the arrest)"
    return f"  (no arrest: {result.stop_reason}; the mean tension while it ran, not an arrest value)"


def _velocity_caveat(result) -> str:
    first, last = result.v_fit_stitches
    why = result.nan_reasons().get("v_lad_over_cb")
    if why:
        return f"(no velocity: {why})"
    span = f"front fit over stitches {first}-{last}"
    if last - first + 1 < MIN_FIT_STITCHES:
        return f"({span}: fewer than {MIN_FIT_STITCHES} stitches, a rough figure)"
    return f"({span})"


def _yarn_option(cfg) -> str:
    """The option that set the yarn's d/l0 in ``cfg``: the stitch length, the yarn file, or d/l0 itself."""
    if getattr(cfg, "stitch_length_mm", None) is not None:
        return "--stitch-length-mm"
    return "--yarn" if getattr(cfg, "yarn", None) is not None else "--d-over-l0"


def _experiment_or_exit(run, progress, kept: str = "nothing written", cfg=None):
    """``run()`` (an experiment, :func:`_experiment`), every way it can end without a result said in
    one line: Ctrl-C (130) and SIGTERM (143), a run that failed (1), settings found infeasible once the knit
    is built (2)."""
    from knitlad.fabric.observers import Interpenetration
    from knitlad.fabric.preparation import InfeasibleRun
    from knitlad.fabric.scenes.knit import CourseTooWide
    from knitlad.engine.simulation import SimulationBlowUp
    from knitlad.fabric.stretching import OutOfReach

    previous = signal.signal(signal.SIGTERM, _on_sigterm)  # a batch system's kill: said, as Ctrl-C is
    try:
        return run()
    except KeyboardInterrupt as e:
        progress.close()
        how, code = ("terminated", 143) if isinstance(e, Terminated) else ("interrupted", 130)
        typer.echo(f"knitlad: {how}; {kept}", err=True)
        raise typer.Exit(code)
    except (OutOfReach, Interpenetration, SimulationBlowUp) as e:  # the run failed (not bad input): one line, exit 1
        progress.close()
        typer.echo(f"knitlad: run failed: {e}", err=True)
        raise typer.Exit(1)
    except CourseTooWide as e:  # no stitch of this yarn fits: bad input, found when the knit is built
        progress.close()
        fail(f"{_yarn_option(cfg)}: {e}; a longer stitch, a thinner yarn or a larger --ly fits")
    except InfeasibleRun as e:  # settings whose step cannot serve the run: bad input, found when it is set
        progress.close()
        fail(str(e))
    finally:
        signal.signal(signal.SIGTERM, previous)


# what knitlad cut, render, movie and plot write in a run folder
RUN_OUTPUTS = ("ladder.h5", "ladder.xdmf", "spatio_temporal.png", "midline_diagram.png", "tension_history.png",
               "energy.png", "ladder.mp4", "ladder.gif", "summary.json", "run.log", "render")


def earlier_run_outputs(out_dir) -> list:
    """The files and folders of an earlier run in ``out_dir``."""
    return [out_dir / name for name in RUN_OUTPUTS if (out_dir / name).exists()]


def _remove(paths) -> None:
    import shutil

    for path in paths:
        shutil.rmtree(path) if path.is_dir() else path.unlink(missing_ok=True)


def _replace_run_outputs(out_dir, finished, earlier: list):
    """Write the run into a staging folder in ``out_dir``, then remove the ``earlier`` run's files (its renders
    and movies would not match this run) and move the new ones in: an OSError while writing leaves the earlier
    run as it was and no staging folder."""
    import shutil

    stage = out_dir / f".new-{os.getpid()}"
    shutil.rmtree(stage, ignore_errors=True)
    stage.mkdir()
    previous = signal.signal(signal.SIGTERM, _on_sigterm)  # a kill while writing: the staging folder goes too
    try:
        h5, png = _write_run_outputs(stage, finished)
        log = _write_run_log(stage / "run.log", finished.summary)
        _remove(earlier)
        for new in (h5, h5.with_suffix(".xdmf"), png, log):
            os.replace(new, out_dir / new.name)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        signal.signal(signal.SIGTERM, previous)
    return out_dir / h5.name, out_dir / png.name


def _json(summary: dict) -> str:
    """``summary`` as valid JSON: a NaN or an infinity (which json writes as NaN, Infinity: not JSON) is null,
    its reason in the summary's ``nan_reasons`` where it has one."""
    import json

    def plain(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, (list, tuple)):
            return [plain(v) for v in value]
        if hasattr(value, "item") and not isinstance(value, (list, dict, str)):  # numpy scalars
            return plain(value.item())
        return value

    return json.dumps({k: plain(v) for k, v in summary.items()}, allow_nan=False, default=float)


def _write_run_log(path, summary: dict):
    """run.log: the command line, where, when and with what it ran, and its summary, as plain text."""

    from knitlad.io.provenance import run_provenance

    lines = ["command: " + " ".join(["knitlad", *sys.argv[1:]]), f"cwd: {os.getcwd()}"]
    lines += [f"{key}: {value}" for key, value in run_provenance().items()]
    lines.append("summary: " + _json(summary))
    path.write_text("\n".join(lines) + "\n")
    return path


def _experiment(name: str, cfg, folder: Path | None = None, progress=None, **hooks):
    """The experiment ``name`` run through its one entry (:data:`knitlad.studies.registry.EXPERIMENTS`), as a sweep's
    job runs it: a :class:`knitlad.studies.registry.Finished`."""
    from knitlad.studies.registry import EXPERIMENTS
    from knitlad.studies.sweep import Output

    return EXPERIMENTS[name].run(cfg, Output(), folder, progress, **hooks)


def _write_experiment(finished, path: Path) -> tuple[Path, ...]:
    """The run file at ``path`` and the tables and pictures beside it; OSError if any cannot be written, with
    nothing of this run left (its files written so far and temporary files removed, HDF5's complaints while
    closing a failed file kept off the terminal): a run is written whole or not at all."""
    previous = sys.unraisablehook
    sys.unraisablehook = lambda info: None  # h5py's __dealloc__ of a file whose writes failed
    there = set(path.parent.iterdir()) if path.parent.is_dir() else set()
    try:
        return (finished.write(path, {}), *finished.beside(path))
    except (OSError, RuntimeError) as e:  # h5py reports some failed writes as RuntimeError
        for p in path.parent.iterdir():  # the files this run made (a file kept before, as cycle.csv, stays)
            if p.is_file() and p not in there:
                p.unlink(missing_ok=True)
        raise OSError(str(e).splitlines()[0]) from None
    finally:
        sys.unraisablehook = previous
        for tmp in path.parent.glob("*.tmp*"):
            tmp.unlink(missing_ok=True)


def _write_run_outputs(out_dir, finished):
    """ladder.h5, ladder.xdmf and spatio_temporal.png of a laddering run (:func:`_write_experiment`)."""
    h5, _, png = _write_experiment(finished, out_dir / "ladder.h5")
    return h5, png


def _keep_summary(out_dir, summary: dict):
    """summary.json beside the run (a few hundred bytes), or None if even that cannot be written."""

    from knitlad.io.atomic import atomic_path

    try:
        with atomic_path(out_dir / "summary.json") as tmp:
            tmp.write_text(_json(summary))
        return out_dir / "summary.json"
    except OSError:
        return None


# the run files a ladder is drawn from, in a folder written by knitlad cut, snag, resistance or cycle
LADDER_FILES = ("ladder.h5", "snag.h5", "resistance.h5", "cycle.h5")


def _run_file(run: str):
    """The run file of a run folder (the first of :data:`LADDER_FILES` it holds), or the file itself; one line
    and exit 2 if there is none."""
    from pathlib import Path

    path = Path(run)
    if path.is_dir():
        path = next((path / name for name in LADDER_FILES if (path / name).is_file()), path / "ladder.h5")
    if not path.is_file():
        fail(f"{run}: no ladder.h5 (a folder written by knitlad cut, or its file; or snag.h5, resistance.h5, "
             "cycle.h5 of a snag, a resistance test or protocol B with a cut)")
    from knitlad.io.hdf5 import RunFileError, check_run_file

    try:
        check_run_file(path)
    except RunFileError as e:
        fail(str(e))
    return path


def _check_colour(colour: str) -> None:
    from knitlad.viz.render import COLOURINGS

    if colour not in COLOURINGS:
        fail(f"--colour: one of {', '.join(COLOURINGS)}, got {colour!r}")


MIN_WIDTH, MAX_WIDTH = 64, 8192  # pixels: a million wide asked VTK for terabytes (std::bad_alloc, an abort)


@app.command()
def render(
    run: str = typer.Argument(..., help="A run folder written by knitlad cut (or its ladder.h5), or the trajectory "
                             "file of a scene of one's own (knitlad.write_trajectory)."),
    at_ms: list[float] = typer.Option(None, "--at-ms", help="Instants after the cut \\[ms] (repeat); default: just "
                                      "after the cut, then four evenly spaced instants of the ladder."),
    view: list[str] = typer.Option(None, "--view", help="front (the x-y plane) and/or oblique (repeat); default both."),
    width: int = typer.Option(1200, "--width", help="Image width \\[pixels]; height 3/4 of it."),
    out: str = typer.Option(None, "--out", help="Folder of the images; default: render/ beside a run's ladder.h5, "
                            "<file>_render/ beside any other file (each job of a sweep its own)."),
    colour: str = typer.Option("course", "--colour", help="What the yarn's colour shows: course, speed, contact "
                               "(free, touching, sliding), strain (axial: the tension) or depth (knit and purl "
                               "apart: which yarn lies in front)."),
) -> None:
    """Images of the fabric: yarns as tubes of their diameter coloured by course, the cut course black, undone cells red."""
    from knitlad.viz.render import render_run

    h5 = _run_file(run)
    out_dir = Path(out) if out else h5.parent / ("render" if h5.name == "ladder.h5" else f"{h5.stem}_render")
    views = tuple(view or ("front", "oblique"))
    if not set(views) <= {"front", "oblique"}:
        fail(f"--view: front or oblique, got {', '.join(views)}")
    if not MIN_WIDTH <= width <= MAX_WIDTH:
        fail(f"--width: {MIN_WIDTH} to {MAX_WIDTH} pixels, got {width}")
    _check_colour(colour)
    if at_ms and not all(math.isfinite(t) for t in at_ms):
        fail(f"--at-ms: finite instants after the cut are needed, got {', '.join(map(str, at_ms))}")
    line = _CountProgress("render", "images")
    try:
        paths = render_run(h5, out_dir, [t * 1e-3 for t in at_ms] if at_ms else None, views,
                           (width, width * 3 // 4), progress=line, colouring=colour)
    except ValueError as e:
        fail(str(e))
    except OSError as e:  # a full disk: what was written whole stays, the rest is said
        line.close()
        typer.echo(f"knitlad: render stopped: {e}", err=True)
        raise typer.Exit(1)
    line.close()
    typer.echo(f"wrote {len(paths)} images in {out_dir}")


@app.command()
def movie(
    run: str = typer.Argument(..., help="A run folder written by knitlad cut (or its ladder.h5), or the trajectory "
                             "file of a scene of one's own (knitlad.write_trajectory)."),
    gif: bool = typer.Option(False, "--gif", help="An animated GIF instead of an MP4."),
    fps: int = typer.Option(12, "--fps", help="Frames per second of the movie."),
    width: int = typer.Option(960, "--width", help="Frame width \\[pixels]; height 3/4 of it."),
    colour: str = typer.Option("course", "--colour", help="What the yarn's colour shows: course, speed, contact, "
                               "strain or depth."),
) -> None:
    """A movie of the laddering: every stored frame, front view, with a time stamp and the undone cells."""
    from knitlad.viz.render import movie as make_movie

    h5 = _run_file(run)
    if fps < 1:
        fail(f"--fps: at least 1, got {fps}")
    _check_colour(colour)
    if not MIN_WIDTH <= width <= MAX_WIDTH:
        fail(f"--width: {MIN_WIDTH} to {MAX_WIDTH} pixels, got {width}")
    line = _CountProgress("movie", "frames")
    previous = sys.unraisablehook
    sys.unraisablehook = lambda info: None  # the GIF writer's clean-up after a failed write complains twice
    try:
        path = make_movie(h5, h5.with_suffix(".gif" if gif else ".mp4"), fps=fps, size=(width, width * 3 // 4),
                          progress=line, colouring=colour)
    except ValueError as e:
        fail(str(e))
    except OSError as e:  # a full disk: the movie is not renamed into place
        line.close()
        typer.echo(f"knitlad: movie not written: {e}", err=True)
        raise typer.Exit(1)
    finally:
        import gc

        gc.collect()  # the failed writer is finalised now, under the quiet hook
        sys.unraisablehook = previous
    line.close()
    typer.echo(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")


# the experiments whose commands above print their own lines (`ladder` is `knitlad cut`)
OWN_COMMANDS = ("ladder", "cycle", "tensile", "snag", "resistance", "loop", "stitch", "diagram")


def experiment_command(name: str):
    """`knitlad <name>` for a registry entry without a command of its own: its config's fields as options
    (a knit's size as --stitches), the run through the entry, ``<name>.h5`` and its companions in --out, the
    summary as ``key = value`` lines or JSON. A new experiment needs no edit here."""
    from knitlad.studies.registry import EXPERIMENTS

    entry = EXPERIMENTS[name]
    knit = "n_x" in entry.config.model_fields

    def command(
        stitches: str = typer.Option(None, "--stitches", help=STITCHES_HELP,
                                     rich_help_panel=EXPERIMENT_PANEL, hidden=not knit),
        out: str = typer.Option(None, "--out", help=f"Output folder; default runs/{name}-<time>.",
                                rich_help_panel=OUTPUT_PANEL),
        json_out: bool = typer.Option(False, "--json", help="Print the summary as one JSON object.",
                                      rich_help_panel=OUTPUT_PANEL),
        options: dict = None,
    ) -> None:
        with _prologue(name, entry.config, options, stitches, None, out) as (cfg, out_dir, progress):
            finished = _experiment_or_exit(lambda: _experiment(name, cfg, progress=progress), progress, cfg=cfg)
            progress.close(finished=True)
            paths = _files_or_exit(lambda: _write_experiment(finished, out_dir / f"{name}.h5"), finished.summary)
        if json_out:
            typer.echo(_json(finished.summary))
            return
        shown = [key for key in entry.summary_keys if key in finished.summary and key != "job_wall_s"]
        width = max((len(key) for key in shown), default=0)
        typer.echo("\n".join([entry.description.split(": ", 1)[-1]]
                             + [f"  {key:{width}s} = {finished.summary[key]}" for key in shown]
                             + [f"  wrote {', '.join(str(p) for p in paths)}"]))

    command.__doc__ = entry.description.split(": ", 1)[-1]
    return config_options(entry.config, exclude=("n_x", "n_y") if knit else ())(command)


def _experiments_without_commands() -> None:
    from knitlad.studies.registry import EXPERIMENTS

    for name in EXPERIMENTS:
        if name not in OWN_COMMANDS:
            app.command(name)(experiment_command(name))


_experiments_without_commands()


def main(argv: list[str] | None = None) -> None:
    """The console entry point: a usage error (an unknown option, a value of the wrong type) is one line and
    exit 2, as every other bad input is, instead of click's boxed usage text."""
    try:  # typer vendors click from 0.20 on
        from typer._click import exceptions as cx
    except ImportError:  # pragma: no cover - older typer, on click itself
        from click import exceptions as cx

    import warnings

    formatwarning, warnings.formatwarning = warnings.formatwarning, _one_line_warning
    try:
        result = app(args=argv, standalone_mode=False)
    except cx.UsageError as e:
        message = e.format_message()  # the help itself when no command is given
        typer.echo(message if message.startswith("Usage:") else f"knitlad: error: {message}", err=True)
        sys.exit(2)
    except typer.Exit as e:
        sys.exit(e.exit_code)
    except BrokenPipeError:  # the reader went away (knitlad scales | head): nothing more to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)
    except typer.Abort:  # Ctrl-C outside a run
        typer.echo("knitlad: interrupted", err=True)
        sys.exit(130)
    finally:
        warnings.formatwarning = formatwarning
    sys.exit(result if isinstance(result, int) else 0)


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """A warning on the terminal is one line that says what happened, not the source line that raised it."""
    return f"knitlad: warning: {str(message).splitlines()[0]}\n"


if __name__ == "__main__":  # python -m knitlad.cli
    main()
