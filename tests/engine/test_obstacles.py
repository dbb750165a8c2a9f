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


def test_a_pin_hooks_only_what_lies_along_it_and_lets_go_when_released():
    """Two parallel yarns along x, 3 mm apart in y, their ends held; a 2 mm pin along y under the first one,
    rising at 1 m/s: it lifts the first yarn's middle onto its top, and the second yarn, beyond the
    pin's cap, stays flat (an endless cylinder would lift both). Released, the pin exerts no force and stops."""
    d = kl.NYLON.diameter
    s = np.linspace(-0.005, 0.005, 41)
    scene = kl.Scene(kl.NYLON)
    for y in (0.0, 3e-3):
        scene.add_yarn(np.column_stack([s, np.full_like(s, y), 0 * s]))
    n = s.size
    scene.hold(0, [0, n - 1])
    scene.hold(1, [0, n - 1])
    pin = kl.Cylinder(stiffness=1e4, point_m=(0.0, 0.0, -0.4e-3), axis=(0.0, 1.0, 0.0), radius_m=0.25e-3,
                      length_m=2e-3, velocity_m_s=(0.0, 0.0, 1.0))
    sim = kl.Simulation(scene.build(), obstacles=[pin])
    sim.run(0.6e-3)
    x = sim.positions_m()
    top = sim.obstacle_positions_m()[0, 2] + 0.25e-3 + 0.5 * d
    assert x[n // 2, 2] == pytest.approx(top, abs=0.05e-3)  # hooked: the first yarn rides on the pin
    assert np.abs(x[n:, 2]).max() < 1e-6  # the second, past the cap, untouched
    assert sim.obstacle_reactions_N()[0, 2] < 0  # the hooked yarn pulls the pin back
    sim.release_obstacle(0)
    at = sim.obstacle_positions_m()[0].copy()
    sim.run(0.2e-3)
    assert np.all(sim.obstacle_reactions_N() == 0.0)
    np.testing.assert_array_equal(sim.obstacle_positions_m()[0], at)
    with pytest.raises(ValueError, match="length_m"):
        kl.Cylinder(stiffness=1.0, length_m=-1.0)
    with pytest.raises(ValueError, match="velocity_m_s"):
        sim.set_obstacle_velocity(0, (1.0, 0.0))
