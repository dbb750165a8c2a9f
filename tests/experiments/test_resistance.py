"""knitlad.experiments.resistance: the threshold bracket of a cut series, the config, and the test end to end
(command line and sweep) on a small knit."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pandas as pd
import pytest
import yaml

from knitlad.experiments.config import ResistanceConfig
from knitlad.experiments.resistance import AT_LEAST, GAVE_WAY, HELD, LADDERING_ONSET_CELLS, ResistanceResult

ROOT = Path(__file__).resolve().parents[2]
KNITLAD = [sys.executable, "-m", "knitlad.cli"]
SMALL = ["--stitches", "6x8", "--preset", "fast", "--tensions", "1", "--tensions", "3", "--weak-point-force", "0.1",
         "--max-pull-mm", "4", "--max-time-ms", "2"]


def a_cut(fx: float, cells: int, courses: tuple[int, int] | None = None, reached_edge: bool = False):
    """A cut of ``cells`` undone cells; ``courses``: the lowest and highest course it undid (in column 3 of a
    16 x 16 knit cut at course 8), for the band's verdict."""
    final = None
    if courses is not None:
        final = np.zeros((16, 16), dtype=bool)
        final[courses[0]: courses[1] + 1, 3] = True
    return SimpleNamespace(fx_ini=fx, n_lad=cells, n_lad_over_ny=cells / 8, v_lad_over_cb=0.2, fx_fin_crossed=1.0,
                           fx_fin=1.0 + 0.05 * fx, stop_reason="no cell changed for 1.0 ms", reached_edge=reached_edge,
                           damage_record=lambda: {"n_lad_released_over_ny": cells / 16}, final_laddered=final,
                           cut_row=8)


def a_result(cells: list[int]) -> ResistanceResult:
    tensions = tuple(2.0 * (k + 1) for k in range(len(cells)))
    snag = SimpleNamespace(summary=lambda: {"peak_force_N": 1.0, "broke": False, "pull_at_break_mm": float("nan"),
                                            "n_lad_over_ny": float("nan"), "fx_ini": 4.0}, ladder=None)
    return ResistanceResult({"pattern": "jersey"}, snag, tensions, [a_cut(t, c) for t, c in zip(tensions, cells)])


def test_the_threshold_lies_between_the_highest_tension_that_holds_and_the_lowest_that_ladders():
    """A run ladders from LADDERING_ONSET_CELLS (4.2) cells: 4 cells hold, 5 ladder."""
    assert LADDERING_ONSET_CELLS == pytest.approx(4.2)
    result = a_result([2, 4, 5, 12])
    assert result.laddered() == [False, False, True, True]
    assert result.threshold_bracket() == (4.0, 6.0)
    row = result.summary()
    assert row["fx_thr_below"] == 4.0 and row["fx_thr_above"] == 6.0 and row["monotonic"]
    assert row["n_lad_over_ny_lowest"] == 0.25 and row["n_lad_over_ny_highest"] == 1.5
    assert result.table().shape == (4, 7) and result.table()[2, 3] == pytest.approx(5 / 16)
    # the paper's f_x^thr: the mean f_x^fin of the cuts that laddered (at 6 and 8: 1.3 and 1.4)
    assert row["fx_thr_arrest"] == pytest.approx(1.35) and row["fx_thr_arrest_runs"] == 2


def test_without_a_band_a_design_holds_while_its_cut_undoes_fewer_than_five_whole_cells():
    result = a_result([2, 4, 5, 12])
    result.cuts[3].reached_edge = True
    assert result.verdicts() == [HELD, HELD, GAVE_WAY, AT_LEAST]
    assert result.holds_up_to() == 4.0 and "5 cells or more" in result.rule()
    assert result.summary()["verdicts"] == "2: held; 4: held; 6: gave way; 8: " + AT_LEAST


@pytest.mark.parametrize("band_row, courses, verdict", [
    (11, (8, 10), HELD), (11, (8, 13), GAVE_WAY), (11, (8, 12), HELD),  # above the cut: courses 11-12
    (3, (5, 8), HELD), (3, (2, 8), GAVE_WAY)])  # below it: courses 3-4
def test_a_band_holds_while_no_cell_beyond_it_is_undone(band_row, courses, verdict):
    """A ladder that stops inside the band held; one with a cell past it, seen from the cut, gave way, however
    many cells it undid."""
    snag = SimpleNamespace(summary=lambda: {}, ladder=None)
    result = ResistanceResult({"pattern": "jersey", "band_row": band_row, "band_courses": 2}, snag, (4.0,),
                              [a_cut(4.0, 20, courses)])
    assert result.verdicts() == [verdict] and "crosses the band" in result.rule()


def test_a_series_that_all_ladders_or_none_leaves_one_side_of_the_bracket_open_and_a_dip_is_said():
    assert a_result([6, 9]).threshold_bracket()[0] != a_result([6, 9]).threshold_bracket()[0]  # NaN below
    assert a_result([1, 2]).threshold_bracket()[1] != a_result([1, 2]).threshold_bracket()[1]  # NaN above
    assert not a_result([5, 2, 9]).summary()["monotonic"]


@pytest.mark.parametrize("tensions, match", [([2.0, 2.0], "twice"), ([0.0, 2.0], "tensions"), ([3.0], "at least 2")])
def test_a_bad_series_is_refused(tensions, match):
    with pytest.raises(ValueError, match=match):
        ResistanceConfig(fx=4.0, tensions=tensions)


@pytest.mark.end_to_end
def test_the_command_runs_the_snag_and_the_series_and_writes_its_report(tmp_path):
    """6 x 8, fast preset, a worn spot of 0.1 N: the pin breaks the yarn, the cuts at f_x^ini 1 and 3 run; the
    series, the snag's curve and the pictured ladder are in the file, the report is drawn."""
    p = subprocess.run([*KNITLAD, "resistance", *SMALL, "--out", str(tmp_path), "--json"], capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    row = json.loads(p.stdout.strip().splitlines()[-1])
    assert row["snag_broke"] and row["tensions"] == 2
    table = pd.read_csv(tmp_path / "resistance.csv")
    assert list(table.fx_target) == [1.0, 3.0] and (abs(table.fx_ini - table.fx_target) < 0.06 * table.fx_target).all()
    with h5py.File(tmp_path / "resistance.h5") as f:
        assert f["resistance/tensions"].shape == (2, 7) and f["snag/force"].attrs["unit"] == "N"
        assert "frames/positions" in f and f.attrs["scale_f0_N"] > 0
    assert (tmp_path / "resistance_report.png").stat().st_size > 50_000


@pytest.mark.end_to_end
def test_a_resistance_sweep_writes_each_designs_report(tmp_path):
    """The sweep scene `resistance` (one design): its summary row, its file and its report beside it."""
    config = tmp_path / "resistance.yaml"
    config.write_text(yaml.safe_dump({
        "scene": "resistance", "fixed": {"n_x": 6, "n_y": 8, "preset": "fast", "fx": 3.0, "tensions": [1.0, 3.0],
                                         "weak_point_force": 0.1, "max_pull_mm": 4.0, "max_time_ms": 2.0},
        "sweep": {"expand": "grid", "axes": {"mu": [0.4]}}, "output": {"frames": False}}))
    out = tmp_path / "out"
    p = subprocess.run([*KNITLAD, "sweep", str(config), "--out", str(out)], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    df = pd.read_csv(out / "summary.csv")
    assert (df.status == "ok").all() and df.design_pattern[0] == "jersey" and bool(df.snag_broke[0])
    job = df.job_id[0]
    assert (out / "jobs" / f"{job}_report.png").exists()
    with h5py.File(out / "jobs" / f"{job}.h5") as f:
        assert f["resistance/tensions"].shape == (2, 7)
    p = subprocess.run([*KNITLAD, "sweep", str(config), "--out", str(out)], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0 and "already done" in p.stdout + p.stderr
    again = pd.read_csv(out / "summary.csv")  # the rerun reads the finished job's row back from its file
    for key in ("snag_peak_force_N", "fx_thr_above", "n_lad_over_ny_highest"):
        assert again[key][0] == pytest.approx(df[key][0], rel=1e-9), key
