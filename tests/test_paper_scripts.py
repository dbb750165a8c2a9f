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
