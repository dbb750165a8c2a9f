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
    return build_knit(KnitGeometry(n_x=5, n_y=4, l_x=request.param * L0, l_y=min(request.param, 0.25) * L0, resolution=36))


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
    assert refresh_contacts(s.state.x, s.model.edge_a, s.model.edge_b, s.model.edge_shift, c, s.state.v, 0.0)
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
    assert_jersey_topology(knit)


def assert_jersey_topology(knit):
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
    knit = build_knit(KnitGeometry(n_x=3, n_y=2, l_x=0.3 * L0, l_y=0.25 * L0, resolution=24, edge="tail"))
    s = knit.rods
    for y in knit.courses:
        held = np.flatnonzero(s.model.held[s.model.yarn_start[y]: s.model.yarn_start[y + 1]])
        assert held.tolist() == [0, s.model.yarn_start[y + 1] - s.model.yarn_start[y] - 1]


@pytest.fixture(scope="module")
def continuous():
    return build_knit(KnitGeometry(n_x=5, n_y=5, l_x=0.3 * L0, l_y=0.245 * L0, resolution=24, edge="continuous"))


def test_the_continuous_knit_is_one_yarn_turning_at_the_side_edges_in_clips_that_slide_along_y(continuous):
    """edge="continuous": the free courses are one yarn, the odd ones run backwards, and course r turns into
    course r + 1 in a half circle of diameter l_y (its end sinkers 1e-9 l0 on the box edges) whose apex, on the
    right for even r and the left for odd r, is the one node on a rail along y; only the yarn's two ends are
    held (two nodes each: position and tangent). The yarn turns smoothly: no hinge of the turning loops
    or their joins bends more than the half circle's own pi / segments."""
    k, g = continuous, continuous.geometry
    m, x = k.rods.model, k.rods.state.x * kl.units.LENGTH
    assert set(k.courses) == {k.courses[0]} and len(k.courses) == g.n_y and len(m.yarn_start) == 4
    yarn = slice(int(m.yarn_start[k.courses[0]]), int(m.yarn_start[k.courses[0] + 1]))
    edge = g.column_x(g.n_x - 1) + 0.5 * g.l_x
    for r in range(g.n_y):
        nodes = k.course_nodes(r)
        direction = 1 if r % 2 == 0 else -1
        assert x[nodes.start, 0] == pytest.approx(-direction * edge, abs=1e-9 * L0)
        assert x[nodes.stop - 1, 0] == pytest.approx(direction * edge, abs=1e-9 * L0)
    assert np.flatnonzero(m.held[yarn]).tolist() == [0, 1, yarn.stop - yarn.start - 2, yarn.stop - yarn.start - 1]
    clips = m.rail_node
    assert clips.size == g.n_y - 1 and np.allclose(m.rail_axis, [0.0, 1.0, 0.0])
    sides = np.sign(x[clips, 0])
    assert sides.tolist() == [1.0 if r % 2 == 0 else -1.0 for r in range(g.n_y - 1)]
    np.testing.assert_allclose(np.abs(x[clips, 0]), edge + 0.5 * g.l_y, rtol=1e-9)
    t = np.diff(x[yarn], axis=0)
    t /= np.linalg.norm(t, axis=1)[:, None]
    turn = np.arccos(np.clip((t[1:] * t[:-1]).sum(axis=1), -1.0, 1.0))
    outside = np.abs(x[yarn][1:-1, 0]) > edge + 1e-9 * L0
    segments = k.course_span[1, 0] - k.course_span[0, 1] + 1
    assert turn[outside].max() <= math.pi / segments * (1 + 1e-6)


def test_the_continuous_knit_interlocks_as_jersey_and_its_turning_loops_thread_nothing(continuous):
    """Every loop threads the head below it and no other (as the clamped knit); a turning loop, outside the box,
    pierces no head: the edges change how the yarn is held, not the fabric."""
    assert_jersey_topology(continuous)
    k = continuous
    span = k.course_span
    for r in range(continuous.geometry.n_y - 1):
        turn = k.rods.state.x[span[r, 1] - 1: span[r + 1, 0] + 1]
        for row in range(continuous.geometry.n_y):
            for col in range(continuous.geometry.n_x):
                assert piercings(head_ring(k, row, col), turn)[0] == 0, (r, row, col)


def test_the_continuous_knit_reads_each_clip_half_for_each_course_it_joins(continuous):
    """f_x from the supports: a course's end is its clip (half of it: two courses pull on one clip) or a held end
    of the yarn (all of it). With each course pulling T on its ends, the clips take 2 T and every course reads T."""
    k = continuous
    n_y, T = k.geometry.n_y, 3.0
    reactions = np.zeros((k.rods.model.n_nodes, 3))
    reactions[k.rods.model.rail_node, 0] = 2 * T * np.sign(k.rods.state.x[k.rods.model.rail_node, 0])
    yarn_ends = k.left_end[0], k.right_end[n_y - 1]
    reactions[yarn_ends[0], 0] = -0.5 * T
    reactions[yarn_ends[1], 0] = 0.5 * T * np.sign(k.rods.state.x[yarn_ends[1][0], 0])
    from knitlad.fabric.measure import course_tensions, tension_per_thread
    np.testing.assert_allclose(course_tensions(reactions, k.left_end, k.right_end, 1.0, k.left_share, k.right_share), T)
    assert tension_per_thread(reactions, k.left_end, k.right_end, 1.0, k.left_share, k.right_share) == pytest.approx(T)


@pytest.mark.parametrize("kwargs, match", [(dict(n_x=0), "1 x 1"), (dict(l_x=L0), "l0"), (dict(resolution=4), "resolution"),
                                           (dict(edge="loose"), "edge must be one of")])
def test_bad_geometry_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        KnitGeometry(**kwargs)
