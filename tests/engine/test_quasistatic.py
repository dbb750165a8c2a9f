"""knitlad.engine.quasistatic: equilibrium through damped dynamics, friction included."""

from __future__ import annotations

import math

import numpy as np
import pytest

import knitlad as kl


def draped(ratio: float, mu: float = 0.3, load: float = 0.02, radius=3e-3, leg=6e-3) -> kl.Simulation:
    """A yarn over a cylinder (half a turn), both ends free and loaded: ``load`` on the right, ``ratio``
    x ``load`` on the left."""
    a = radius + 0.5 * kl.NYLON.diameter
    arc = np.linspace(math.pi, 0.0, 48)
    down = np.linspace(0.0, leg, 16)[1:]
    points = np.vstack([np.column_stack([np.full(15, -a), -down[::-1], np.zeros(15)]),
                        np.column_stack([a * np.cos(arc), a * np.sin(arc), 0 * arc]),
                        np.column_stack([np.full(15, a), -down, np.zeros(15)])])
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(points)
    sim = kl.Simulation(scene.build(), implicit_axial=True,
                        obstacles=[kl.Cylinder(stiffness=2e3, mu=mu, radius_m=radius, axis=(0, 0, 1))])
    forces = np.zeros((len(points), 3))
    forces[0, 1], forces[-1, 1] = -ratio * load, -load
    sim.set_external_forces(forces)
    return sim


def test_a_yarn_over_a_cylinder_settles_below_the_capstan_ratio_and_slides_above_it():
    """Capstan: loads in the ratio 2 < e^(0.3 pi) = 2.57 are held by friction: settle reaches a residual
    of 1e-5 N (5e-4 of the loads) within its time limit, its ends having moved along the legs by less
    than 0.05 mm (stretch and lift-off: measured 0.017 and 0.019 mm); at 3.2 no equilibrium exists:
    settle says so at its time limit, and the ends have run by more than a millimetre."""
    held = draped(2.0)
    start = held.positions_m()[[0, -1], 1].copy()
    out = held.settle(force_tol_N=1e-5, max_time_s=0.05, damping_per_s=2e4)
    assert out["converged"] and out["max_force_N"] <= 1e-5 and out["time_s"] < 0.05
    assert np.abs(held.positions_m()[[0, -1], 1] - start).max() < 5e-5
    assert held.obstacle_reactions_N()[0, 1] == pytest.approx(-3.0 * 0.02, rel=1e-3)  # the loads, carried
    sliding = draped(3.2)
    start = sliding.positions_m()[[0, -1], 1].copy()
    out = sliding.settle(force_tol_N=1e-5, max_time_s=0.01, damping_per_s=2e4)
    assert not out["converged"] and out["time_s"] == pytest.approx(0.01, rel=0.01)
    assert np.abs(sliding.positions_m()[[0, -1], 1] - start).min() > 1e-3


@pytest.mark.slow
def test_settle_reaches_the_static_answer_of_a_frictionless_cantilever_and_restores_the_drag():
    """A cantilever with a tip load, settled by damped dynamics, bends as FIRE's relaxation does: both
    to a residual of 1e-11 N, which on its tip stiffness 3B/L^3 = 0.013 N/m leaves 1e-9 m, 1e-5 of the
    tip's deflection. The drag in force before is back afterwards."""
    s = np.linspace(0.0, 0.02, 21)

    def cantilever():
        scene = kl.Scene(kl.NYLON)
        rod = scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))
        scene.hold(rod, [0, 1])
        sim = kl.Simulation(scene.build(), drag_per_s=5.0)
        forces = np.zeros((21, 3))
        forces[-1, 1] = -1e-6
        sim.set_external_forces(forces)
        return sim

    fire, damped = cantilever(), cantilever()
    assert fire.relax(force_tol_N=1e-11, max_steps=1_000_000)["converged"]
    out = damped.settle(force_tol_N=1e-11, max_time_s=5.0, damping_per_s=100.0)
    assert out["converged"] and out["max_force_N"] <= 1e-11
    assert damped.positions_m()[-1, 1] == pytest.approx(fire.positions_m()[-1, 1], rel=1e-4)
    assert damped.drag * 1.0 == pytest.approx(5.0 * kl.units.TIME)
    with pytest.raises(ValueError, match="positive"):
        damped.settle(force_tol_N=0.0, max_time_s=1.0, damping_per_s=1.0)


@pytest.fixture(scope="module")
def small_knit():
    return kl.stretch(kl.CutConfig(n_x=4, n_y=4, lx=0.36, preset="fast").stretch_settings())


def pulled_course(knit, mu=0.4):
    sim = kl.Simulation(knit.knit.rods.copy(), contact=kl.ContactModel.for_knit(kl.NYLON, mu=mu))
    end = sim.nodes_of(knit.knit.courses[2], [-2, -1])
    sim.release(end[:1])
    sim.relax(force_tol_N=1e-8, max_steps=400_000)
    return sim, end[1:]


@pytest.mark.slow
def test_a_course_pulled_by_a_ramp_gives_one_pull_at_any_slow_speed_and_jumps_give_less(small_knit):
    """With friction the path counts: ramps at 0.04 and 0.02 m/s (and two dampings) end on one settled
    pull within 1e-3; jumps of 50 um, each settled, leave the knit ringing and slipping, 5 % or more
    below it. The supports land where the ramp says."""
    pulls = []
    for speed, alpha in ((0.04, 2e4), (0.02, 2e4), (0.04, 1e4)):
        sim, end = pulled_course(small_knit)
        start = sim.positions_m()[end].copy()
        out = sim.ramp_held(end, by_m=(2e-4, 0.0, 0.0), speed_m_s=speed, damping_per_s=alpha)
        np.testing.assert_allclose(sim.positions_m()[end] - start, [[2e-4, 0.0, 0.0]], atol=1e-12)
        assert out["time_s"] == pytest.approx(2e-4 / speed, rel=1e-3) and sim.drag == 0.0
        assert sim.settle(force_tol_N=1e-6, max_time_s=0.05, damping_per_s=alpha)["converged"]
        pulls.append(sim.reaction_forces_N()[end[0], 0])
    assert pulls[1] == pytest.approx(pulls[0], rel=1e-3) and pulls[2] == pytest.approx(pulls[0], rel=1e-3)
    sim, end = pulled_course(small_knit)
    for _ in range(4):
        sim.move_held(end, by_m=(5e-5, 0.0, 0.0))
        assert sim.settle(force_tol_N=1e-6, max_time_s=0.05, damping_per_s=2e4)["converged"]
    assert sim.reaction_forces_N()[end[0], 0] < 0.95 * pulls[0]
    middle = sim.nodes_of(small_knit.knit.courses[2], [5])
    with pytest.raises(ValueError, match="held"):
        sim.ramp_held(middle, by_m=(1e-5, 0, 0), speed_m_s=0.01, damping_per_s=1e4)


def test_a_reaction_read_while_the_supports_move_under_a_drag_warns_with_its_bias():
    """The reaction read during ramp_held gave F_x/N = 0.50 at mu 0.3, and 0.301 after settle(): the natural
    read was wrong and only a docstring said so. Read while moving, it warns with the bias alpha M V; read
    after the supports stop, it does not."""
    import warnings

    import numpy as np

    import knitlad as kl
    from knitlad.fabric.scenes.rod import Cantilever

    sim = kl.Simulation(Cantilever(0.02, 21).build())
    ends = sim.nodes_of(0, [0, 1])
    sim.set_drag(1e4)
    sim.hold(ends, velocity_m_s=(0.0, 0.0, 0.2))
    sim.step(2000)
    bias = sim.reaction_bias_N()
    assert bias[2] > 0  # the rod dragged upwards: the supports pay its drag
    with pytest.warns(kl.MovingSupportWarning, match=r"biased by about .* N"):
        sim.reaction_forces_N()
    full = 1e4 * (sim.model.mass[~sim.model.held] * kl.units.MASS).sum() * 0.2
    assert 0.1 * full < bias[2] <= full  # alpha M V once everything moves with the supports
    sim.hold(ends)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.reaction_forces_N()
    assert not np.any(sim.reaction_bias_N())


@pytest.mark.slow
def test_a_ramp_carries_a_clip_across_its_rail_and_the_ledger_counts_the_rail_s_work():
    """ramp_held(rails=...): a yarn along y, held at one end, its other end in a clip on a rail along y and
    pushed across the rail by F along +x. Both ends carried by dx along x: the clip lands on dx to round-off
    (its y is free, its z kept), and the ledger closes: the rail's work -F dx balances the load's F dx (without
    it the residual would be F dx); to 1e-3 of F dx (measured 3e-7)."""
    n, length, push, dx = 11, 0.01, 1e-3, 2e-4
    pts = np.zeros((n, 3))
    pts[:, 1] = np.linspace(0.0, length, n)
    scene = kl.Scene()
    y = scene.add_yarn(pts)
    scene.hold(y, [0])
    scene.slide(y, [n - 1], (0.0, 1.0, 0.0))
    scene.apply_force(y, n - 1, (push, 0.0, 0.0))
    sim = kl.Simulation(scene.build())
    sim.reset_ledger()
    before = sim.positions_m()[-1].copy()
    sim.ramp_held([0], by_m=(dx, 0.0, 0.0), speed_m_s=0.05, damping_per_s=2e3, rails=[n - 1],
                  rails_by_m=(dx, 0.0, 0.0))
    after = sim.positions_m()[-1]
    assert after[0] - before[0] == pytest.approx(dx, rel=1e-12) and after[2] == before[2]
    assert np.all(sim.state.v[n - 1, [0, 2]] == 0.0)  # carried no further
    ledger = sim.ledger()
    # the supports' work: the rail's -F dx, and the few % the held end pays for the drag and the yarn's motion
    assert -push * dx < ledger.support_work < -0.95 * push * dx
    assert abs(ledger.residual) < 1e-3 * push * dx
    with pytest.raises(ValueError, match="rails: ramp_held carries nodes on rails only"):
        sim.ramp_held([0], by_m=(dx, 0.0, 0.0), speed_m_s=0.05, damping_per_s=2e3, rails=[1])
