"""Natural curvature and twist against closed-form rod mechanics."""

from __future__ import annotations

import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.contact import make_contacts
from knitlad.engine.kernels.dissipation import no_damping
from knitlad.engine.kernels.integrate import AXIAL_EXPLICIT, DASHPOTS_HALF_STEP, TWIST_FRAMED, compute_forces
from knitlad.engine.obstacles import obstacle_state
from knitlad.engine.state import Workspace

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
    compute_forces(rods.model, rods.state, w, make_contacts(rods, None), TWIST_FRAMED, False, no_damping(), 1.0,
                   AXIAL_EXPLICIT, DASHPOTS_HALF_STEP, obstacle_state([], rods.model.n_nodes))
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


@pytest.mark.slow
def test_a_course_freed_of_the_knit_relaxes_to_the_natural_curvature_it_was_given():
    """The paper's extraction measurement, in simulation: a 4 x 4 knit whose yarn remembers the
    unloaded fabric's shape with K = mean (kappa_bar/kappa0)^2 = 1 (CutConfig.natural_curvature),
    stretched to f_x 4, then freed of its holds and of contact: a course relaxes (FIRE, twist on)
    to a shape whose mean (kappa/kappa0)^2, read from the positions alone (|kb| = 2 tan(phi/2)
    over the Voronoi length), is K within 2 %. Stretched, the same course is bent more (1.86)."""
    from knitlad.experiments.config import CutConfig
    from knitlad.fabric.shape_memory import positional_curvature
    from knitlad.fabric.preparation import stretch
    from knitlad.engine.simulation import Simulation

    K = 1.0
    cfg = CutConfig(n_x=4, n_y=4, fx=4.0, natural_curvature=K, preset="fast")
    knit = stretch(cfg.stretch_settings())
    rods, material = knit.knit.rods, cfg.stretch_settings().material
    assert rods.twist and cfg.twist
    m = rods.model
    hinges = np.flatnonzero(m.node_yarn[m.edge_a[m.hinge_e1]] == knit.knit.courses[1])

    def mean_squared_curvature(x):
        return float(np.mean(positional_curvature(rods, x, hinges, material)))

    stretched = mean_squared_curvature(rods.state.x)
    free = rods.copy().replace_model(held=np.zeros_like(m.held), v_prescribed=np.zeros_like(m.v_prescribed))
    sim = Simulation(free, contact=None)
    assert sim.relax(force_tol_N=1e-7, max_steps=400_000)["converged"]
    assert mean_squared_curvature(sim.state.x) == pytest.approx(K, rel=0.02)
    assert stretched > 1.5 * K


def test_a_tilted_planar_arc_laid_flat_keeps_its_curvature_and_an_ellipse_its_vertex_curvatures():
    """flattened_curvature: a circle of radius R drawn in a tilted plane reads 1/R at every vertex (its
    own plane is the best fit); an ellipse (a, b) reads a/b^2 at the ends of its major axis, b/a^2 at
    the minor, to the discretisation's second order."""
    from knitlad.fabric.shape_memory import flattened_curvature

    R = 2e-3
    arc = circle(R, 200, arc=1.5 * math.pi, closed=False)
    tilt = np.array([[1, 0, 0], [0, math.cos(0.7), -math.sin(0.7)], [0, math.sin(0.7), math.cos(0.7)]])
    k = flattened_curvature(arc @ tilt.T + [1e-3, -2e-3, 5e-4])
    np.testing.assert_allclose(np.abs(k), 1 / R, rtol=1e-4)
    a, b, n = 3.0, 1.0, 4000
    phi = np.linspace(0, 2 * math.pi, n + 1)
    k = np.abs(flattened_curvature(np.column_stack([a * np.cos(phi), b * np.sin(phi), 0 * phi])))
    assert k[n // 2 - 1] == pytest.approx(a / b**2, rel=1e-4)  # vertex n/2: phi = pi
    assert k[n // 4 - 1] == pytest.approx(b / a**2, rel=1e-4)  # vertex n/4: phi = pi/2


@pytest.mark.parametrize("peak_ratio", [None, 3.5])
def test_a_remembered_shape_has_the_mean_asked_and_a_concentrated_one_the_peak_asked(peak_ratio):
    """remember_shape on an open elliptical arc (curvature varying 1.7-fold): the natural curvature's mean
    (kappa_bar/kappa0)^2 is K; the scaled copy keeps the shape's own max/mean; the memory concentrated at
    the most bent hinges reaches the max/mean asked, the paper's 3.5, still with mean K, and its largest
    natural curvature sits where the arc is most bent."""
    from knitlad.fabric.shape_memory import mean_squared_curvature, remember_shape, voronoi_lengths

    phi = np.linspace(0.1, 2.9, 120)
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([3e-3 * np.cos(phi), 2.5e-3 * np.sin(phi), 0 * phi]))
    rods = scene.build()
    hinges = np.arange(rods.model.hinge_e0.size)
    K = 1.0
    own = remember_shape(rods, K, hinges, kl.NYLON)
    rods = remember_shape(rods, K, hinges, kl.NYLON, peak_ratio)
    lengths = voronoi_lengths(rods)
    kappa0 = kl.NYLON.kappa0 * kl.units.LENGTH
    q = np.sum(rods.model.kappa_bar**2, axis=1) / (lengths * kappa0) ** 2
    q_own = np.sum(own.model.kappa_bar**2, axis=1) / (lengths * kappa0) ** 2
    assert mean_squared_curvature(rods.model.kappa_bar, lengths, kl.NYLON) == pytest.approx(K, rel=1e-9)
    if peak_ratio is None:
        np.testing.assert_allclose(q, q_own, rtol=1e-12)
    else:
        assert q.max() / q.mean() == pytest.approx(peak_ratio, rel=1e-6)
        assert q_own.max() / q_own.mean() < 0.8 * peak_ratio
        assert np.argmax(q) == np.argmax(q_own)
    with pytest.raises(ValueError, match="below the shape's own"):
        remember_shape(rods, K, hinges, kl.NYLON, 1.01)
