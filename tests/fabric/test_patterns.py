"""knitlad.fabric.patterns: the stitch signs, the face along a course, and each pattern's built topology."""

from __future__ import annotations

import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.contact import ContactModel, make_contacts
from knitlad.engine.kernels.contact import refresh_contacts, segment_distance
from knitlad.fabric.patterns import FACE_SWITCH, KNIT, PATTERNS, PURL, KnitPattern, fabric_pattern, knit_pattern
from knitlad.fabric.scenes.knit import KnitGeometry, build_knit, build_loop_overlap, widest_fitting_width
from knitlad.fabric.topology import piercings, threading_direction
from tests.fabric.test_knit import head_ring, loop_arc

D = kl.NYLON.diameter
L0 = kl.NYLON.stitch_length


def test_the_patterns_stitches():
    assert knit_pattern("jersey").stitch(np.arange(3)[:, None], np.arange(4)).tolist() == [[KNIT] * 4] * 3
    assert knit_pattern("rib").stitch(5, np.arange(4)).tolist() == [KNIT, PURL, KNIT, PURL]
    assert knit_pattern("garter").stitch(np.arange(-1, 3), 7).tolist() == [PURL, KNIT, PURL, KNIT]


@pytest.mark.parametrize("kwargs, match", [(dict(name="x", repeat=()), "rectangle"),
                                           (dict(name="x", repeat=((1,), (1, -1))), "rectangle"),
                                           (dict(name="x", repeat=((0,),)), "knit")])
def test_a_bad_repeat_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        KnitPattern(**kwargs)


def test_an_unknown_pattern_is_refused_with_the_known_ones():
    with pytest.raises(ValueError, match="jersey, rib, garter"):
        knit_pattern("tuck")
    with pytest.raises(ValueError, match="unknown knit pattern"):
        KnitGeometry(pattern="tuck")


def test_the_face_takes_the_stitch_above_on_a_head_and_the_stitch_below_on_a_sinker():
    """Course 1 of garter: its heads belong to purl stitches (course 1), its sinkers to knit ones (course 0);
    rib: the sinker between a knit and a purl column switches face half-way. Away from the switches the
    face is +-1 to within tanh's tail."""
    heads, sinkers = 2 * math.pi * np.arange(4), 2 * math.pi * np.arange(4) + math.pi
    garter, rib = knit_pattern("garter"), knit_pattern("rib")
    assert garter.face(heads, 1) == pytest.approx(-1.0, abs=1e-12)
    assert garter.face(sinkers, 1) == pytest.approx(1.0, abs=1e-12)
    assert rib.face(heads, 0).tolist() == pytest.approx([1.0, -1.0, 1.0, -1.0], abs=1e-12)
    assert rib.face(sinkers, 0) == pytest.approx(0.0, abs=1e-12)  # the mid-plane, between a knit and a purl leg
    off = sinkers + 3 * FACE_SWITCH
    assert rib.face(off, 0) == pytest.approx(-rib.face(sinkers - 3 * FACE_SWITCH, 0), abs=1e-12)
    assert np.all(np.abs(rib.face(off, 0)) > 0.99)
    assert knit_pattern("jersey").face(np.linspace(-3, 30, 50), 4).tolist() == [1.0] * 50


@pytest.fixture(scope="module", params=list(PATTERNS))
def knit(request):
    """Each pattern built as the stretch builds it at l_y/l0 = 0.25: the widest l_x/l0 <= 0.30 whose loops
    reach build_loop_overlap past the next course (jersey: 0.30)."""
    overlap = build_loop_overlap(kl.NYLON, request.param)
    lx = widest_fitting_width(0.30, 0.25, kl.NYLON, 36, min_loop_overlap=overlap, pattern=request.param)
    return build_knit(KnitGeometry(n_x=6, n_y=4, l_x=lx * L0, l_y=0.25 * L0, resolution=36,
                                   pattern=request.param))


def test_each_loop_threads_the_head_below_it_the_way_its_stitch_says(knit):
    """Loop (r+1, i) threads head (r, i) exactly (two opposite piercings), moving to -z for a knit stitch
    and to +z for a purl one; it does not touch the heads beside it. One yarn per course."""
    g = knit.geometry
    pattern = knit_pattern(g.pattern)
    assert len(knit.courses) == g.n_y and knit.rods.model.n_yarns == g.n_y + 2
    for r in range(g.n_y - 1):
        for i in range(1, g.n_x - 1):
            ring, arc = head_ring(knit, r, i), loop_arc(knit, r + 1, i)
            assert piercings(ring, arc) == (2, 0), (r, i)
            assert threading_direction(ring, arc) == -pattern.stitch(r, i), (r, i)
            for other in (i - 1, i + 1):
                assert piercings(ring, loop_arc(knit, r + 1, other))[0] == 0, (r, i, other)


def test_no_two_yarns_overlap_as_built(knit):
    """Non-neighbouring yarn axes >= 1.5 d apart (measured at l_y/l0 0.25: jersey 1.59 d, rib 2.4 d, garter 2.2 d)."""
    s = knit.rods
    c = make_contacts(s, ContactModel(stiffness=1.0, skin=3 * D))
    assert refresh_contacts(s.state.x, s.model.edge_a, s.model.edge_b, s.model.edge_shift, c, s.state.v, 0.0)
    dists = [segment_distance(s.state.x, s.model.edge_a, s.model.edge_b, s.model.edge_shift, i, j)[0]
             for i, j in c.pairs[: c.n_pairs[0]]]
    assert min(dists) * kl.units.LENGTH > 1.5 * D


def test_each_stitch_of_a_pattern_holds_l0_on_average(knit):
    """The mean yarn per stitch over the knit is l0 (a pattern's repeat, not each stitch: the face's
    switches take a little yarn)."""
    g = knit.geometry
    lengths = []
    for k in range(g.n_y):
        x = knit.rods.state.x[knit.course_nodes(k)] * kl.units.LENGTH
        lengths.append(np.linalg.norm(np.diff(x, axis=0), axis=1).sum() / g.n_x)
    assert np.mean(lengths) == pytest.approx(L0, rel=2e-3)


def test_a_band_of_rib_in_jersey_threads_its_own_courses_as_rib_and_the_rest_as_jersey():
    """A jersey of 6 x 6 with courses 2 and 3 knitted in rib: the loops drawn through the heads of courses 2
    and 3 thread as rib's columns say, every other as jersey's; the face of course 2's lower half (its
    sinkers, on jersey's course 1) is jersey's."""
    band = fabric_pattern("jersey", ("rib", 2, 2))
    assert band.stitch(np.arange(6)[:, None], np.arange(2)).tolist() == [[1, 1], [1, 1], [1, -1], [1, -1], [1, 1],
                                                                          [1, 1]]
    overlap = build_loop_overlap(kl.NYLON, "jersey", "rib")
    lx = widest_fitting_width(0.30, 0.25, kl.NYLON, 36, min_loop_overlap=overlap, pattern="jersey")
    knit = build_knit(KnitGeometry(n_x=6, n_y=6, l_x=lx * L0, l_y=0.25 * L0, resolution=36,
                                   band=("rib", 2, 2)))
    for r in range(5):
        for i in range(1, 5):
            ring, arc = head_ring(knit, r, i), loop_arc(knit, r + 1, i)
            assert piercings(ring, arc) == (2, 0), (r, i)
            assert threading_direction(ring, arc) == -band.stitch(r, i), (r, i)
    sinkers = 2 * math.pi * np.arange(6) + math.pi
    assert band.face(sinkers, 2) == pytest.approx(1.0, abs=1e-12)


def test_a_band_of_no_courses_is_refused():
    with pytest.raises(ValueError, match="at least one"):
        fabric_pattern("jersey", ("rib", 2, 0))
