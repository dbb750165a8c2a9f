"""knitlad/studies/columns.py: every column of a sweep's summary has a unit and a meaning."""

import pandas as pd
import pytest

from knitlad.studies.columns import column_dictionary, unit_of
from knitlad.studies.registry import EXPERIMENTS


@pytest.mark.parametrize("scene", list(EXPERIMENTS))
def test_every_column_a_summary_can_have_is_in_the_dictionary_with_a_unit_and_a_meaning(scene):
    """The inputs (the config's fields), the frame's columns and every result the scene's summary keeps."""
    rows = column_dictionary(scene)
    names = [name for name, _, _ in rows]
    assert len(names) == len(set(names)), [n for n in names if names.count(n) > 1]
    expected = {"job_id", "scene", "status", "error", "knitlad_code", "fx_nominal", "ensemble_member",
                "ensemble_point", "same_knit_as",
                *EXPERIMENTS[scene].config.model_fields,
                *EXPERIMENTS[scene].summary_keys}
    assert set(names) == expected
    for name, unit, meaning in rows:
        assert unit and len(meaning) > 10, name


def test_no_result_is_described_that_no_scene_keeps():
    for scene, entry in EXPERIMENTS.items():
        assert set(entry.results) <= set(entry.summary_keys), scene


def test_a_fields_unit_is_read_from_the_brackets_its_description_ends_with():
    assert unit_of("target tension per thread f_x^ini = F_x/(n_y f0) [-] (force control)") == "1"
    assert unit_of("longest laddering time simulated after the cut [ms]") == "ms"
    assert unit_of("no unit given") == "-"


def test_a_ladder_summary_names_its_velocity_fit_by_two_numbers_and_the_sweep_writes_the_dictionary(tmp_path):
    """`v_fit_stitches` was the text "[1, 2]"; the summary holds v_fit_first and v_fit_last, and a sweep writes
    summary_columns.csv beside summary.csv."""
    from knitlad.studies.runner import run_sweep
    from knitlad.studies.sweep import load_sweep
    from tests.studies.test_sweep import TINY, write_config
    from tests.sweep_helpers import fake_runner

    _, jobs = load_sweep(write_config(tmp_path / "c.yaml", {"fixed": {**TINY, "lx": 0.4},
                                                             "sweep": {"axes": {"mu": [0.1, 0.3]}}}))
    run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False)
    table = pd.read_csv(tmp_path / "out" / "summary_columns.csv")
    summary = pd.read_csv(tmp_path / "out" / "summary.csv")
    assert set(summary.columns) <= set(table.column)
    assert {"v_fit_first", "v_fit_last"} <= set(table.column)
