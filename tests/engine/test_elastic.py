"""The implicit axial springs (kernels/elastic.implicit_stretching_forces): the tensions solve their equation."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.kernels.elastic import edge_vectors, implicit_stretching_forces
from knitlad.engine.kernels.integrate import rail_forces
from knitlad.engine.state import Workspace
from knitlad.engine.timestep import critical_time_steps


def two_wavy_yarns_one_held_in_the_middle():
    rng = np.random.default_rng(7)
    scene = kl.Scene()
    for k in range(2):
        pts = np.zeros((12, 3))
        pts[:, 0] = np.linspace(0.0, 5e-3, 12)
        pts[:, 1] = 1e-3 * k + 2e-4 * np.sin(np.linspace(0.0, 6.0, 12))
        scene.add_yarn(pts + rng.normal(scale=3e-5, size=pts.shape))
    scene.hold(0, [5])
    rods = scene.build(stretch_damping_ratio=0.2)
    m, s = rods.model, rods.state
    s.x[:] += rng.normal(scale=2e-3, size=s.x.shape) * m.rest_length.mean()  # strains of order 1e-3
    s.v[:] = np.where(m.held[:, None], 0.0, rng.normal(scale=1.0, size=s.v.shape))  # mm/ms
    other = rng.normal(scale=0.1, size=s.x.shape)  # mN: the forces the tensions must answer
    return m, s, other


def end_of_kick_tensions(m, s, w, F, other, dt):
    """The tensions T_k = g_k+ / eps_k + c_k dg_k+/dt at the end of the kick v+ = v + dt M^-1 F that ``F`` causes,
    and the forces they and ``other`` make: what the solve must have returned."""
    v_end = s.v + dt * np.where(m.held, 0.0, 1.0 / m.mass)[:, None] * F
    t = w.e / w.elen[:, None]
    rate = np.sum(t * (v_end[m.edge_b] - v_end[m.edge_a]), axis=1)
    tension = m.EA * (w.elen + dt * rate - m.rest_length) / m.rest_length + m.stretch_damping * rate
    rebuilt = other.copy()
    np.add.at(rebuilt, m.edge_a, tension[:, None] * t)
    np.add.at(rebuilt, m.edge_b, -tension[:, None] * t)
    return tension, rebuilt


@pytest.mark.parametrize("one_range", [True, False])
def test_the_tensions_are_those_at_the_end_of_the_kick_they_cause(one_range):
    """T_k = g_k+ / eps_k + c_k dg_k+/dt with g+ = g + dt t.(v+_b - v+_a) and v+ = v + dt M^-1 F, to
    round-off, at 5 x the explicit stretching limit; a break between yarns is found over one range."""
    m, s, other = two_wavy_yarns_one_held_in_the_middle()
    dt = 5.0 * critical_time_steps(m, False).stretching
    w = Workspace.for_model(m)
    edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen)
    F = other.copy()
    ranges = [(0, m.edge_a.shape[0])] if one_range else [(w.yarn_edges[y], w.yarn_edges[y + 1]) for y in range(2)]
    for first, last in ranges:
        implicit_stretching_forces(w.e, w.elen, s.v, m.held, m.mass, m.edge_a, m.edge_b, m.rest_length, m.EA,
                                   m.stretch_damping, dt, F, w.axial_sweep, first, last)
    tension, rebuilt = end_of_kick_tensions(m, s, w, F, other, dt)
    assert np.abs(tension).max() > 10 * np.abs(other).max()  # the springs dominate: a real test of the solve
    np.testing.assert_allclose(F, rebuilt, rtol=0, atol=1e-10 * np.abs(F).max())


def test_on_a_rail_the_tensions_are_those_at_the_end_of_the_kick_along_the_rail():
    """A node on a rail of axis a has the inverse mass a a^T / m: the tensions are those at the end of the
    kick its projected force causes (the forces of the other nodes as above), to round-off."""
    m, s, other = two_wavy_yarns_one_held_in_the_middle()
    axis = np.array([0.6, 0.8, 0.0])
    node = 17  # on the second yarn
    m = m._replace(rail_node=np.array([node]), rail_axis=axis[None, :])
    s.v[node] = axis * (s.v[node] @ axis)  # a node on a rail moves along it
    other[node] = axis * (other[node] @ axis)  # the integrator projects every other force first
    dt = 5.0 * critical_time_steps(m, False).stretching
    w = Workspace.for_model(m)
    edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen)
    F = other.copy()
    rail_of_node = np.full(m.n_nodes, -1)
    rail_of_node[node] = 0
    implicit_stretching_forces(w.e, w.elen, s.v, m.held, m.mass, m.edge_a, m.edge_b, m.rest_length, m.EA,
                               m.stretch_damping, dt, F, w.axial_sweep, 0, m.edge_a.shape[0], None, rail_of_node,
                               m.rail_axis)
    taken = np.zeros((1, 3))
    rail_forces(m.rail_node, m.rail_axis, F, taken)
    v_end = s.v + dt * np.where(m.held, 0.0, 1.0 / m.mass)[:, None] * F
    assert abs(np.cross(v_end[node], axis)).max() < 1e-12 * np.abs(v_end[node]).max()  # still along the rail
    _, rebuilt = end_of_kick_tensions(m, s, w, F, other, dt)
    rebuilt[node] -= taken[0]  # the rail takes what is across it
    np.testing.assert_allclose(F, rebuilt, rtol=0, atol=1e-10 * np.abs(F).max())
    np.testing.assert_allclose(taken[0] @ axis, 0.0, atol=1e-12 * np.abs(taken).max())


def test_a_ring_refuses_implicit_axial_springs():
    theta = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    ring = kl.Scene()
    ring.add_yarn(np.c_[np.cos(theta), np.sin(theta), 0 * theta] * 1e-3, closed=True)
    with pytest.raises(ValueError, match="open yarns only"):
        kl.Simulation(ring.build(), implicit_axial=True)
