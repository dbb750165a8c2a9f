"""The jersey scene: yarn length, no initial overlap, the right topology."""

from __future__ import annotations

import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.contact import ContactModel, make_contacts
from knitlad.engine.kernels.contact import refresh_contacts, segment_distance
from knitlad.fabric.scenes.knit import KnitGeometry, build_knit
from knitlad.fabric.topology import piercings

D = kl.NYLON.diameter
L0 = kl.NYLON.stitch_length


@pytest.fixture(scope="module", params=[0.245, 0.30], ids=["paper-start-0.245", "protocol-build-0.30"])
def knit(request):
    """The paper's initial l_x = l_y = 0.245 l0, and the l_x = 0.30 l0 the protocol builds at."""
    return build_knit(KnitGeometry(n_x=5, n_y=4, l_x=request.param * L0, l_y=min(request.param, 0.25) * L0, nodes_per_stitch=36))


def test_each_stitch_holds_l0_of_yarn(knit):
    g = knit.geometry
    # the resampled course (chords, as the rod sees it): n_x stitches between the end sinkers
    s = knit.rods
    nodes = knit.course_nodes(0)
    t = knit.node_t[nodes]
    inside = np.isfinite(t)
    x = s.state.x[nodes][inside] * kl.units.LENGTH
    length = np.linalg.norm(np.diff(x, axis=0), axis=1).sum()
    assert length == pytest.approx(g.n_x * L0, rel=1e-4)


def test_no_two_non_neighbouring_segments_are_closer_than_d(knit):
    """No overlap: non-neighbouring yarn axes stay >= d apart (measured 2.83 d at 0.245 l0, 1.56 d at 0.30 l0)."""
    s = knit.rods
    c = make_contacts(s, ContactModel(stiffness=1.0, skin=3 * D))
    assert refresh_contacts(s.state.x, s.model.edge_a, s.model.edge_b, s.model.edge_shift, c)
    dists = [segment_distance(s.state.x, s.model.edge_a, s.model.edge_b, s.model.edge_shift, i, j)[0] for i, j in c.pairs[: c.n_pairs[0]]]
    assert len(dists) > 0
    assert min(dists) * kl.units.LENGTH > D


def head_ring(knit, row, col):
    """Closed head of course `row` at column `col`: t in [2 pi col - pi/2, 2 pi col + pi/2]."""
    nodes = knit.course_nodes(row)
    t = knit.node_t[nodes]
    sel = (t >= 2 * math.pi * col - math.pi / 2) & (t <= 2 * math.pi * col + math.pi / 2)
    return knit.rods.state.x[nodes][sel]


def loop_arc(knit, row, col):
    """Loop of course `row` at column `col`, sinker to sinker: t in [2 pi col - pi, 2 pi col + pi]."""
    nodes = knit.course_nodes(row)
    t = knit.node_t[nodes]
    sel = (t >= 2 * math.pi * col - math.pi) & (t <= 2 * math.pi * col + math.pi)
    return knit.rods.state.x[nodes][sel]


def test_jersey_topology_each_loop_passes_through_the_loop_of_the_course_below(knit):
    """Loop (r+1, i) threads head (r, i) exactly (two opposite piercings); no other pair touches."""
    n_x, n_y = knit.geometry.n_x, knit.geometry.n_y
    for r in range(n_y - 1):
        for i in range(1, n_x - 1):
            ring = head_ring(knit, r, i)
            assert piercings(ring, loop_arc(knit, r + 1, i)) == (2, 0), (r, i)
            for other_row, other_col in ((r + 1, i - 1), (r + 1, i + 1), (r, i), (r - 1, i)):
                if 0 <= other_row < n_y and (other_row, other_col) != (r, i):
                    assert piercings(ring, loop_arc(knit, other_row, other_col))[0] == 0, (r, i, other_row, other_col)


def test_edge_courses_are_held_and_courses_are_clamped_at_their_edge_sinkers(knit):
    """Two nodes held at each end (position and tangent), the end node on the box edge at the
    bottom of the sinker, the yarn leaving it along x: the periodic stitch's mirror symmetry there."""
    s, g = knit.rods, knit.geometry
    for y in knit.bars:
        assert s.model.held[s.model.yarn_start[y]: s.model.yarn_start[y + 1]].all()
    for k, y in enumerate(knit.courses):
        nodes = s.state.x[s.model.yarn_start[y]: s.model.yarn_start[y + 1]] * kl.units.LENGTH
        held = np.flatnonzero(s.model.held[s.model.yarn_start[y]: s.model.yarn_start[y + 1]])
        last = nodes.shape[0] - 1
        assert held.tolist() == [0, 1, last - 1, last]
        assert nodes[0, 0] == pytest.approx(g.column_x(0) - 0.5 * g.l_x, abs=1e-9 * L0)
        assert nodes[last, 0] == pytest.approx(g.column_x(g.n_x - 1) + 0.5 * g.l_x, abs=1e-9 * L0)
        assert nodes[0, 1] == pytest.approx(k * g.l_y - knit.H, abs=1e-9 * L0)
        for a, b in ((0, 1), (last, last - 1)):
            t = (nodes[b] - nodes[a]) / np.linalg.norm(nodes[b] - nodes[a])
            assert abs(t[0]) > 0.99


def test_course_ends_with_tails_are_held_at_one_node():
    knit = build_knit(KnitGeometry(n_x=3, n_y=2, l_x=0.3 * L0, l_y=0.25 * L0, nodes_per_stitch=24, edge="tail"))
    s = knit.rods
    for y in knit.courses:
        held = np.flatnonzero(s.model.held[s.model.yarn_start[y]: s.model.yarn_start[y + 1]])
        assert held.tolist() == [0, s.model.yarn_start[y + 1] - s.model.yarn_start[y] - 1]


@pytest.mark.parametrize("kwargs, match", [(dict(n_x=0), "1 x 1"), (dict(l_x=L0), "l0"), (dict(nodes_per_stitch=4), "nodes_per_stitch"),
                                           (dict(edge="loose"), "edge must be one of")])
def test_bad_geometry_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        KnitGeometry(**kwargs)
