"""The command line: bad input is refused in one line with exit code 2; `knitlad cut` end to end."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from tests.conftest import knitlad

KNITLAD = [sys.executable, "-m", "knitlad.cli"]


def run(*args, cwd=None):
    return knitlad(*args, cwd=cwd or os.getcwd())


@pytest.mark.parametrize(
    "args, option",
    [
        (["cut", "--stitches", "3"], "--stitches"),
        (["cut", "--stitches", "8y"], "--stitches"),
        (["cut", "--mu", "-1"], "--mu"),
        (["cut", "--lx", "1.2"], "--lx"),
        (["cut", "--lx", "0.4", "--fx", "3"], "either fx"),
        (["cut", "--resolution", "4"], "--resolution"),
        (["cut", "--drag", "-5"], "--drag"),
        (["demo", "--nodes", "2"], "--nodes"),
        (["loop", "--mu", "-0.1"], "--mu"),
        (["loop", "--lx", "0.39"], "--lx"),
        (["loop", "--max-time-ms", "0"], "--max-time-ms"),
        (["loop", "--geometry", "ring"], "--geometry"),
        (["loop", "--geometry", "strip", "--lx", "0.32"], "lx"),
        (["loop", "--geometry", "periodic", "--columns", "3"], "columns"),
        (["cut", "--preset", "fastest"], "--preset"),
        (["cut", "--pattern", "purl"], "--pattern"),
        (["cut", "--pattern", "rib", "--stretch-start", "tiled"], "stretch_start"),
        (["cut", "--band", "rib"], "band_row"),
        (["cut", "--band", "rib", "--band-row", "8", "--stretch-start", "tiled"], "stretch_start"),
        (["loop", "--preset", "exact"], "--preset"),
        (["cycle", "--lx", "0.38", "--lx-max", "0.36"], "--lx-max"),
        (["cycle"], "--lx-max"),
        (["cycle", "--lx-max", "0.38", "--bar-speed", "0"], "--bar-speed"),
        (["cut", "--clip-friction", "0.3"], "--clip-friction"),
        (["cut", "--clip-friction", "-1", "--bars", "sliding"], "--clip-friction"),
    ],
)
def test_bad_options_get_one_line_and_exit_code_2(args, option):
    p = run(*args)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and option in lines[0] and "Traceback" not in p.stderr


def test_cut_runs_a_ladder_end_to_end_on_a_small_knit(tmp_path):
    """8 x 10 stitches stretched to l_x = 0.40 l0 (f_x ~ 4.5): after the cut a ladder runs
    and releases tension; the summary, the HDF5 file and the diagram are written."""
    p = run("cut", "--lx", "0.40", "--stitches", "8x10", "--max-time-ms", "10", "--out", str(tmp_path), "--json")
    assert p.returncode == 0, p.stderr
    summary = json.loads(p.stdout.strip().splitlines()[-1])
    for key in ("fx_ini", "fx_fin", "n_lad_over_ny", "v_lad_over_cb", "lx_over_l0", "ly_over_l0", "wall_s"):
        assert key in summary
    assert summary["fx_ini"] > 2.0
    assert summary["n_lad_over_ny"] >= 0.2  # at least two cells undone
    assert summary["fx_fin"] < summary["fx_ini"]  # the freed yarn relaxes the fabric
    with h5py.File(tmp_path / "ladder.h5") as f:
        assert f["frames/positions"].shape[0] >= 1
        assert f.attrs["scale_f0_N"] == pytest.approx(0.01477, abs=1e-4)
        assert len(f["series/front_up"]) == len(f["series/time"])
    assert (tmp_path / "spatio_temporal.png").stat().st_size > 1000


@pytest.mark.parametrize("pattern", ["rib", "garter"])
@pytest.mark.end_to_end
def test_cut_ladders_and_renders_a_knit_of_another_pattern(tmp_path, pattern):
    """A 6 x 6 knit of rib or garter is built, stretched affinely to f_x^ini 3, cut and rendered; its file
    says its pattern, the read-out names it."""
    p = run("cut", "--pattern", pattern, "--stitches", "6x6", "--preset", "fast", "--fx", "3", "--max-time-ms", "2",
            "--out", str(tmp_path))
    assert p.returncode == 0, p.stderr
    assert f"6 x 6 {pattern}, mu = 0.4" in p.stdout
    with h5py.File(tmp_path / "ladder.h5") as f:
        assert json.loads(f.attrs["settings_json"])["stretch"]["pattern"] == pattern
        assert f.attrs["fx_ini"] == pytest.approx(3.0, rel=0.02)
        assert f.attrs["n_lad"] >= 1
    p = run("render", str(tmp_path), "--at-ms", "0", "--view", "front", "--width", "400")
    assert p.returncode == 0, p.stderr
    assert len(list((tmp_path / "render").glob("render_front_*.png"))) == 1


@pytest.mark.end_to_end
def test_cycle_runs_protocol_b_end_to_end_on_a_small_knit(tmp_path):
    """One cycle of a 6 x 8 knit (fast preset) to l_x = 0.36 l0 and a cut there: the readings (start, a
    loading, the hold, an unloading) in the CSV and the HDF5 file beside the ladder, Fig. 4a as a PNG."""
    p = run("cycle", "--stitches", "6x8", "--preset", "fast", "--lx-max", "0.36", "--cycles", "1",
            "--readings-per-leg", "3", "--bar-speed", "0.2", "--fx-thr", "1", "--max-time-ms", "1", "--out", str(tmp_path))
    assert p.returncode == 0, p.stderr
    assert "predicted n_lad/n_y" in p.stdout and "cut: n_lad/n_y" in p.stdout
    table = (tmp_path / "cycle.csv").read_text().splitlines()
    assert table[0] == "cycle,leg,t_s,box_lx_over_l0,fx" and len(table) == 1 + 1 + 3 + 1 + 3
    with h5py.File(tmp_path / "cycle.h5") as f:
        assert f["cycle/readings"].shape == (8, 5) and "series/fx" in f
        assert f.attrs["cycle_fx_ini"] > 1 and f.attrs["cycle_delta_l_over_l0"] > 0
        # Eq. 1 also read at the cut copy's own f_x^fin (the paper's f_thr)
        assert f.attrs["cycle_fx_thr_own"] == pytest.approx(f.attrs["fx_fin"])
    assert (tmp_path / "cycle.png").stat().st_size > 1000
    assert run("cycle", "--stitches", "6x8", "--lx-max", "0.36", "--out", str(tmp_path)).returncode == 2  # not over it


@pytest.mark.end_to_end
def test_tensile_pulls_a_small_knit_and_writes_its_loops(tmp_path):
    """`knitlad tensile` on a 6 x 8 knit (fast preset) along x: the readings in the CSV and the HDF5 file (with
    their unit), the loops as a PNG; without --lx-max or --ly-max the box does not move: exit 2."""
    p = run("tensile", "--stitches", "6x8", "--preset", "fast", "--lx", "0.36", "--lx-max", "0.37",
            "--readings-per-leg", "2", "--out", str(tmp_path))
    assert p.returncode == 0, p.stderr
    assert "friction took" in p.stdout
    table = (tmp_path / "tensile.csv").read_text().splitlines()
    assert table[0] == "leg,t_s,box_lx_over_l0,box_ly_over_l0,lx_over_l0,ly_over_l0,fx,fy" and len(table) == 1 + 1 + 2 + 1 + 2
    with h5py.File(tmp_path / "tensile.h5") as f:
        assert f["tensile/readings"].shape == (6, 8) and "unit" in f["tensile/readings"].attrs
        assert f.attrs["tensile_fx_top"] > f.attrs["tensile_fx_start"]
    assert (tmp_path / "tensile.png").stat().st_size > 1000
    bad = run("tensile", "--stitches", "6x8", "--lx", "0.36", "--out", str(tmp_path / "no"))
    assert bad.returncode == 2 and "lx_max" in bad.stderr and "Traceback" not in bad.stderr


@pytest.mark.end_to_end
def test_snag_breaks_a_worn_loop_and_writes_the_curve_and_the_ladder(tmp_path):
    """`knitlad snag` on a 6 x 6 knit (fast preset) with a 0.1 N worn spot: the break and the ladder said, the
    pull-out curve as CSV and PNG, the ladder's file; a snag outside the knit: exit 2 in one line."""
    p = run("snag", "--stitches", "6", "--preset", "fast", "--snag-speed", "3", "--weak-point-force", "0.1",
            "--max-time-ms", "1", "--out", str(tmp_path))
    assert p.returncode == 0, p.stderr
    assert "the yarn broke at 0.10" in p.stdout and "ladder: n_lad/n_y" in p.stdout
    table = (tmp_path / "snag.csv").read_text().splitlines()
    assert table[0] == "pull_mm,force_N" and len(table) > 10
    assert (tmp_path / "snag.png").stat().st_size > 1000 and (tmp_path / "snag.h5").exists()
    bad = run("snag", "--stitches", "6", "--snag-row", "9", "--out", str(tmp_path / "no"))
    assert bad.returncode == 2 and "--snag-row:" in bad.stderr and "Traceback" not in bad.stderr
    assert not (tmp_path / "no").exists() or not any((tmp_path / "no").iterdir())


def test_a_run_that_fails_is_reported_in_one_line_with_exit_code_1(tmp_path, monkeypatch):
    """A run that stops on its own (force control out of reach, interpenetration, blow-up)
    raises; the command prints one line and writes nothing. The failure is injected: the
    force-control failure itself is tested in test_laddering."""
    from typer.testing import CliRunner

    from knitlad.cli import app
    from knitlad.fabric.stretching import OutOfReach
    from knitlad.studies import registry

    def fail(cfg, folder, progress=None):
        raise OutOfReach("at l_x/l0 = 0.300 the relaxed knit already carries f_x = 0.40 > 0.05: use position control (--lx)")

    monkeypatch.setattr(registry, "prepared_knit", fail)
    p = CliRunner().invoke(app, ["cut", "--fx", "0.05", "--stitches", "8x10", "--out", str(tmp_path / "out")])
    assert p.exit_code == 1
    assert p.output.strip().splitlines()[-1].startswith("knitlad: run failed: at l_x/l0")
    assert not (tmp_path / "out").exists()


def test_loop_prints_the_release_as_json():
    p = run("loop", "--fx", "4", "--mu", "0.4", "--json")
    assert p.returncode == 0, p.stderr
    s = json.loads(p.stdout.strip().splitlines()[-1])
    assert s["released"] and s["v_lad_over_cb"] > 0 and 0 < s["tau_s"] < 1e-3
    assert s["v_lad_over_cb"] == pytest.approx(0.25 * 9.74e-3 / s["tau_s"] / 30.58, rel=2e-3)  # l_y / tau / c_b


def test_presets_set_their_settings_and_an_explicit_one_wins():
    from knitlad.experiments.config import CutConfig, LoopConfig, StitchConfig

    assert [CutConfig(fx=4, preset=p).resolution for p in ("fast", "default", "accurate")] == [24, 48, 96]
    assert [CutConfig(fx=4, preset=p).sagitta_radius for p in ("fast", "default", "accurate")] == [0, 11, 11]
    assert [CutConfig(fx=4, preset=p).implicit_axial for p in ("fast", "default", "accurate")] == [False, True, True]
    assert [StitchConfig(preset=p).resolution for p in ("fast", "default", "accurate")] == [24, 48, 96]
    assert [LoopConfig(preset=p).resolution for p in ("fast", "default", "accurate")] == [24, 36, 48]
    assert CutConfig(fx=4, preset="fast", resolution=30).resolution == 30
    assert CutConfig(fx=4, preset="default", sagitta_radius=0).sagitta_radius == 0
    assert CutConfig(fx=4, implicit_axial=False).implicit_axial is False
    settings = CutConfig(fx=4, preset="accurate").stretch_settings()
    assert (settings.resolution, settings.sagitta_radius) == (96, 11)


def test_the_drag_of_cut_reaches_the_laddering_settings_and_defaults_to_none():
    from knitlad.experiments.config import CutConfig

    assert CutConfig(fx=4).dynamics_settings().drag_per_s == 0.0
    assert CutConfig(fx=4, drag_per_s=2e3).dynamics_settings().drag_per_s == 2e3
    assert CutConfig(fx=4).dynamics_settings().twist is False
    assert CutConfig(fx=4, twist=True).dynamics_settings().twist is True


def test_natural_curvature_turns_twist_on_and_needs_the_tiled_stretch():
    from knitlad.experiments.config import CutConfig

    assert CutConfig(fx=4, natural_curvature=2).twist
    assert not CutConfig(fx=4).twist
    with pytest.raises(ValueError, match="natural_curvature"):
        CutConfig(fx=4, natural_curvature=2, twist=False)
    with pytest.raises(ValueError, match="natural_curvature"):
        CutConfig(fx=4, natural_curvature=2, stretch_start="affine")
    with pytest.raises(ValueError, match="natural_curvature"):
        CutConfig(fx=4, natural_curvature=-1)


def test_a_yarn_too_thick_for_any_stitch_is_one_line_and_nothing_written(tmp_path):
    """d/l0 = 0.1: no jersey stitch fits at l_y/l0 = 0.25 (found when the knit is built): bad input, exit 2."""
    out = tmp_path / "out"
    p = run("cut", "--d-over-l0", "0.1", "--stitches", "4", "--out", str(out))
    assert p.returncode == 2, p.stderr
    assert "--d-over-l0" in p.stderr and "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not out.exists()
    # given as a stitch length, the refusal names the stitch length (the option the user gave)
    p = run("cut", "--stitch-length-mm", "1.5", "--stitches", "4", "--out", str(out))
    assert p.returncode == 2 and p.stderr.startswith("knitlad: error: --stitch-length-mm: "), p.stderr
    assert not out.exists()


@pytest.mark.parametrize("args, where", [(["sweep", "configs/smoke.yaml", "--workers", "two"], "--workers"),
                                         (["cut", "--bogus"], "--bogus")])
def test_a_usage_error_is_one_line(args, where):
    """Click's usage errors took four lines (a usage line, a hint, a box) where every other bad input takes one."""
    p = run(*args, cwd=Path(__file__).resolve().parents[1])
    assert p.returncode == 2 and where in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr


@pytest.mark.process
def test_the_version_and_python_dash_m_knitlad():
    from knitlad import __version__

    for command in ([*KNITLAD, "--version"], [sys.executable, "-m", "knitlad", "--version"]):
        p = subprocess.run(command, capture_output=True, text=True)
        assert p.returncode == 0 and p.stdout.strip() == f"knitlad {__version__}", p.stderr


def test_a_rerun_into_a_used_folder_is_refused_or_replaces_the_whole_earlier_run(tmp_path):
    """A rerun replaced ladder.h5 and left the earlier run's renders, movie and diagrams beside it."""
    out = tmp_path / "run"
    args = ["cut", "--stitches", "4x4", "--lx", "0.36", "--preset", "fast", "--resolution", "16", "--max-time-ms",
            "0.05", "--out", str(out)]
    assert run(*args).returncode == 0
    (out / "render").mkdir()
    (out / "render" / "render_front_0000000.0us.png").write_bytes(b"an earlier run's picture")
    (out / "ladder.gif").write_bytes(b"an earlier run's movie")
    p = run(*args)
    assert p.returncode == 2 and "--overwrite" in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    p = run(*args, "--overwrite")
    assert p.returncode == 0, p.stderr
    assert (out / "ladder.h5").exists() and not (out / "render").exists() and not (out / "ladder.gif").exists()


def test_the_read_out_says_when_f_x_fin_is_no_arrest_value_and_when_v_lad_is_rough():
    """The demo printed an f_x^fin averaged over the ringing after the ladder reached an edge, and a
    v_lad fitted over three stitches, with no caveat."""
    from types import SimpleNamespace

    from knitlad.cli import _fin_caveat, _velocity_caveat

    edge = SimpleNamespace(stop_reason="ladder reached an edge course", v_fit_stitches=(1, 3), nan_reasons=dict)
    arrest = SimpleNamespace(stop_reason="no cell changed for 2.0 ms", v_fit_stitches=(2, 10), nan_reasons=dict)
    short = SimpleNamespace(stop_reason="max_time_s reached", v_fit_stitches=(2, 10),
                            nan_reasons=lambda: {"v_lad_over_cb": "the front ran 1 stitch above the cut, ..."})
    assert "no arrest" in _fin_caveat(edge) and "after the arrest" in _fin_caveat(arrest)
    assert "rough" in _velocity_caveat(edge) and "rough" not in _velocity_caveat(arrest)
    assert _velocity_caveat(short) == "(no velocity: the front ran 1 stitch above the cut, ...)"


def test_a_first_run_says_it_is_compiling(tmp_path):
    """With a fresh Numba cache knitlad cut printed nothing for 94 s."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    proc = subprocess.Popen([*KNITLAD, "cut", "--stitches", "4", "--lx", "0.36", "--preset", "fast", "--out",
                             str(tmp_path / "o")], stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, env=env)
    try:
        first = proc.stderr.readline()
    finally:
        proc.kill()
        proc.wait()
    assert first.startswith("knitlad: compiling the kernels")


def test_replace_validates_as_a_new_config_does():
    """The README taught model_copy(update=...), which took mu = -1 and dt_safety = 5."""
    from pydantic import ValidationError

    from knitlad.experiments.config import CutConfig

    cfg = CutConfig(fx=4, preset="fast")
    assert cfg.replace(mu=0.8).mu == 0.8 and cfg.replace(mu=0.8).resolution == 24
    with pytest.raises(ValidationError, match="mu"):
        cfg.replace(mu=-1.0)


def test_cut_help_groups_its_options_and_keeps_units_and_carries_no_dated_measurement():
    """27 options were one flat list with dated measurements in it; rich read the units in [brackets] as markup."""
    import re

    p = subprocess.run([*KNITLAD, "cut", "--help"], capture_output=True, text=True, env={**os.environ, "COLUMNS": "200"})
    assert p.returncode == 0, p.stderr
    panels = [m.group(1) for m in re.finditer(r"╭─ ([A-Za-z ]+?) ─", p.stdout)]
    assert panels[1:] == ["The experiment", "Run length and output", "Model and numerics"], panels
    experiment = p.stdout[p.stdout.index("The experiment"):p.stdout.index("Run length and output")]
    assert all(f"--{o} " in experiment for o in ("stitches", "preset", "fx", "lx", "ly", "mu"))
    assert "[ms] [default: 30.0]" in p.stdout and "[us]" in p.stdout and "[1/s]" in p.stdout
    assert not re.search(r"20\d\d-\d\d-\d\d", p.stdout)
    # a preset's setting defaults to the chosen preset's value: the help said 0.35 for --dt-safety, which
    # `--preset accurate` runs at 0.7; it names each preset that sets another value
    dt_help = p.stdout[p.stdout.index("--dt-safety"):p.stdout.index("--axial-stiffness-factor")]
    dt_help = " ".join(dt_help.replace("│", " ").split())
    assert "the preset's" in dt_help and "[default: 0.35; accurate: 0.7; crassous2023: 0.7]" in dt_help


@pytest.mark.parametrize("columns", ["80", "150"])
@pytest.mark.process
def test_help_writes_every_flag_out_whole_and_no_undefined_default(columns):
    """At 80 columns `cut --help` cut flag names short (`--contact-damping-r…`), so they could not be copied;
    `cycle --help` showed `[default: PydanticUndefined]` for the required --lx-max."""
    from knitlad.experiments.config import CutConfig, cli_option

    env = {**os.environ, "COLUMNS": columns}
    cut = subprocess.run([*KNITLAD, "cut", "--help"], capture_output=True, text=True, env=env)
    cycle = subprocess.run([*KNITLAD, "cycle", "--help"], capture_output=True, text=True, env=env)
    for name in CutConfig.model_fields:
        if name not in ("n_x", "n_y"):
            assert cli_option(CutConfig, name) in cut.stdout, name
    assert "Undefined" not in cycle.stdout and "[required]" in cycle.stdout


@pytest.mark.end_to_end
def test_a_stitch_that_does_not_converge_fails_instead_of_printing_its_tensions_as_results():
    """`stitch --d-over-l0 1e-9` printed f_x 2.7e6 with `converged: false` and exited 0."""
    p = subprocess.run([*KNITLAD, "stitch", "--d-over-l0", "1e-9", "--preset", "fast", "--resolution", "12",
                        "--lx", "0.35"], capture_output=True, text=True)
    assert p.returncode == 1 and "did not converge" in p.stderr.strip().splitlines()[-1], p.stderr


@pytest.mark.end_to_end
def test_the_stitch_of_a_pattern_is_one_repeat_and_says_which():
    """`stitch --pattern garter`: the cell of a knit and a purl course, its tensions per thread and stitch."""
    p = subprocess.run([*KNITLAD, "stitch", "--pattern", "garter", "--preset", "fast", "--resolution", "16",
                        "--lx", "0.36"], capture_output=True, text=True)
    assert p.returncode == 0 and p.stdout.startswith("periodised garter stitch"), p.stderr
    fx = float(p.stdout.split("f_x = ")[1].split(",")[0])
    assert fx > 0  # in tension at 0.36 (docs/patterns.md: garter's f_x = 0 width is below it)


def test_an_experiment_without_a_command_of_its_own_gets_one_from_its_registry_entry(tmp_path, monkeypatch):
    """A new experiment is a config, a runner and an entry: `knitlad <name>` then takes the config's fields as
    options, runs the entry, writes <name>.h5 and prints the summary; a bad value is one line, exit 2."""
    import h5py
    import typer
    from pydantic import BaseModel, ConfigDict, Field
    from typer.testing import CliRunner

    from knitlad import cli
    from knitlad.io.hdf5 import write_record
    from knitlad.studies import registry

    class ToyConfig(BaseModel):
        model_config = ConfigDict(extra="forbid", frozen=True)
        length: float = Field(1.0, gt=0, description="a length [mm]")

    def run_toy(cfg, output, folder=None, progress=None):
        summary = {"twice": 2 * cfg.length}
        return registry.Finished(None, summary, lambda path, record: write_record(path, {**summary, **record}))

    monkeypatch.setitem(registry.EXPERIMENTS, "toy", registry.Experiment(
        ToyConfig, run_toy, ("twice", "wall_s", "job_wall_s"), "`knitlad toy`: twice a length",
        results={"twice": ("mm", "twice the length")}))
    app = typer.Typer()
    app.command("toy")(cli.experiment_command("toy"))
    app.command("other")(lambda: None)  # two commands, so that the toy is called by its name
    p = CliRunner().invoke(app, ["toy", "--length", "1.5", "--out", str(tmp_path)])
    assert p.exit_code == 0, p.output
    assert "twice = 3.0" in p.output
    with h5py.File(tmp_path / "toy.h5") as f:
        assert f.attrs["twice"] == 3.0
    bad = CliRunner().invoke(app, ["toy", "--length", "-1", "--out", str(tmp_path / "bad")])
    assert bad.exit_code == 2 and "--length" in bad.output and "Traceback" not in bad.output
    again = CliRunner().invoke(app, ["toy", "--out", str(tmp_path)])
    assert again.exit_code == 2 and "earlier toy run" in again.output


@pytest.mark.parametrize("model, size", [("CutConfig", 42), ("CycleConfig", 16), ("SnagConfig", 16)])
def test_without_stitches_a_command_runs_its_configs_size(tmp_path, model, size):
    """The fabric's size has one default, the config's: --stitches left out gives the size Python and sweeps give."""
    from knitlad import cli
    from knitlad.experiments import config

    cfg, _ = cli._knit_run(getattr(config, model), {"lx_max": 0.5} if model == "CycleConfig" else {}, None, 4.0,
                           str(tmp_path / "out"), "x")
    assert (cfg.n_x, cfg.n_y) == (size, size) == (getattr(config, model).model_fields["n_x"].default,) * 2


@pytest.mark.end_to_end
def test_the_diagram_takes_its_cells_options_from_the_config_and_its_widths_per_ly(tmp_path):
    """`knitlad diagram`: the cell's options are DiagramConfig's (a bad one is one line, exit 2), --ly repeats,
    and each l_y gives its f_x = 0 width, narrower for taller cells (the paper's curve falls: 0.33 at 0.25)."""
    import pandas as pd
    from typer.testing import CliRunner

    from knitlad.cli import app

    bad = CliRunner().invoke(app, ["diagram", "--ly", "0.25", "--preset", "bogus", "--out", str(tmp_path)])
    assert bad.exit_code == 2 and "--preset" in bad.output
    ok = CliRunner().invoke(app, ["diagram", "--ly", "0.25", "--ly", "0.27", "--preset", "fast", "--out", str(tmp_path)])
    assert ok.exit_code == 0, ok.output
    curve = pd.read_csv(tmp_path / "fx0_curve.csv")
    assert list(curve.ly_over_l0) == [0.25, 0.27]
    assert 0.30 < curve.lx_over_l0_at_fx0[1] < curve.lx_over_l0_at_fx0[0] < 0.36
