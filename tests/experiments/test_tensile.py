"""The fabric's tensile test (knitlad.experiments.tensile): against the periodised stitch at mu = 0, friction's
loop, the coupling of the two directions, `knitlad tensile`."""

from __future__ import annotations

import numpy as np
import pytest

from knitlad.experiments.config import TensileConfig
from knitlad.experiments.tensile import run_tensile
from knitlad.fabric.preparation import stitch_of, stretch
from knitlad.fabric.stretching import stretch_to


def config(**changes) -> TensileConfig:
    return TensileConfig(**{"n_x": 6, "n_y": 8, "preset": "fast", "lx": 0.36, "lx_max": 0.38, "readings_per_leg": 3,
                            **changes})


@pytest.fixture(scope="module")
def pulled():
    """One 6 x 8 knit stretched at mu = 0 to l_x/l0 0.36, pulled to 0.38 and back at mu = 0 and 0.4."""
    knit = stretch(config().stretch_settings())
    return knit, {mu: run_tensile(knit, config(mu=mu).tensile_settings(), config(mu=mu).dynamics_settings())
                  for mu in (0.0, 0.4)}


@pytest.mark.slow
def test_at_mu_0_the_knit_pulled_carries_the_periodised_stitchs_tension(pulled):
    """At the top, held until static, the knit's f_x is the periodised stitch's at the knit's own (l_x, l_y)
    within 5 % (its edges: +4 % measured on 6 columns); its f_y lies above the stitch's by the pull the
    course ends' clamps add (they hold y too) and within 25 % (+17 % on 6 columns)."""
    knit, runs = pulled
    top = runs[0.0].readings[runs[0.0].readings[:, 0] == 0][0]
    cell = stitch_of(knit.settings, top[4])
    stretch_to(cell, top[4], top[5], knit.settings.stretch_increment)
    cell.settle()
    fx, fy = cell.tensions()
    assert top[6] == pytest.approx(fx, rel=0.05)
    assert fy < top[7] < 1.25 * fy


@pytest.mark.slow
def test_friction_opens_a_loop_that_mu_0_does_not(pulled):
    """At mu = 0.4 the unloading lies below the loading at every box between the ends and the closed path
    costs work (f0 l0 per stitch); at mu = 0 only the damping of the moving bars takes any (its bias alpha M V
    on the readings, in proportion to the bars' speed: 0.8 % of friction's at 0.25 m/s, 6 % at 0.5), under
    5 % of that at the default speed."""
    _, runs = pulled
    r = runs[0.4].readings
    loading, unloading = r[r[:, 0] == 1], r[r[:, 0] == -1]
    inner = loading[1:-1]
    for row in inner:
        below = unloading[np.isclose(unloading[:, 2], row[2])]
        assert below.size and below[0, 6] < row[6]
    work = runs[0.4].dissipated_per_stitch
    assert work > 0
    assert abs(runs[0.0].dissipated_per_stitch) < 0.05 * work


@pytest.mark.slow
def test_pulled_along_x_between_held_bars_the_courses_draw_together_and_pull_on_the_bars(pulled):
    """The Poisson coupling at fixed bars: the knit's own l_y falls inside its box and f_y rises with f_x."""
    _, runs = pulled
    s = runs[0.0].summary()
    assert s["ly_top_over_l0"] < 0.25 - 1e-3
    assert s["coupling"] > 0.5 and s["fy_top"] > s["fy_start"]


def test_the_box_must_move():
    with pytest.raises(ValueError, match="lx_max"):
        config(lx_max=None)


def test_sliding_bars_are_pulled_along_x_only():
    """A bar whose yarn slides along x cannot be moved along y by its end nodes: refused, naming ly_max."""
    with pytest.raises(ValueError, match="ly_max"):
        config(bars="sliding", lx_max=None, ly_max=0.3)
    assert config(bars="sliding").bars == "sliding"


@pytest.mark.slow
def test_a_moving_box_carries_the_continuous_edges_clips_with_its_sides():
    """The tensile test on the experiment's boundary (edge continuous, bars sliding), at mu 0: the box pulled
    from l_x/l0 0.36 to 0.38 carries each turning loop's clip across its rail as its side moves, to
    round-off (along the rail, y, the clip slides), and the knit's f_x rises with the pull, as with clamped
    course ends. Protocol B accepts the edge too."""
    from knitlad.experiments.config import CycleConfig
    from knitlad.experiments.cycling import LoadedKnit

    cfg = config(edge="continuous", bars="sliding", mu=0.0)
    knit = stretch(cfg.stretch_settings())
    loaded = LoadedKnit(knit, cfg.tensile_settings(), cfg.dynamics_settings())
    model, x = loaded.sim.model, loaded.sim.state.x
    clips = model.rail_node[np.abs(model.rail_axis[:, 1]) == 1.0]
    assert clips.size == 7
    side = np.abs(x[loaded.held, 0]).max()
    before, f_before = x[clips].copy(), loaded.tension()
    loaded.move_box(0.38, loaded.ly)
    moved = x[clips] - before
    np.testing.assert_allclose(moved[:, 0], np.sign(before[:, 0]) * side * (0.38 / 0.36 - 1.0), rtol=1e-9)
    assert np.all(moved[:, 2] == 0.0) and np.all(loaded.sim.state.v[clips][:, [0, 2]] == 0.0)
    assert loaded.tension() > 1.2 * f_before
    assert CycleConfig(fx=0.68, lx_max=0.38, edge="continuous").edge == "continuous"




def synthetic(loading: np.ndarray, unloading: np.ndarray, lx=(0.36, 0.38), n_x=6, n_y=8, cycles=1):
    """A TensileResult of readings made by hand: f_x along the box's l_x, up on ``loading``, back on ``unloading``."""
    import knitlad as kl
    from knitlad.experiments.tensile import HOLD, LOADING, UNLOADING, TensileResult, TensileSettings

    up = np.linspace(*lx, len(loading))
    rows = []
    for c in range(cycles):
        rows += [(LOADING, 0.0, x, 0.25, x, 0.25, f, 0.0) for x, f in zip(up, loading)]
        rows += [(HOLD, 0.0, up[-1], 0.25, up[-1], 0.25, loading[-1], 0.0)]
        rows += [(UNLOADING, 0.0, x, 0.25, x, 0.25, f, 0.0) for x, f in zip(up[::-1][1:], unloading[::-1][1:])]
    settings = TensileSettings(lx[1], None, True, 0.25, 0.0, len(loading) - 1, 1e-3, 1e-3, cycles=cycles)
    return TensileResult(settings, kl.NYLON, n_x, n_y, np.array(rows, dtype=float))


def test_a_testers_figures_are_the_papers_readings_in_newtons_and_millimetres():
    """A linear knit, f_x = 2 + 100 (l_x/l0 - 0.36) up and down the same line: the gauge is n_x l_x, the strip
    n_y l_y wide, F = f_x n_y f0, the strain (l_x - l_x0)/l_x0, the modulus the line's slope in those units, and no
    hysteresis."""
    import knitlad as kl

    lx = np.linspace(0.36, 0.38, 5)
    f = 2 + 100 * (lx - 0.36)
    r = synthetic(f, f)
    (row,) = r.tester_results()
    l0_mm, f0 = kl.NYLON.stitch_length * 1e3, kl.NYLON.f0
    assert row["gauge_length_mm"] == pytest.approx(6 * 0.36 * l0_mm)
    assert row["width_mm"] == pytest.approx(8 * 0.25 * l0_mm)
    assert row["peak_force_N"] == pytest.approx(f[-1] * 8 * f0)
    assert row["extension_at_peak_pct"] == pytest.approx(100 * 0.02 / 0.36)
    per_5cm = 50 / row["width_mm"]
    assert row["initial_modulus_N_per_5cm"] == pytest.approx(100 * 0.36 * 8 * f0 * per_5cm)
    assert row["hysteresis_energy_mJ"] == pytest.approx(0, abs=1e-12)


def test_the_hysteresis_is_the_loops_area_in_millijoules_every_cycle():
    """Loading at 3 f0 per thread, unloading at 2, over a stroke of 0.02 l0 per stitch in four ramps: the readings
    are all a tester has, so the loop is their trapezoids, and the first unloading ramp leaves the top (3) for the
    line (2): 3 x 0.02 - (2.5 x 0.005 + 2 x 0.015) = 0.0175 f0 l0 per thread and stitch, times n_y f0 and n_x l0
    for the bars' work, every cycle alike."""
    import knitlad as kl

    up, down = np.full(5, 3.0), np.full(5, 2.0)
    rows = synthetic(up, down, cycles=3).tester_results()
    area = 8 * kl.NYLON.f0 * 0.0175 * 6 * kl.NYLON.stitch_length * 1e3  # mJ
    assert [row["cycle"] for row in rows] == [1, 2, 3]
    assert [row["hysteresis_energy_mJ"] for row in rows] == pytest.approx([area] * 3, rel=1e-9)


def test_more_cycles_than_one_need_the_unloading():
    with pytest.raises(ValueError, match="cycles"):
        config(cycles=2, unload=False)
