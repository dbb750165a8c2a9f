"""The friction couple: with twist on, friction acts on the yarns' surfaces and turns them.

Two straight yarns cross, pressed together (axes 0.98 d apart), their centrelines held;
yarn A may spin about its axis. The contact point sits on both surfaces, so

* a spinning A slides on B and the friction torque r mu f_n spins it down:
  d/dt sum(I omega) = -r mu F_n exactly (Coulomb sliding);
* A rolling on B (axis moving at -r omega, so its surface at the contact is at rest)
  feels no friction at all.
"""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine import units
from knitlad.engine.contact import ContactModel
from knitlad.engine.state import Scene, with_twist

D = kl.NYLON.diameter
R = 0.5 * D
MU = 0.3


def crossing(spin_rad_s: float, axis_velocity=(0.0, 0.0, 0.0)):
    n, length = 21, 4e-3
    s = np.linspace(-length / 2, length / 2, n)
    scene = Scene(kl.NYLON)
    a = scene.add_yarn(np.column_stack([s, 0 * s, 0 * s + 0.49 * D]))
    b = scene.add_yarn(np.column_stack([0 * s, s, 0 * s - 0.49 * D]))
    scene.hold(a, range(n), velocity=axis_velocity)
    scene.hold(b, range(n))
    rods = scene.build(twist=True)
    rods.state.v[:] = rods.model.v_prescribed  # moving from the first force evaluation on
    edges_a = np.flatnonzero(rods.model.node_yarn[rods.model.edge_a] == a)
    rods.state.omega[edges_a] = spin_rad_s * units.TIME
    sim = kl.Simulation(rods, contact=ContactModel(stiffness=1e3, mu=MU))
    return sim, edges_a


def test_a_spinning_yarn_is_spun_down_by_the_friction_torque_r_mu_fn():
    sim, ea = crossing(2.0e5)  # surface speed r omega = 14 m/s
    s = sim.state
    times, spins, normal = [], [], []
    for _ in range(40):
        sim.step(20)
        times.append(sim.time_s)
        spins.append(float((sim.model.twist_inertia[ea] * s.omega[ea]).sum()) * units.MASS * units.LENGTH**2 / units.TIME)
        normal.append(sim.contact_stats().normal_force_sum_N)
    assert sim.contact_stats().sliding >= 1
    rate = np.polyfit(times[10:], spins[10:], 1)[0]  # after the tangential spring has loaded
    expected = -R * MU * np.mean(normal[10:])
    assert expected < 0
    assert rate == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("direction, rolls", [(-1.0, True), (1.0, False)])
def test_a_yarn_rolling_on_another_feels_no_friction_one_skidding_does(direction, rolls):
    omega = 2.0e4
    # A lies along x above B; its surface at the contact (below its axis) moves at +r omega along y
    sim, ea = crossing(omega, axis_velocity=(0.0, direction * R * omega, 0.0))
    sliding = 0
    for _ in range(20):
        sim.step(5)
        sliding = max(sliding, sim.contact_stats().sliding)
    spin_change = abs(sim.state.omega[ea].mean() / units.TIME - omega) / omega
    if rolls:
        assert sliding == 0 and spin_change < 1e-9
    else:
        assert sliding >= 1 and spin_change > 1e-3


@pytest.mark.parametrize("mode", ["framed", "straight"])
def test_switching_twist_on_leaves_every_force_unchanged(mode):
    """Either twist path (framed DER; the frame-free path of yarns straight at rest) gives the
    twist-free forces at the cut, where the reference frames are Bishop's and theta = 0."""
    from knitlad.engine.contact import make_contacts
    from knitlad.engine.kernels.integrate import (AXIAL_EXPLICIT, DASHPOTS_HALF_STEP, TWIST_FRAMED, TWIST_OFF,
                                                  TWIST_STRAIGHT, compute_forces, potential_energy)
    from knitlad.engine.obstacles import obstacle_state
    from knitlad.engine.kernels.dissipation import no_damping
    from knitlad.fabric.scenes.knit import KnitGeometry, build_knit
    from knitlad.engine.state import Workspace

    l0 = kl.NYLON.stitch_length
    knit = build_knit(KnitGeometry(n_x=3, n_y=4, l_x=0.33 * l0, l_y=0.25 * l0, resolution=24))
    plain = knit.rods
    plain.state.x[:] += np.random.default_rng(3).normal(scale=0.02 * D / units.LENGTH, size=plain.state.x.shape)  # any shape
    twisted = with_twist(plain, kl.NYLON.twisting_stiffness / kl.NYLON.bending_stiffness)
    contact = ContactModel(stiffness=1e3)
    forces = []
    for rods, twist in ((plain, TWIST_OFF), (twisted, TWIST_FRAMED if mode == "framed" else TWIST_STRAIGHT)):
        w = Workspace.for_model(rods.model)
        c = make_contacts(rods, contact)
        assert compute_forces(rods.model, rods.state, w, c, twist, True, no_damping(), 1e-3, AXIAL_EXPLICIT,
                              DASHPOTS_HALF_STEP, obstacle_state([], rods.model.n_nodes))
        forces.append(w.force.copy())
        if twist:
            assert np.abs(w.torque).max() < 1e-9 * np.abs(w.force).max()
            stretching, bending, twisting = potential_energy(rods.model, rods.state, w, c, twist, True)[:3]
            assert abs(twisting) < 1e-12 * (stretching + bending)
    np.testing.assert_allclose(forces[1], forces[0], rtol=0, atol=1e-9 * np.abs(forces[0]).max())
    with pytest.raises(ValueError, match="already carries twist"):
        with_twist(twisted, 0.7)
