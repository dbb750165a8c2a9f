"""Rows periodic along the course (knitlad.fabric.scenes.rows) and the period under an imposed tension
(knitlad.experiments.periodic_loop.TensionBox): checked on straight rows, whose tension is EA times the strain."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.contact import ContactModel
from knitlad.experiments.periodic_loop import TensionBox
from knitlad.fabric.scenes.rows import IMAGES_X, build_periodic_rows

M = kl.NYLON
REST = 3.0  # period at rest [internal length, mm]


def straight_rows(rows: int = 2, columns: int = 1, spacing: float = 5.0, **kwargs):
    """Straight rows along x, ``spacing`` apart (no contact between them), at their rest period."""
    k = 12
    pts = np.zeros((k, 3))
    pts[:, 0] = np.arange(k) * REST / (k * columns)
    stack = build_periodic_rows(pts, REST / columns, spacing, rows, columns, M, **kwargs)
    sim = kl.Simulation(stack.rods, contact=ContactModel.for_knit(M, 20.0, 0.05, mu=0.0))
    return stack, sim


def test_each_row_is_an_endless_course_with_its_images():
    stack, sim = straight_rows(rows=3, columns=2, rails={2: None}, held=(0,))
    m = sim.model
    assert stack.period == pytest.approx(REST)
    for row in range(3):
        assert len(stack.images[row]) == 2 * IMAGES_X
        seam = np.flatnonzero((m.node_yarn[m.edge_a] == row) & np.any(m.edge_shift != 0, axis=1))
        assert seam.size == 1 and m.edge_shift[seam[0], 0] == pytest.approx(stack.period)
    shifts = sorted(float(m.image_shift[m.node_yarn[m.image_node] == y][0, 0]) for y in stack.images[1])
    assert shifts == pytest.approx([i * REST for i in (-2, -1, 1, 2)])
    assert m.held[stack.row_nodes(sim, 0)].all() and not m.held[stack.row_nodes(sim, 1)].any()
    railed = set(m.rail_node.tolist())
    assert set(range(stack.row_nodes(sim, 2).start, stack.row_nodes(sim, 2).stop)) == railed


def test_the_energy_belongs_to_the_rows_present():
    stack, sim = straight_rows(rows=3)
    all_edges = stack.real_edges.size
    stack.absent.add(0)
    assert stack.real_edges.size == all_edges * 2 // 3
    assert np.all(sim.model.node_yarn[sim.model.edge_a[stack.real_edges]] > 0)


def test_tension_of_a_stretched_row_is_ea_times_strain():
    """dE/dL of straight rows at strain e is EA e per row, to round-off (central differences of a quadratic)."""
    stack, sim = straight_rows(rows=2)
    box = TensionBox(stack, sim, M, rows_carrying=2)
    stack.set_period(sim, REST * 1.001)
    assert box.tension() == pytest.approx(M.stretching_stiffness * 1e-3 / M.f0, rel=1e-8)


def test_the_period_follows_the_imposed_tension():
    """In time, the overdamped period settles where the rows carry the imposed tension: strain f_x f0 / EA
    (from the rows at rest: within 2e-3 after 20 steps, to round-off after 100; 300 steps are run)."""
    stack, sim = straight_rows(rows=2)
    box = TensionBox(stack, sim, M, rows_carrying=2)
    box.set_response(0.3e-6)
    assert box.tension() == pytest.approx(0.0, abs=1e-9)  # it starts unloaded
    for _ in range(300):
        sim.step(1)
        box.follow(2.0, sim.dt)
    assert stack.period / REST - 1 == pytest.approx(2.0 * M.f0 / M.stretching_stiffness, rel=1e-3)
    assert box.tension() == pytest.approx(2.0, rel=1e-3)


def test_touching_pairs_of_edge_sets_count_as_those_of_yarns():
    """Two crossing straight yarns: the pair count by edge masks equals the count by yarns."""
    scene = kl.Scene(M)
    t = np.linspace(-1e-3, 1e-3, 11)[:, None]
    a = scene.add_yarn(np.hstack([t, 0 * t, 0 * t]))
    b = scene.add_yarn(np.hstack([0 * t, t, 0 * t + 0.9 * M.diameter]))
    sim = kl.Simulation(scene.build(), contact=ContactModel.for_knit(M, 20.0, 0.05, mu=0.0))
    edge_yarn = sim.model.node_yarn[sim.model.edge_a]
    by_yarn = sim.touching_pairs(a, b)
    assert by_yarn >= 1
    assert sim.touching_pairs_of_edges(edge_yarn == a, edge_yarn == b) == by_yarn
    assert sim.touching_pairs_of_edges(edge_yarn == a, edge_yarn == a) == 0
