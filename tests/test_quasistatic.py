"""knitlad.quasistatic: equilibrium through damped dynamics, friction included."""

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
                        obstacles=[kl.Cylinder(stiffness=2e3, friction=mu, radius_m=radius, axis=(0, 0, 1))])
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
