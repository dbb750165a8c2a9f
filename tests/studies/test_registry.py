"""knitlad.studies.registry: each experiment names its config, runner and summary columns once, and its one
entry serves the command line and sweeps."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import pytest

from knitlad.experiments.config import CutConfig
from knitlad.studies.registry import EXPERIMENTS, stretch_of


def test_every_scene_has_a_runner_taking_the_progress_and_distinct_summary_columns():
    for name, scene in EXPERIMENTS.items():
        assert list(inspect.signature(scene.run).parameters)[:4] == ["cfg", "output", "folder", "progress"], name
        assert len(set(scene.summary_keys)) == len(scene.summary_keys), name
        assert "job_wall_s" in scene.summary_keys and scene.description, name


def test_laddering_jobs_share_a_stretch_exactly_when_their_stretch_settings_agree():
    """A sweep over mu (the dynamics) stretches once; another tension or resolution is another knit."""
    base = CutConfig(n_x=6, n_y=8, fx=4.0, mu=0.4)
    assert stretch_of(base) == stretch_of(base.replace(mu=0.0, max_time_ms=3.0))
    assert stretch_of(base) != stretch_of(base.replace(fx=5.0))
    assert stretch_of(base) != stretch_of(base.replace(preset="fast"))


def test_the_command_line_runs_each_experiment_through_its_entry():
    """`knitlad cut`, `cycle`, `tensile`, ... call the registry's runner, as a sweep's job does: cli.py names no
    experiment's own run function and writes no experiment's file itself."""
    import knitlad.cli as cli

    source = Path(cli.__file__).read_text()
    direct = {"run_ladder", "run_protocol_b", "run_tensile", "run_snag", "run_resistance", "run_single_loop",
              "StitchRun", "write_ladder_result", "write_cycle_result", "write_tensile_result", "write_snag_result",
              "write_resistance_result"}
    named = {name for name in direct if re.search(rf"\b{name}\b", source)}
    assert not named, f"cli.py runs or writes these itself: {sorted(named)}"
    for name in ("ladder", "cycle", "tensile", "snag", "resistance", "loop", "stitch", "diagram"):
        assert f'_experiment("{name}"' in source, name


@pytest.mark.end_to_end
def test_a_point_of_the_diagram_is_the_stitchs_zero_tension_width():
    """The diagram's entry (a sweep's job, `knitlad diagram`) gives what zero_tension_lx gives for its settings."""
    from knitlad.experiments.config import DiagramConfig
    from knitlad.fabric.stitch_model import zero_tension_lx
    from knitlad.studies.sweep import Output

    cfg = DiagramConfig(ly=0.25, preset="fast")
    finished = EXPERIMENTS["diagram"].run(cfg, Output())
    s = cfg.settings()
    direct = zero_tension_lx(0.25, resolution=s.resolution, material=s.material,
                             sagitta_radius=s.sagitta_radius)
    assert finished.summary["lx_over_l0_at_fx0"] == direct and 0.25 < direct < 0.40
    assert finished.result.settings.lx == direct


def test_an_entry_whose_results_name_a_column_its_summary_does_not_keep_is_refused_at_once():
    """`knitlad columns` crashed with a KeyError on such an entry; now it cannot be made."""
    from knitlad.studies.registry import Experiment

    with pytest.raises(ValueError, match="results fx_typo are not among its summary_keys"):
        Experiment(CutConfig, lambda *a: None, ("fx_ini",), "`knitlad x`: a test", None,
                   {"fx_ini": ("f0", "the tension"), "fx_typo": ("f0", "a result no summary keeps")})
