"""knitlad.engine.kernels.integrate: the fused passes of velocity Verlet give the same bits as the passes
they replace."""

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.kernels.integrate import (
    drift_edges,
    drift_nodes,
    kick_drift_edges,
    kick_drift_nodes,
    kick_edges,
    kick_nodes,
)


def test_the_fused_kick_and_drift_equal_the_kick_then_the_drift_to_the_bit():
    rng = np.random.default_rng(3)
    n, dt = 1001, 3.7e-5
    held = rng.random(n) < 0.1
    mass = rng.uniform(0.5, 2.0, n)
    force = rng.normal(size=(n, 3)) * 1e3
    v_prescribed = np.where(held[:, None], rng.normal(size=(n, 3)), 0.0)
    v, x = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    v1, x1 = v.copy(), x.copy()
    kick_nodes(held, mass, force, v1, dt)
    drift_nodes(held, v_prescribed, v1, x1, dt)
    v2, x2 = v.copy(), x.copy()
    kick_drift_nodes(held, mass, force, v_prescribed, v2, x2, dt)
    assert np.array_equal(v1, v2) and np.array_equal(x1, x2)
    assert not np.array_equal(x1, x)  # the nodes moved

    theta_held = rng.random(n) < 0.1
    inertia, torque = rng.uniform(0.1, 1.0, n), rng.normal(size=n)
    omega, theta = rng.normal(size=n), rng.normal(size=n)
    o1, t1 = omega.copy(), theta.copy()
    kick_edges(theta_held, inertia, torque, o1, dt)
    drift_edges(theta_held, o1, t1, dt)
    o2, t2 = omega.copy(), theta.copy()
    kick_drift_edges(theta_held, inertia, torque, o2, t2, dt)
    assert np.array_equal(o1, o2) and np.array_equal(t1, t2)
    assert np.all(o2[theta_held] == 0.0)


VELOCITY = 3.0


@pytest.mark.parametrize("twist, framed, predicted", [(False, False, False), (True, False, False),
                                                      (True, True, False), (False, False, True)])
def test_a_step_yarn_by_yarn_gives_the_bits_of_the_force_evaluation_then_the_kick(twist, framed, predicted):
    """verlet_steps evaluates a contact scene's forces and kicks its nodes yarn by yarn in one parallel pass
    (fused_step), which also tests the edges' displacements for the next step's list: the positions,
    velocities and spins must be those of the whole force evaluation (compute_forces) followed by the kick and
    drift of every node, step after step, to the bit, with the list rebuilt at the same steps."""
    from knitlad.engine.contact import ContactModel
    from knitlad.engine.kernels import contact as kc
    from knitlad.engine.kernels import integrate as ki
    from knitlad.fabric.scenes.weave import plain_weave

    def simulation():
        rods = plain_weave(4, spacing=4 * kl.NYLON.diameter, nodes_per_spacing=6,
                           amplitude=0.4 * kl.NYLON.diameter).build(twist=twist)
        sim = kl.Simulation(rods, contact=ContactModel(stiffness=1e3, mu=0.4, capacity_per_edge=64),
                            framed_twist=framed, predicted_dashpots=predicted)
        rng = np.random.default_rng(5)
        # mm/ms: every yarn moves, by more than the list's allowance within the run (so that it is rebuilt)
        sim.state.v[:] = rng.normal(scale=VELOCITY, size=sim.state.v.shape)
        sim.state.omega[:] = rng.normal(scale=0.1, size=sim.state.omega.shape)
        sim.state.v[sim.model.held] = 0.0
        sim.compute_forces()
        return sim

    n, fused, whole = 300, simulation(), simulation()
    args = (fused.model, fused.state, fused.work, fused.contacts, fused.dt)
    assert ki.verlet_steps(*args, n, fused.twist_mode, True, 0.0, fused.axial_mode, fused.dashpot_mode) == n

    m, s, w, c, dt = whole.model, whole.state, whole.work, whole.contacts, whole.dt
    spin = whole.twist_mode
    ki.half_kick(m, s, w, 0.5 * dt, spin)
    ki.drift_nodes(m.held, m.v_prescribed, s.v, s.x, dt)
    if spin:
        ki.drift_edges(m.theta_held, s.omega, s.theta, dt)
    for step in range(n):
        if predicted:
            ki.predict_velocities(m.held, m.mass, w.force, s.v, 0.5 * dt, w.v_damp)
            if spin:
                ki.predict_spins(m.theta_held, m.twist_inertia, w.torque, s.omega, 0.5 * dt, w.omega_damp)
        assert ki.compute_forces(m, s, w, c, spin, True, 0.0, dt, whole.axial_mode, whole.dashpot_mode)
        if step < n - 1:
            kick_drift_nodes(m.held, m.mass, w.force, m.v_prescribed, s.v, s.x, dt)
            if spin:
                kick_drift_edges(m.theta_held, m.twist_inertia, w.torque, s.omega, s.theta, dt)
        else:
            ki.half_kick(m, s, w, 0.5 * dt, spin)
    ki.complete_frames(m, s, w, spin)

    assert whole.contacts.stats[0] > 0  # pairs touch
    rebuilds = int(c.status[kc.REBUILDS])
    assert rebuilds >= 3 and fused.contacts.status[kc.REBUILDS] == rebuilds
    assert not np.array_equal(s.x, simulation().state.x)  # the nodes moved
    for name in ("x", "v", "omega", "theta", "ref_u"):
        np.testing.assert_array_equal(getattr(fused.state, name), getattr(s, name), err_msg=name)
    np.testing.assert_array_equal(fused.work.force, w.force)
    np.testing.assert_array_equal(fused.contacts.stats, c.stats)
