"""knitlad.engine.kernels.integrate: the fused passes of velocity Verlet give the same bits as the passes
they replace."""

import numpy as np

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
