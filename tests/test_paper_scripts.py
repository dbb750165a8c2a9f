"""The analysis scripts of docs/ (``scripts/paper/``) on synthetic tables whose answer is known."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from tests.script_loading import load_script


def paper_script(name: str):
    return load_script("scripts/paper", name)


def test_the_paired_step_study_pairs_each_knit_with_itself_at_the_reference_factor():
    """Three knits per tension, targets 0.5 % apart: the change is taken knit by knit, so a knit-to-knit
    spread that every factor shares cancels and only the factor's own change remains."""
    study = paper_script("paired_step_factor")
    rows = []
    for nominal in (4.0, 13.6):
        for k, offset in enumerate((-0.005, 0.0, 0.005)):
            knit = 1.0 + 0.2 * k  # a 20 % spread between knits, the same at every factor
            for factor, change in ((0.175, 1.0), (0.35, 1.0), (0.7, 1.0 + 0.01 * (k + 1))):
                rows.append({"fx": nominal * (1 + offset), "dt_safety": factor, "status": "ok", "fx_ini": nominal,
                             "steps": 1000 / factor, "wall_propagate_s": 1.0, "v_lad_over_cb": 0.5 * knit * change,
                             "n_lad_over_ny": knit, "fx_fin": 2.0 * knit})
    rows.append({**rows[0], "dt_safety": 0.7, "status": "failed"})  # a failed run is left out
    table = study.paired_changes(pd.DataFrame(rows)).set_index(["fx_nominal", "dt_safety"])
    assert sorted(table.index.get_level_values(0).unique()) == [4.0, 13.6]
    row = table.loc[(4.0, 0.7)]
    assert row.knits == 3 and row.reference == 0.175
    assert row.v_lad_over_cb_change_pct == pytest.approx(2.0)  # +1, +2, +3 %
    assert row.v_lad_over_cb_change_se == pytest.approx(1.0 / np.sqrt(3))
    assert row.n_lad_over_ny_change_pct == pytest.approx(0.0) and row.fx_fin_change_pct == pytest.approx(0.0)
    against_035 = study.paired_changes(pd.DataFrame(rows), reference=0.35).set_index(["fx_nominal", "dt_safety"])
    assert against_035.loc[(13.6, 0.175)].v_lad_over_cb_change_pct == pytest.approx(0.0)
    assert "| 4.00 | 0.7 | 3 |" in study.markdown(study.paired_changes(pd.DataFrame(rows)))
    held = pd.DataFrame(rows).rename(columns={"dt_safety": "friction_every"})  # another factor, the same pairing
    by_friction = study.paired_changes(held, factor="friction_every").set_index(["fx_nominal", "friction_every"])
    assert by_friction.loc[(4.0, 0.7)].v_lad_over_cb_change_pct == pytest.approx(2.0)
    words = pd.DataFrame(rows).replace({"dt_safety": {0.175: "held", 0.7: "sliding"}})  # a factor of words
    words = words[words["dt_safety"] != 0.35].rename(columns={"dt_safety": "bars"})
    by_bars = study.paired_changes(words, reference="held", factor="bars")
    assert "| 4.00 | sliding | 3 |" in study.markdown(by_bars, "bars")


def test_the_run_stop_band_table_says_whether_a_ladder_entered_and_crossed_the_band(tmp_path):
    """Two synthetic jobs on 16 courses, band 11-12, cut at 8: one ladder stops at 10 (below the band), one
    runs to 14 (across it); the table reads the reach from each file's final map."""
    import h5py

    study = paper_script("run_stop_band")
    (tmp_path / "jobs").mkdir()
    rows = []
    for job, top in (("a", 10), ("b", 14)):
        laddered = np.zeros((16, 16), dtype=bool)
        laddered[6:top + 1, 8] = True
        with h5py.File(tmp_path / "jobs" / f"{job}.h5", "w") as f:
            f["final/laddered"] = laddered
        rows.append({"job_id": job, "fx": 4.0, "fx_ini": 4.0, "band_row": 11, "band_courses": 2, "mu": 0.4,
                     "band_friction_factor": 2.0 if job == "a" else 1.0, "n_lad_over_ny": (top - 5) / 16,
                     "fx_fin": 2.0, "v_lad_over_cb": 0.3, "stop_reason": "arrested"})
    pd.DataFrame(rows).to_csv(tmp_path / "summary.csv", index=False)
    table = study.table(tmp_path).set_index("job_id")
    assert table.loc["a", "top_course"] == 10 and not table.loc["a", "entered_band"]
    assert table.loc["b", "top_course"] == 14 and table.loc["b", "crossed_band"]
    assert table.loc["a", "bottom_course"] == 6 and table.loc["a", "mu_band"] == pytest.approx(0.8)
    points = study.by_point(table.reset_index()).set_index("band")
    assert points.loc["friction x2", "crossed"] == 0 and points.loc["friction x1", "crossed"] == 1
    assert points.loc["friction x1", "knits"] == 1


@pytest.mark.parametrize("band, kind", [("rib", "rib"), ("curvature", "curvature K3")])
def test_the_run_stop_band_table_reads_a_knitted_band_beside_the_plain_knit(tmp_path, band, kind):
    """A rib band or a band of a yarn with memory (K 3; courses 11-12) that holds the ladder at 10 and the
    plain knit (no band_row) whose ladder runs to 14: the plain knit is read where the band would be."""
    import h5py

    study = paper_script("run_stop_band")
    (tmp_path / "jobs").mkdir()
    rows = []
    for job, top, band, row in (("rib", 10, band, 11), ("plain", 14, "friction", None)):
        laddered = np.zeros((16, 16), dtype=bool)
        laddered[6:top + 1, 8] = True
        with h5py.File(tmp_path / "jobs" / f"{job}.h5", "w") as f:
            f["final/laddered"] = laddered
        rows.append({"job_id": job, "fx": 4.0, "fx_ini": 4.0, "band": band, "band_row": row, "band_courses": 2,
                     "mu": 0.4, "band_friction_factor": 2.0, "band_curvature": 3.0, "n_lad_over_ny": (top - 5) / 16,
                     "fx_fin": 2.0,
                     "v_lad_over_cb": 0.3, "stop_reason": "arrested"})
    pd.DataFrame(rows).to_csv(tmp_path / "summary.csv", index=False)
    table = study.table(tmp_path).set_index("job_id")
    assert table.loc["rib", "kind"] == kind and table.loc["rib", "mu_band"] == pytest.approx(0.4)
    assert table.loc["plain", "kind"] == "none" and table.loc["plain", "band"] == "11-12"
    assert not table.loc["rib", "crossed_band"] and table.loc["plain", "crossed_band"]


def test_the_loose_to_jammed_table_averages_each_points_knits_and_counts_its_failures_apart():
    study = paper_script("loose_to_jammed")
    rows = []
    for d, share in ((1 / 70, 4.0), (1 / 40, 8.0)):
        for k, fx in enumerate((3.99, 4.01)):
            rows.append({"d_over_l0": d, "fx_nominal": 4.0, "status": "ok", "fx_ini": fx, "lx_over_l0": 0.36,
                         "lx0_over_l0": 0.33,
                         "lx_over_lx0": 1.1, "n_lad_over_ny": 1.0 + 0.5 * k,
                         "released_over_ny": 0.5, "v_lad_over_cb": 0.3, "fx_fin_crossed": 2.0, "reached_edge": k == 1})
    rows.append({"d_over_l0": 1 / 25, "fx_nominal": 4.0, "status": "failed", "error": "OutOfReach"})
    points = study.by_point(pd.DataFrame(rows)).set_index("l0_over_d")
    assert list(points.index) == pytest.approx([70, 40, 25])  # loose to jammed
    assert points.loc[70, "n_lad_over_ny"] == pytest.approx(1.25) and points.loc[70, "n_lad_over_ny_se"] == pytest.approx(0.25)
    assert points.loc[70, "edge"] == 1
    assert points.loc[25, "knits"] == 0 and points.loc[25, "failed"] == 1
    assert "| 25 | - | 0 (1) |" in study.markdown(points.reset_index())


def test_the_threshold_bracket_per_thickness_needs_every_knit_to_agree():
    """Held: no knit undid 4.2 cells or more; laddered: every knit did; a point whose knits disagree brackets
    nothing (the bracket then spans it)."""
    study = paper_script("loose_to_jammed")
    cells = {(1 / 50, 5.0): (4, 4), (1 / 50, 6.0): (8, 9), (1 / 40, 4.0): (3, 4), (1 / 40, 5.0): (4, 7),
             (1 / 40, 6.0): (8, 8)}
    rows = [{"d_over_l0": d, "fx_nominal": fx, "status": "ok", "n_lad": n}
            for (d, fx), ns in cells.items() for n in ns]
    brackets = study.thresholds(pd.DataFrame(rows)).set_index("l0_over_d")
    assert (brackets.loc[50, "held_up_to"], brackets.loc[50, "laddered_from"]) == (5.0, 6.0)
    assert (brackets.loc[40, "held_up_to"], brackets.loc[40, "laddered_from"]) == (4.0, 6.0)
    assert brackets.loc[40, "cells_per_knit"] == "4: 3, 4; 5: 4, 7; 6: 8, 8"


def test_a_patterns_unloaded_width_is_where_its_loading_curve_turns_positive():
    study = paper_script("pattern_curves")
    curve = pd.DataFrame({"box_lx": [0.30, 0.31, 0.32, 0.33], "fx": [-2.0, -1.0, 1.0, 3.0]})
    assert study.zero_crossing(curve) == pytest.approx(0.315)
    assert np.isnan(study.zero_crossing(curve.assign(fx=[1.0, 2.0, 3.0, 4.0])))  # in tension from the build


def test_a_periodised_patterns_unloaded_width_is_where_its_curve_turns_positive():
    study = paper_script("pattern_stitch_curves")
    curve = pd.DataFrame({"lx_over_l0": [0.16, 0.18, 0.20, 0.22], "fx": [-2.0, -1.0, 1.0, 3.0]})
    assert study.zero_width(curve) == pytest.approx(0.19)
    assert np.isnan(study.zero_width(curve.assign(fx=[-1.0, -1.0, -1.0, -1.0])))  # never in tension


def test_the_tensile_stretch_at_a_tension_is_read_on_the_loading_from_the_start():
    study = paper_script("tensile_patterns")
    # leg, t, box l_x, box l_y, l_x, l_y, f_x, f_y: loading 0.20 -> 0.30, then unloading
    r = np.array([[1, 0, 0.20, 0.25, 0, 0, 1.0, 0], [1, 0, 0.25, 0.25, 0, 0, 3.0, 0],
                  [1, 0, 0.30, 0.25, 0, 0, 5.0, 0], [-1, 0, 0.25, 0.25, 0, 0, 4.5, 0]])
    assert study.stretch_at(r, 4.0) == pytest.approx(0.275 / 0.20 - 1)  # not the unloading's 4.5 at 0.25
    assert study.stretch_at(r, 0.5) == 0.0 and np.isnan(study.stretch_at(r, 6.0))


def test_the_eq1_ensemble_takes_each_protocols_knits_together():
    """Three knits of one protocol (and one of another): each count of the damage over Eq. 1 at the run's own
    arrest tension, mean and standard error over the knits of a group."""
    study = paper_script("damage_prediction")
    rows = [{"n_y": 16, "ly": 0.25, "lx_max": 0.36, "bar_speed": 0.5, "fx_fin_crossed": f, "predicted_own": 0.5,
             "n_lad_over_ny": 1.0, "released_over_ny": r, "released_taut_over_ny": 0.25}
            for f, r in ((1.0, 0.4), (1.1, 0.5), (1.2, 0.6))]
    rows.append({**rows[0], "lx_max": 0.38})
    table = study.ensemble_table(pd.DataFrame(rows)).set_index("lx_max")
    assert table.loc[0.36].knits == 3 and table.loc[0.38].knits == 1
    assert table.loc[0.36].released_over_eq1 == pytest.approx(1.0)  # 0.4, 0.5, 0.6 over 0.5
    assert table.loc[0.36].released_over_eq1_se == pytest.approx(0.2 / np.sqrt(3))
    assert table.loc[0.36].taut_over_eq1 == pytest.approx(0.5) and table.loc[0.36].taut_over_eq1_se == 0
    assert np.isnan(table.loc[0.38].fx_fin_crossed_se)


def test_the_drag_ceiling_is_the_largest_lambda_whose_frictionless_change_stays_within_ten_per_cent():
    """Paired against lambda = 0 at each tension; the worst tension decides; the crossing interpolated linearly;
    the mu = 0.4 rows do not enter; a failed run is left out."""
    study = paper_script("authors_drag")
    rows = []
    for fx, slope in ((4.0, 0.5), (13.6, 1.0)):  # the change: -slope x lambda / 1e-3 x 100 %
        for lam in (0.0, 1e-4, 3e-4, 1e-3):
            rows.append({"mu": 0.0, "fx": fx, "drag_lambda": lam, "status": "ok",
                         "v_lad_over_cb": np.sqrt(fx) * (1 - slope * lam / 1e-3)})
            rows.append({**rows[-1], "mu": 0.4, "v_lad_over_cb": 0.01})
    rows.append({**rows[0], "drag_lambda": 2e-4, "status": "failed", "v_lad_over_cb": 0.0})
    changes = study.drag_changes(pd.DataFrame(rows))
    assert len(changes) == 8 and changes.change.max() == 0.0
    assert changes.set_index(["fx", "drag_lambda"]).change[(13.6, 3e-4)] == pytest.approx(-0.3)
    largest, reached = study.ceiling(changes)
    assert largest == 1e-4 and reached == pytest.approx(1e-4)  # -10 % exactly at 1e-4 at f_x 13.6
    softer = study.drag_changes(pd.DataFrame([{**r, "v_lad_over_cb": r["v_lad_over_cb"] ** 0.5} for r in rows]))
    assert study.ceiling(softer)[0] == 1e-4 and 1e-4 < study.ceiling(softer)[1] < 3e-4
    der = study.der_points(pd.DataFrame([{"fx": f, "drag_lambda": 1e-4, "status": "ok", "v_lad_over_cb": v}
                                         for f, v in ((1.572, 0.2), (1.58, 0.22), (15.67, 1.05))]))
    low = der.set_index("point").loc[1.58]
    assert low["count"] == 2 and low["mean"] == pytest.approx(0.21) and low.ratio == pytest.approx(0.21 / 0.176)


def test_the_run_stop_pictures_say_what_each_panel_varies():
    study = paper_script("run_stop_band")
    assert study.panel_label("friction x3") == "band friction 3 x the fabric's mu"
    assert study.panel_label("friction x1") == study.panel_label("none") == "no band (the plain knit)"
    assert study.panel_label("rib") == "band: rib"


def test_the_readme_pictures_script_reads_the_readmes_own_demo_command():
    """It remakes the README's pictures from the README's command: it must find the README (it once looked for it
    one folder too deep, after it moved under scripts/paper/)."""
    command = paper_script("readme_pictures").readme_demo_command()  # the options after `knitlad cut`
    assert "--stitches" in command and "--out" in command
