"""Natural curvature and twist against closed-form rod mechanics."""

from __future__ import annotations

import math

import numpy as np

import knitlad as kl
from knitlad.contact import make_contacts
from knitlad.kernels.integrate import compute_forces
from knitlad.state import Workspace

B = kl.NYLON.bending_stiffness


def circle(radius: float, n: int, arc: float = 2 * math.pi, closed: bool = True) -> np.ndarray:
    phi = np.arange(n) * arc / (n if closed else n - 1)
    return np.column_stack([radius * np.cos(phi), radius * np.sin(phi), np.zeros(n)])


def circumradii(x: np.ndarray) -> np.ndarray:
    a, b, c = x[:-2], x[1:-1], x[2:]
    ab, bc, ca = np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1), np.linalg.norm(a - c, axis=1)
    area2 = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    return ab * bc * ca / (2 * area2)


def test_pre_curved_ring_is_force_free_in_its_rest_shape():
    """A ring whose natural curvature is its own: forces below 1e-9 of B/R^2."""
    R = 2e-3
    scene = kl.Scene()
    scene.add_yarn(circle(R, 40), closed=True, natural_curvature="rest")
    rods = scene.build()
    w = Workspace.for_model(rods.model)
    compute_forces(rods.model, rods.state, w, make_contacts(rods, None), True, False, 0.0, 1.0)
    scale = B / R**2 / kl.units.FORCE
    assert np.max(np.abs(w.force)) < 1e-9 * scale
    assert np.max(np.abs(w.torque)) < 1e-9 * scale * R / kl.units.LENGTH


def test_straightened_rod_with_natural_curvature_curls_back_to_its_arc():
    """Release a rod with natural curvature 1/R from a straight shape: it relaxes to radius R (0.5 %)."""
    R = 2e-3
    n = 31
    scene = kl.Scene()
    arc = circle(R, n, arc=1.5 * math.pi, closed=False)
    scene.add_yarn(arc, natural_curvature="rest")
    rods = scene.build()
    length = rods.model.rest_length.sum()
    rods.state.x[:] = 0.0
    rods.state.x[:, 0] = np.linspace(0.0, length, n)
    rods.state.x[:, 1] = 1e-3 * np.sin(np.linspace(0, math.pi, n)) * length  # break the symmetry
    sim = kl.Simulation(rods)
    result = sim.relax(force_tol_N=1e-9, max_steps=2_000_000)
    assert result["converged"], result
    radii = circumradii(sim.positions_m())
    # the circumradius of a chord polygon of a circle of radius R is R itself
    np.testing.assert_allclose(radii, R, rtol=5e-3)


def test_twisted_rod_carries_torque_GJ_phi_over_L():
    """A straight rod with both end edges clamped in twist, one turned by phi: torque = GJ phi / L."""
    n = 21
    h = 0.5e-3
    pts = np.zeros((n, 3))
    pts[:, 0] = np.arange(n) * h
    scene = kl.Scene()
    y = scene.add_yarn(pts)
    scene.hold(y, [0, 1, n - 2, n - 1])
    scene.hold_twist(y, [0, n - 2])
    rods = scene.build(twist=True)
    phi = 0.3
    rods.state.theta[-1] = phi
    sim = kl.Simulation(rods)
    sim.relax(force_tol_N=1e-12, torque_tol_Nm=1e-14)
    L = (n - 2) * h  # between the midpoints of the two clamped edges
    expected = kl.NYLON.twisting_stiffness * phi / L
    torque_end = -sim.work.torque[-1] * kl.units.FORCE * kl.units.LENGTH
    assert abs(torque_end / expected - 1.0) < 1e-6
    # the twist relaxed to a uniform rate
    rate = np.diff(rods.state.theta)
    np.testing.assert_allclose(rate, phi / (n - 2), rtol=1e-6)
