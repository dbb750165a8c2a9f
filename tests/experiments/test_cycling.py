"""Protocol B (knitlad.experiments.cycling): the cycles, delta l, the cut of a cycled knit, `knitlad cycle`."""

from __future__ import annotations

import math

import numpy as np
import pytest

from knitlad.experiments.config import CycleConfig
from knitlad.experiments.cycling import HOLD, LOADING, UNLOADING, cut_cycled, run_cycles, shortening_to
from knitlad.experiments.laddering import cut
from knitlad.fabric.preparation import stretch


def test_delta_l_is_read_between_readings_where_the_unloading_crosses_the_threshold():
    unloading = np.array([[0.40, 9.0], [0.39, 6.0], [0.38, 3.0], [0.37, 1.0]])  # box l_x/l0, f_x
    # f_x = 4 lies 2/3 of the way from 0.39 to 0.38: l_x 0.38333; 10 columns: 10 x 0.01667 l0
    assert shortening_to(unloading, 4.0, n_x=10) == pytest.approx(10 * (0.40 - (0.39 - 0.01 * 2 / 3)))
    assert math.isnan(shortening_to(unloading, 0.5, n_x=10))  # never reached
    assert math.isnan(shortening_to(unloading, 10.0, n_x=10))  # already below at the start


def cycle_config(**changes):
    return CycleConfig(**{"n_x": 6, "n_y": 8, "fx": 0.68, "lx_max": 0.36, "preset": "fast", "cycles": 2,
                          "readings_per_leg": 4, "bar_speed": 0.1, "fx_thr": 2.0, **changes})


@pytest.fixture(scope="module")
def cycled():
    """A 6 x 8 knit cycled twice; at Delta x_max of the second cycle a copy is cut, friction history and all."""
    cfg = cycle_config()
    knit = stretch(cfg.stretch_settings())
    seen = {}

    def at_the_cut(snapshot, sim):
        seen["snapshot"], seen["loaded_slip"] = snapshot, sim.contacts.slip[:sim.contacts.n_pairs[0]].copy()
        seen["loaded_pairs"] = sim.contacts.pairs[:sim.contacts.n_pairs[0]].copy()
        seen["run"] = cut_cycled(snapshot, sim, cfg.dynamics_settings())
        forgetful = cut(snapshot, cfg.dynamics_settings(), rods_ready=True)  # the same cut, springs lost
        forgetful.sim.compute_forces()
        away = (snapshot.knit.node_course() != snapshot.settings.n_y // 2) & ~sim.model.held
        seen["force_off_cut"] = [np.linalg.norm(r.sim.forces_N()[away], axis=1).max() for r in (seen["run"], forgetful)]

    seen["checkpoints"] = []
    result = run_cycles(knit, cfg.cycle_settings(), cfg.dynamics_settings(), at_the_cut=at_the_cut,
                        keep=seen["checkpoints"].append)
    return cfg, knit, result, seen


@pytest.mark.slow
def test_the_cycles_collapse_onto_one_loop_from_the_first_retraction(cycled):
    """The paper's observation (Fig. 4a): the first loading, from the knit stretched at mu = 0, differs; the
    unloadings of both cycles agree within 3 % where f_x > 1, as do the holds at Delta x_max."""
    cfg, knit, result, _ = cycled
    first, second = result.leg(1, UNLOADING), result.leg(2, UNLOADING)
    np.testing.assert_allclose(first[:, 0], second[:, 0])
    loaded = first[:, 1] > 1.0
    np.testing.assert_allclose(second[loaded, 1], first[loaded, 1], rtol=0.03)
    holds = result.readings[result.readings[:, 1] == HOLD]
    assert holds[2, 4] == pytest.approx(holds[1, 4], rel=0.01)  # cycles 1 and 2 at Delta x_max
    # friction: the loadings lie above the unloadings (a hysteresis loop), the first loading highest
    assert np.all(result.leg(2, LOADING)[:-1, 1] > second[::-1][1:, 1])
    assert result.leg(1, LOADING)[0, 1] > 1.1 * result.leg(2, LOADING)[0, 1]
    assert result.hold_converged and result.fx_ini > cfg.fx_thr
    # delta l and Eq. 1's prediction from the twin's last unloading
    assert 0 < result.delta_l_over_l0 < cfg.n_x * (cfg.lx_max - knit.box_lx)
    assert result.predicted_damage == pytest.approx(result.delta_l_over_l0 / (1 - result.lx_over_l0))


@pytest.mark.slow
def test_a_cycled_knit_is_cut_with_the_friction_history_its_loading_left(cycled):
    """Every pair of the loaded knit but the cut edge's is in the cut run's contacts with its spring (to 1e-4:
    the first evaluation after the cut advances each spring by its slip over one step, the settled knit's
    residual speed times dt)."""
    _, _, result, seen = cycled
    run, snapshot = seen["run"], seen["snapshot"]
    assert snapshot.fx_ini == pytest.approx(result.fx_ini) and snapshot.box_lx == pytest.approx(0.36)
    c = run.sim.contacts
    carried = {tuple(p): s for p, s in zip(c.pairs[:c.n_pairs[0]], c.slip[:c.n_pairs[0]])}
    shift = lambda e: e - (e > run.cut_edge)  # noqa: E731 - edges above the cut move down by one
    springs = [(tuple(shift(p)), s) for p, s in zip(seen["loaded_pairs"], seen["loaded_slip"])
               if run.cut_edge not in p and np.any(s)]
    assert len(springs) > 50
    for pair, slip in springs:
        if pair in carried:  # still a candidate after the cut's rebuild
            np.testing.assert_allclose(carried[pair], slip, atol=1e-4 * np.abs(slip).max())
    assert sum(pair in carried for pair, _ in springs) > 0.9 * len(springs)
    # the point of it: off the cut course the knit is as static as the hold left it (within twice the hold's
    # tolerance, 1e-3 f0); with the springs lost, friction lets go at once (2026-12-04: 0.013 mN against 35 mN)
    f0 = snapshot.settings.material.f0
    kept, lost = seen["force_off_cut"]
    assert kept < 2e-3 * f0 and lost > 100 * kept


def test_cycle_settings_are_checked_before_anything_runs():
    with pytest.raises(ValueError, match="lx_max"):
        cycle_config(fx=None, lx=0.38, lx_max=0.36)
    with pytest.raises(ValueError, match="lx_max"):
        CycleConfig(n_x=6, n_y=8, fx=0.68)
    with pytest.raises(ValueError, match="bar_speed"):
        cycle_config(bar_speed=0)


@pytest.mark.slow
def test_the_cycle_does_not_depend_on_the_bars_speed():
    """Halving the bars' speed (0.1 to 0.05 m/s) changes f_x^ini by < 0.2 % and delta l by < 0.5 %
    (2026-12-04: 0.06 % and 0.24 % between 0.1 and 0.025 m/s, 6 x 8, fast preset)."""
    cfg = cycle_config(lx_max=0.39, readings_per_leg=10, fx_thr=1.0)
    knit = stretch(cfg.stretch_settings())
    fast, slow = (run_cycles(knit, cfg.replace(bar_speed=v).cycle_settings(), cfg.dynamics_settings())
                  for v in (0.1, 0.05))
    assert slow.fx_ini == pytest.approx(fast.fx_ini, rel=2e-3)
    assert slow.delta_l_over_l0 == pytest.approx(fast.delta_l_over_l0, rel=5e-3)


def test_a_sweep_of_protocol_b_plots_its_damage_against_eq_1(tmp_path):
    import pandas as pd

    from knitlad.viz.plots import summary_plots

    table = pd.DataFrame({"status": ["ok", "ok", "failed"], "scene": ["cycle"] * 3, "ly": [0.25, 0.3, 0.3],
                          "predicted_damage": [0.5, 1.2, np.nan], "cut_n_lad_over_ny": [0.6, 1.0, np.nan],
                          "cut_reached_edge": [False, True, False], "fx_ini": [3.0, 6.0, np.nan]})
    paths = summary_plots(table, tmp_path)
    assert [p.name for p in paths] == ["damage_vs_prediction.png"] and paths[0].stat().st_size > 1000


def test_the_final_tension_plot_draws_the_three_readings_of_the_arrest(tmp_path):
    import pandas as pd

    from knitlad.viz.plots import final_tension_plot

    table = pd.DataFrame({"fx_ini": [2.0, 6.0], "fx_fin": [1.8, 4.0], "fx_fin_crossed": [1.5, 2.5],
                          "fx_fin_intact": [1.9, 5.0]})
    assert final_tension_plot(table, tmp_path / "f.png").stat().st_size > 1000


def test_an_unreached_threshold_says_why_delta_l_is_nan():
    """`cycle` printed "delta l = nan" when the unloading never reached --fx-thr."""
    import math

    import numpy as np

    from knitlad.experiments.cycling import CycleResult, CycleSettings

    s = CycleSettings(lx_max=0.4, cycles=1, bar_speed=0.25, cycle_damping_per_s=2e4, readings_per_leg=2, hold_s=1e-3,
                      hold_tol_f0=1e-3, fx_thr=0.5, cut=False)
    readings = np.array([[0, 0, 0.0, 0.35, 1.0], [1, 1, 0.1, 0.40, 9.0], [1, 0, 0.2, 0.40, 8.5],
                         [1, -1, 0.3, 0.37, 4.0], [1, -1, 0.4, 0.35, 1.2]])
    result = CycleResult(settings=s, n_x=6, lx_min=0.35, readings=readings, lx_over_l0=0.39)
    assert math.isnan(result.predicted_damage)
    assert "never fell to f_x^thr = 0.5 (its lowest f_x: 1.200)" in result.summary()["nan_reasons"]
    assert "delta_l_over_l0" not in CycleResult(settings=s, n_x=6, lx_min=0.35, readings=readings,
                                                delta_l_over_l0=0.1, lx_over_l0=0.39).nan_reasons()
    assert "no cut copy" in result.nan_reasons()["predicted_damage_own"]


def test_eq1_is_also_read_at_the_runs_own_post_arrest_tension():
    """The paper's f_thr is the tension at the bars after the ladder stopped: delta l read down to the cut
    copy's f_x^fin, on the same unloading (from the hold at Delta x_max) as the fixed threshold."""
    from knitlad.experiments.cycling import CycleResult, CycleSettings

    s = CycleSettings(lx_max=0.4, cycles=1, bar_speed=0.25, cycle_damping_per_s=2e4, readings_per_leg=2, hold_s=1e-3,
                      hold_tol_f0=1e-3, fx_thr=2.0, cut=False)
    readings = np.array([[0, 0, 0.0, 0.35, 1.0], [1, 1, 0.1, 0.40, 9.0], [1, 0, 0.2, 0.40, 8.0],
                         [1, -1, 0.3, 0.38, 4.0], [1, -1, 0.4, 0.36, 0.0]])
    result = CycleResult(settings=s, n_x=10, lx_min=0.35, readings=readings, lx_over_l0=0.39)
    # from (0.40, 8) to (0.38, 4): f_x 6 halfway, at 0.39; from (0.38, 4) to (0.36, 0): f_x 2 halfway, at 0.37
    assert result.shortening_at(6.0) == pytest.approx(10 * 0.01)
    assert result.shortening_at(2.0) == pytest.approx(10 * 0.03)
    result.fx_thr_own, result.delta_l_own_over_l0 = 6.0, result.shortening_at(6.0)
    assert result.predicted_damage_own == pytest.approx(0.1 / 0.61)
    assert result.summary()["fx_thr_own"] == 6.0 and "predicted_damage_own" not in result.nan_reasons()


@pytest.mark.slow
def test_protocol_b_resumed_from_a_checkpoint_file_reads_the_same_curve_to_the_bit(cycled, tmp_path):
    """A run stopped after a leg (Ctrl-C, a killed job) goes on from its last checkpoint: after the first cycle's
    return, and after the last hold at Delta x_max (before the cut, which is then made again)."""
    from knitlad.experiments.cycling import LOADED, UNLOADED
    from knitlad.io.hdf5 import read_arrays, write_arrays

    cfg, knit, result, seen = cycled
    phases = [tuple(c["cycle/done"]) for c in seen["checkpoints"]]
    assert phases == [(1, LOADED), (1, UNLOADED), (2, LOADED)]  # none after the last cut
    for checkpoint in seen["checkpoints"][1:]:
        arrays, _ = read_arrays(write_arrays(tmp_path / "checkpoint.h5", checkpoint))
        cut_again = []
        resumed = run_cycles(knit, cfg.cycle_settings(), cfg.dynamics_settings(), resume=arrays,
                             at_the_cut=lambda snapshot, sim: cut_again.append(snapshot.fx_ini))
        assert np.array_equal(resumed.readings, result.readings)
        assert resumed.delta_l_over_l0 == result.delta_l_over_l0 and resumed.fx_ini == result.fx_ini
        assert cut_again == [result.fx_ini]
