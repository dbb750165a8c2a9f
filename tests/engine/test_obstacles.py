"""knitlad.engine.obstacles: rigid planes and cylinders, their checks, their motion (the contact law: tests/test_examples.py)."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl


def test_a_moving_plate_carries_a_yarn_resting_on_it_and_says_where_it_is():
    """A plate rising at 0.1 m/s under a free, weightless yarn pushes it: after 2 ms (whole steps) the plate
    has moved 0.1 m/s times the time run, and the yarn, launched off it (nothing pulls it back), lies
    above it by at least its radius less 1 um: no node went through."""
    d = kl.NYLON.diameter
    s = np.linspace(0.0, 0.01, 21)
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([s, 0 * s, np.full_like(s, 0.5 * d)]))
    plate = kl.Plane(stiffness=100.0, velocity_m_s=(0.0, 0.0, 0.1))
    sim = kl.Simulation(scene.build(), obstacles=[plate])
    sim.run(2e-3)
    np.testing.assert_allclose(sim.obstacle_positions_m()[0], [0.0, 0.0, 0.1 * sim.time_s], atol=1e-12)
    z = sim.positions_m()[:, 2]
    assert z.min() > 0.1 * sim.time_s + 0.5 * d - 1e-6
    sim.move_obstacle(0, (0.0, 0.0, -1e-3))
    assert sim.obstacle_positions_m()[0, 2] == pytest.approx(0.1 * sim.time_s - 1e-3)


@pytest.mark.parametrize("make, says", [
    (lambda: kl.Plane(stiffness=-1.0), "stiffness"),
    (lambda: kl.Plane(stiffness=1.0, normal=(0, 0, 0)), "normal"),
    (lambda: kl.Cylinder(stiffness=1.0, radius_m=0.0), "radius_m"),
    (lambda: kl.Cylinder(stiffness=1.0, mu=-0.1), "friction"),
    (lambda: kl.Plane(stiffness=1.0, velocity_m_s=(1.0, 2.0)), "velocity_m_s"),
])
def test_a_bad_obstacle_is_refused_naming_what_is_wrong(make, says):
    with pytest.raises(ValueError, match=says):
        make()


def test_obstacles_stiffen_the_time_step_and_a_wrong_index_or_shift_is_refused():
    s = np.linspace(0.0, 0.01, 21)
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))
    rods = scene.build()
    free = kl.Simulation(rods.copy())
    walled = kl.Simulation(rods.copy(), obstacles=[kl.Plane(stiffness=1e6, point_m=(0, 0, -1.0))])
    assert walled.dt_s < free.dt_s
    with pytest.raises(IndexError):
        walled.move_obstacle(1, (0, 0, 0))
    with pytest.raises(ValueError, match="by_m"):
        walled.move_obstacle(0, (0, 0))
    assert free.obstacle_reactions_N().shape == (0, 3) and free.obstacle_contacts().shape == (21, 0)
