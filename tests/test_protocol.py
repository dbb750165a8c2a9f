"""The laddering protocol's choices that measurements made: where the knit is built."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from knitlad import units
from knitlad.protocol import BUILD_LX, LadderRun, LadderSettings, build_width
from knitlad.units import NYLON


def test_tall_cells_are_built_narrower_so_that_the_loops_interlock():
    """At l_y/l0 = 0.302, Crane loops built at 0.30 l0 overlap the next course by 0.12 d only and the
    knit comes apart; at the stitch's f_x = 0 width they overlap by more than 2 d."""
    assert build_width(0.25, NYLON) == BUILD_LX
    lx = build_width(0.302, NYLON)
    assert 0.24 < lx < 0.29
    run = LadderRun(LadderSettings(n_x=4, n_y=6, fx_target=None, lx_over_l0=0.35, ly_over_l0=0.302))
    l0, d = NYLON.stitch_length, NYLON.diameter
    overlap = 2 * run.knit.H - 0.302 * l0
    assert overlap > 2 * d


@pytest.mark.parametrize("ly", [0.302])
def test_force_control_reaches_its_target_in_a_tall_knit(ly):
    run = LadderRun(LadderSettings(n_x=6, n_y=8, fx_target=4.0, ly_over_l0=ly, nodes_per_stitch=16))
    run.stretch()
    assert run.result.fx_within_tolerance
    assert run.result.fx_ini == pytest.approx(4.0, rel=0.02)


def test_dashpot_and_drag_settings_reach_the_knit_and_the_laddering_dynamics():
    """The dissipation of the dynamics after the cut is set from LadderSettings alone (the
    damping study and scripts/energy_drift.py switch it off this way)."""
    from knitlad import units

    run = LadderRun(LadderSettings(n_x=4, n_y=4, nodes_per_stitch=16, fx_target=None, lx_over_l0=0.30,
                                   contact_damping_ratio=0.0, stretch_damping_ratio=0.0, drag_per_s=3e3))
    # the mu = 0 stretch (FIRE) keeps its own dashpots and no drag: they only shape its path
    assert run.knit.state.stretch_damping.min() > 0 and run.contact.damping_ratio == 0.3
    assert run.sim.drag == 0.0
    run.cut()
    assert not run.sim.state.stretch_damping.any()
    assert run.sim.contact_model.damping_ratio == 0.0 and run.sim.contact_model.tangential_damping_ratio == 0.0
    assert run.sim.drag == pytest.approx(3e3 * units.TIME)


def test_the_stretched_knit_does_not_depend_on_the_laddering_time_step():
    """dt_safety sets the step of the dynamics after the cut only: a stretch at another step
    would end in another relaxed state, and the ladder from it differs by the knit's scatter
    (16 x 16 at f_x = 3.9: v_lad 0.27 against 0.49), which would pass for an effect of dt."""
    import numpy as np

    runs = []
    for dt in (0.35, 0.175):
        run = LadderRun(LadderSettings(n_x=4, n_y=4, nodes_per_stitch=16, fx_target=None, lx_over_l0=0.34,
                                       dt_safety=dt))
        run.stretch()
        runs.append(run)
    assert np.array_equal(runs[0].sim.state.x, runs[1].sim.state.x)
    assert runs[0].result.fx_ini == runs[1].result.fx_ini
    steps = []
    for run in runs:
        run.cut()
        steps.append(run.sim.dt / run.sim.limits.combined)
    assert steps == pytest.approx([0.35, 0.175], rel=1e-9)


@pytest.mark.parametrize("name", ["contact_damping_ratio", "stretch_damping_ratio", "drag_per_s"])
def test_a_negative_dissipation_setting_is_refused_before_anything_runs(name):
    with pytest.raises(ValueError, match=name):
        LadderSettings(fx_target=4.0, **{name: -0.1})


def test_an_unknown_contact_counting_is_refused_before_anything_runs():
    with pytest.raises(ValueError, match="contact_counting"):
        LadderSettings(fx_target=4.0, contact_counting="every")


def _relax_in_rounds(run: LadderRun, rounds: int) -> tuple[list[float], dict]:
    """The protocol's FIRE rounds at a fixed box; f_x after each, and the last round's report."""
    readings, info = [], {}
    for _ in range(rounds):
        info = run._relax(run.s.steps_per_increment)
        readings.append(run.tension())
        if info["converged"]:
            break
    return readings, info


def test_at_mu_0_a_knit_with_clamped_course_ends_reaches_equilibrium_at_a_fixed_box():
    """Course ends clamped at the edge sinkers (position and tangent, the mirror symmetry of the
    periodic stitch there): FIRE reaches its force tolerance (1e-3 f0), so f_x has settled. Ends held at the tip of
    straight tails instead leave the edge stitches free to trade yarn, and the knit creeps: 8 x 10
    at l_x/l0 = 0.355 wandered between f_x 1.21 and 1.46 over 30 rounds, residual ~0.4 f0."""
    clamped = LadderRun(LadderSettings(n_x=8, n_y=10, lx_over_l0=0.355, fx_target=None, edge="clamped"))
    clamped.stretch_to(0.355, 0.25)
    readings, info = _relax_in_rounds(clamped, 40)
    assert info["converged"], f"residual {info['max_force_N'] / NYLON.f0:.3g} f0 after {len(readings)} rounds"

    tail = LadderRun(LadderSettings(n_x=8, n_y=10, lx_over_l0=0.355, fx_target=None, edge="tail"))
    tail.stretch_to(0.355, 0.25)
    _, info = _relax_in_rounds(tail, len(readings) + 10)
    assert info["max_force_N"] > 10 * 1e-3 * NYLON.f0


def test_an_unknown_edge_is_refused_before_anything_runs():
    with pytest.raises(ValueError, match="edge must be one of"):
        LadderRun(LadderSettings(n_x=4, n_y=4, lx_over_l0=0.35, fx_target=None, edge="loose"))


def test_force_control_says_when_the_knit_as_built_is_already_past_the_target():
    """With tails, the 8 x 10 knit built at l_x/l0 = 0.30 carries f_x ~ 0.4: a target of 0.05
    cannot be reached by stretching, and force control says so (position control is advised)."""
    run = LadderRun(LadderSettings(n_x=8, n_y=10, fx_target=0.05, edge="tail"))
    with pytest.raises(RuntimeError, match="use position control"):
        run.stretch()


def test_a_branch_of_a_stretched_run_ladders_like_a_fresh_run_with_its_settings():
    """LadderRun.branch: the laddering studies compare settings of the dynamics from one
    stretched knit. A branch must be independent of its parent, carry its new settings into the
    dynamics, and give the very ladder a fresh run with those settings gives (the stretch is
    deterministic and does not read them)."""
    base = LadderSettings(n_x=4, n_y=4, nodes_per_stitch=16, fx_target=None, lx_over_l0=0.34, max_time_s=0.2e-3)
    parent = LadderRun(base)
    parent.stretch()
    x_before = parent.sim.state.x.copy()
    child = parent.branch(mu=0.0, drag_per_s=1e3)
    child.propagate()
    assert np.array_equal(parent.sim.state.x, x_before)  # the parent is untouched
    assert child.result.settings.mu == 0.0 and parent.s.mu == base.mu
    fresh = LadderRun(replace(base, mu=0.0, drag_per_s=1e3))
    fresh.stretch()
    fresh.propagate()
    assert np.array_equal(child.sim.state.x, fresh.sim.state.x)
    assert child.result.fx_series == fresh.result.fx_series
    with pytest.raises(ValueError, match="n_x: not a setting of the laddering dynamics"):
        parent.branch(n_x=6)
    with pytest.raises(ValueError, match="drag_per_s must be >= 0"):
        parent.branch(drag_per_s=-1.0)
    with pytest.raises(RuntimeError, match="already cut"):
        child.branch(mu=0.4)


def test_with_twist_the_laddering_yarns_spin_and_the_time_step_allows_for_it():
    """LadderSettings(twist=True): twist switched on at the cut (friction couple on)."""
    base = LadderSettings(n_x=4, n_y=4, nodes_per_stitch=16, fx_target=None, lx_over_l0=0.34, max_time_s=0.1e-3)
    parent = LadderRun(base)
    parent.stretch()
    plain = parent.branch()
    plain.propagate()
    twisted = parent.branch(twist=True)
    twisted.propagate()
    assert twisted.sim.twist and not plain.sim.twist
    spin = np.abs(twisted.sim.state.omega).max() / units.TIME  # rad/s
    assert spin > 1e3  # friction has turned the yarns (surface speeds of 0.1 m/s and more)
    assert twisted.sim.limits.contact < plain.sim.limits.contact  # the turning adds to the contact stiffness
    assert twisted.sim.dt <= base.dt_safety * twisted.sim.limits.combined * (1 + 1e-12)
    assert np.isfinite(twisted.sim.state.x).all()
