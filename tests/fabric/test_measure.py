"""Observables on synthetic data: laddered-cell detection, the front, v_lad, tension, periodicity."""

from __future__ import annotations

import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.fabric.measure import (
    cell_overlap,
    ladder_front,
    loop_sequence,
    laddered_cells,
    laddering_column,
    front_arrivals,
    front_step_speeds,
    laddering_velocity,
    mean_front_speed,
    periodicities,
    tension_per_thread,
)
from knitlad.fabric.scenes.knit import KnitGeometry, build_knit
from knitlad.engine.state import cut_edge

L0 = kl.NYLON.stitch_length


@pytest.fixture(scope="module")
def knit():
    return build_knit(KnitGeometry(n_x=6, n_y=6, l_x=0.3 * L0, l_y=0.25 * L0, resolution=24))


def rows_of(knit, x):
    s = knit.rods.model
    return [x[s.yarn_start[y]: s.yarn_start[y + 1]] for y in knit.courses + [knit.bars[1]]]


def unit(knit):
    g = knit.geometry
    return g.column_x(np.arange(g.n_x)) / kl.units.LENGTH, g.l_x / kl.units.LENGTH, g.l_y / kl.units.LENGTH


def test_an_intact_knit_has_no_laddered_cell(knit):
    cols, lx, ly = unit(knit)
    overlap = cell_overlap(rows_of(knit, knit.rods.state.x), cols, lx)
    assert np.all(overlap > 0.1 * ly)
    assert not laddered_cells(overlap, ly).any()


def test_a_flattened_head_is_detected_as_exactly_one_laddered_cell(knit):
    """Pull the head of course 2 at column 3 down onto the course line: that cell, and only it."""
    cols, lx, ly = unit(knit)
    x = knit.rods.state.x.copy()
    nodes = knit.course_nodes(2)
    course = x[nodes]
    head = np.abs(course[:, 0] - cols[3]) < 0.45 * lx
    course[head, 1] = np.minimum(course[head, 1], 2 * ly - 0.3 * ly)
    x[nodes] = course
    lad = laddered_cells(cell_overlap(rows_of(knit, x), cols, lx), ly)
    assert lad[2, 3]
    assert lad.sum() == 1


def test_ladder_front_follows_the_run_from_the_cut_across_small_gaps():
    lad = np.zeros((14, 5), dtype=bool)
    lad[5:8, 2] = True  # cut row 4: the cell just above still holds, then three undone
    assert ladder_front(lad, 2, 4) == (3, 0)
    lad[12, 2] = True  # beyond a gap of four intact cells: not part of this ladder
    assert ladder_front(lad, 2, 4) == (3, 0)
    lad[2:4, 2] = True
    assert ladder_front(lad, 2, 4) == (3, 2)
    assert ladder_front(lad, 1, 4) == (0, 0)


def test_the_followed_column_is_the_one_whose_ladder_ran_farthest_up():
    # 20 x 20 at f_x 13.6: the left column's ladder ran 8 up and 3 down, the right one's 9 up
    # (to the top course) and 2 down; up + down ties at 11 and would follow the left one
    assert laddering_column([(8, 3), (9, 2)]) == 1
    assert laddering_column([(9, 2), (8, 3)]) == 0
    assert laddering_column([(5, 1), (5, 4)]) == 1  # same upward extent: the longer downward one
    assert laddering_column([(5, 4), (5, 4)]) == 0


def test_laddering_velocity_recovers_a_constant_front_speed():
    """A front advancing one stitch every 0.1 ms with jitter: v = l_y / 0.1 ms within 1 %."""
    rng = np.random.default_rng(0)
    t = np.arange(0, 2e-3, 5e-6)
    front = np.floor(t / 1e-4 + 0.05 * rng.standard_normal(t.size)).clip(min=0)
    v = laddering_velocity(t, front, l_y=2.5e-3)
    assert v == pytest.approx(2.5e-3 / 1e-4, rel=0.01)
    assert np.isnan(laddering_velocity(t[:10], front[:10], l_y=2.5e-3))  # never reaches stitch 10


def test_tension_per_thread_averages_the_two_ends():
    r = np.zeros((6, 3))
    r[[0, 1], 0] = -2.0  # left ends pulled outward
    r[[4, 5], 0] = 2.0
    assert tension_per_thread(r, np.array([0, 1]), np.array([4, 5]), f0=0.5) == pytest.approx(4.0)


def test_periodicities_of_the_built_knit(knit):
    cols, lx, ly = unit(knit)
    mlx, mly = periodicities(rows_of(knit, knit.rods.state.x)[:-1], cols, lx)
    assert mlx == pytest.approx(lx, rel=1e-3) and mly == pytest.approx(ly, rel=1e-3)


def test_a_ribs_width_is_fitted_over_columns_of_one_stitch():
    """Heads at i l_x, those of odd columns (a rib's purl) 0.2 l_x off to the right: over the central columns 2 to
    5 of eight, an even count, the slope of all of them is tilted by the offsets (1.04 l_x); over the columns of one
    stitch of the repeat it is l_x."""
    lx, n = 1.0, 8
    column_x = np.arange(n) * lx
    course = np.array([[i * lx + (0.2 * lx if i % 2 else 0.0), 1.0, 0.0] for i in range(n)])
    rows = [course + [0, k, 0] for k in range(4)]
    tilted, _ = periodicities(rows, column_x, lx)
    ribbed, _ = periodicities(rows, column_x, lx, repeat=2)
    assert tilted == pytest.approx(1.04 * lx, rel=1e-9)
    assert ribbed == pytest.approx(lx, rel=1e-12)


def test_cut_edge_splits_a_yarn_and_frees_its_ends(knit):
    s = knit.rods.model
    y = knit.courses[2]
    start = int(s.yarn_start[y])
    edge = int(np.flatnonzero(s.edge_a == start + 30)[0])
    cut = cut_edge(knit.rods, edge).model
    assert cut.n_yarns == s.n_yarns + 1
    assert cut.edge_a.shape[0] == s.edge_a.shape[0] - 1
    assert cut.hinge_e0.shape[0] == s.hinge_e0.shape[0] - 2
    assert cut.yarn_of(start + 31) == (y + 1, 0)
    # no hinge bends across the cut, and every hinge still joins two consecutive edges
    assert not np.any((cut.edge_b[cut.hinge_e0] == start + 31) & (cut.edge_a[cut.hinge_e0] == start + 30))
    assert np.all(cut.edge_b[cut.hinge_e0] == cut.edge_a[cut.hinge_e1])


def test_each_course_carries_its_own_tension_and_their_mean_is_the_knit_s():
    """Three courses clamped by two nodes at each end, pulled by 2, 4 and 6 f0 (the right ends along +x,
    the left along -x, split unevenly over the clamp's two nodes): course_tensions gives 2, 4, 6 and
    tension_per_thread their mean, 4."""
    from knitlad.fabric.measure import course_tensions, tension_per_thread

    f0 = 0.0148
    left, right = np.array([[0, 1], [2, 3], [4, 5]]), np.array([[6, 7], [8, 9], [10, 11]])
    reactions = np.zeros((12, 3))
    for course, pull in enumerate((2.0, 4.0, 6.0)):
        reactions[left[course], 0] = -pull * f0 * np.array([0.3, 0.7])
        reactions[right[course], 0] = pull * f0 * np.array([0.9, 0.1])
    np.testing.assert_allclose(course_tensions(reactions, left, right, f0), [2.0, 4.0, 6.0])
    assert tension_per_thread(reactions, left, right, f0) == pytest.approx(4.0)


def cut_at_row_4_between_columns_2_and_3():
    """A hand-made run on 9 rows x 6 columns, the cut at row 4's sinker between columns 2 and 3: when the cut
    thread left each needle loop (``withdrawn``) and when each cell came undone (``undone``), empty."""
    return np.full(6, np.nan), np.full((9, 6), np.nan)


def test_the_loops_are_named_by_where_the_cut_thread_went_and_the_ladders_by_the_loop_they_ran_from():
    """The cut thread leaves column 3 first: loop (1) is column 3 and the ladder up it is (1)'s; the heads
    below the cut, row 3 of columns 2 and 3, are loops (2)/(3), and a ladder runs down once row 2 comes undone;
    the thread's next needle loops are column 2 (its left end's first) and column 4 (its right end's second):
    a ladder up either is (4)/(5). In that order the sequence is the paper's."""
    withdrawn, undone = cut_at_row_4_between_columns_2_and_3()
    withdrawn[3] = 1e-4
    undone[4, 3], undone[5:8, 3] = 1e-4, [2e-4, 3e-4, 4e-4]  # the cut course's cell, then the ladder up (1)
    undone[3, 2:4] = 0.5e-4  # the heads below the cut drop with it: freed, not yet a ladder
    r = loop_sequence(withdrawn, undone, cut_row=4, cut_column=3)
    assert r["loop1_column"] == 3 and r["sequence"] == "(1)" and r["down_from_2_3_s"] != r["down_from_2_3_s"]
    undone[0:3, 2] = [9e-4, 8e-4, 7e-4]  # row 2 and below in column 2: a ladder down from (2)/(3)
    withdrawn[2], undone[5, 2] = 1.0e-3, 1.1e-3  # the left end leaves column 2 and the course above ladders
    r = loop_sequence(withdrawn, undone, cut_row=4, cut_column=3)
    assert r["sequence"] == "(1), (2)/(3), (4)/(5)" and r["paper_order"]
    assert (r["up_from_1_s"], r["down_from_2_3_s"], r["up_from_4_5_s"]) == pytest.approx((2e-4, 7e-4, 1.1e-3))
    assert not r["cut_thread_held"] and not r["hindered"] and r["other_ladders"] == 0


def test_a_ladder_before_loop_one_is_not_the_papers_order_and_one_away_from_the_cut_is_no_freed_loops():
    withdrawn, undone = cut_at_row_4_between_columns_2_and_3()
    withdrawn[3], undone[5, 3] = 5e-4, 6e-4  # loop (1) lets go late ...
    undone[2, 2] = 1e-4  # ... after a ladder ran down from (2)/(3)
    undone[6, 0] = 2e-4  # a ladder up column 0, which the cut thread never left
    r = loop_sequence(withdrawn, undone, cut_row=4, cut_column=3)
    assert r["sequence"] == "(2)/(3), (1)" and not r["paper_order"] and r["other_ladders"] == 1
    withdrawn[:] = np.nan  # the thread left no needle loop: no loop (1), whatever undid cells
    r = loop_sequence(withdrawn, undone, cut_row=4, cut_column=3)
    assert r["loop1_column"] == -1 and r["sequence"] == "(2)/(3)"


def test_the_cut_thread_held_in_loops_four_and_five_after_ladders_from_one_and_two_three_is_hindered():
    """The paper's appendix: "the second upward ladder that was expected to propagate was hindered because the
    cut thread got pinched in loops (4) and (5)"."""
    withdrawn, undone = cut_at_row_4_between_columns_2_and_3()
    withdrawn[2] = 1e-4  # loop (1): column 2, the left end's first; (4)/(5): column 3 and column 1
    undone[5:8, 2] = 2e-4  # the ladder up from (1)
    undone[0:3, 2], undone[0:3, 3] = 5e-4, 7e-4  # ladders down from (2) and (3)
    r = loop_sequence(withdrawn, undone, cut_row=4, cut_column=3)
    assert r["loop1_column"] == 2 and r["cut_thread_held"] and r["hindered"]
    withdrawn[3], undone[5, 3] = 1.0e-3, 1.2e-3  # the right end lets go of (4)/(5): a second upward ladder
    r = loop_sequence(withdrawn, undone, cut_row=4, cut_column=3)
    assert not r["cut_thread_held"] and not r["hindered"] and r["up_from_4_5_s"] == pytest.approx(1.2e-3)


def test_a_cell_whose_yarn_has_gone_is_destroyed_and_one_without_a_head_reading_is_not():
    """Three columns of two courses and the held top one. Course 0 pulled out of column 1 (a cut course's
    retracted yarn): cell (0, 1) is -inf, undone; the course above pulled out of both sides of column 2: cell
    (1, 2) is -inf too; a column whose head is not read (the yarn only at its edge) is NaN, not undone."""
    l_x, l_y = 1.0, 1.0
    columns = np.array([0.0, 1.0, 2.0])

    def course(y0, xs):
        t = np.linspace(-0.5, 2.5, 121)
        keep = np.zeros_like(t, dtype=bool)
        for lo, hi in xs:
            keep |= (t >= lo) & (t <= hi)
        # a head (+0.3 l_y) at each column, sinkers between
        return np.column_stack([t, y0 + 0.3 * np.cos(2 * np.pi * t), np.zeros_like(t)])[keep]

    rows = [course(0.0, [(-0.5, 0.55), (1.45, 2.5)]), course(0.7, [(-0.5, 1.35)]), course(1.4, [(-0.5, 2.5)])]
    overlap = cell_overlap(rows, columns, l_x)
    assert np.isneginf(overlap[0, 1]) and np.isneginf(overlap[1, 2])
    assert laddered_cells(overlap, l_y)[0, 1] and laddered_cells(overlap, l_y)[1, 2]
    assert not laddered_cells(overlap, l_y)[1, 0] and np.isfinite(overlap[1, 0])
    # course 0 absent within l_x/4 of column 0 but there within 0.4 l_x (an end passing): no head, not gone
    gap = [course(0.0, [(-0.5, -0.3), (0.3, 0.55), (1.45, 2.5)]), rows[1], rows[2]]
    overlap = cell_overlap(gap, columns, l_x)
    assert np.isnan(overlap[0, 0]) and not laddered_cells(overlap, l_y)[0, 0]


def test_a_cell_once_undone_is_hooked_again_above_its_sinkers_and_between_below_them():
    from knitlad.fabric.measure import between_cells, rehooked_cells

    overlap = np.array([[0.3, 0.1, -0.1, -0.3, -np.inf]])
    ever = np.array([[False, True, True, True, True]])
    assert rehooked_cells(overlap, ever).tolist() == [[False, True, False, False, False]]
    assert between_cells(overlap, ever, 1.0).tolist() == [[False, False, True, False, False]]
    assert laddered_cells(overlap, 1.0).tolist() == [[False, False, False, True, True]]


def test_the_front_is_read_on_the_mid_line_in_the_labs_frame():
    """Two courses crossing the mid-line x = 0: the highest crossing, interpolated; a gap between two pieces
    (farther apart than an edge) crosses nothing. The front's height is the first course past the reach, and
    its speed the slope of that height while the reach runs from stitch ``first`` to ``last``."""
    from knitlad.fabric.measure import front_heights, front_speed, midline_heights

    loop = np.array([[-1.0, 0.0, 0], [-0.5, 1.0, 0], [0.5, 2.0, 0], [1.0, 0.0, 0]])  # crosses x = 0 at y = 1.5
    cut = np.array([[-1.0, 5.0, 0], [-0.2, 5.0, 0], [0.2, 7.0, 0], [1.0, 7.0, 0]])  # pieces 0.4 apart, no edge
    heights = midline_heights([loop, cut], np.array([0.0]), longest_edge=1.5)
    assert heights[0, 0] == pytest.approx(1.5) and np.isnan(heights[1, 0])
    # a front running 1 stitch per ms over courses 1 apart, the cloth above it moving down at 0.2 per ms
    t = np.arange(12) * 1e-3
    extent = np.arange(12)
    courses = np.arange(20)[None, :] - 0.2 * t[:, None] * 1e3 + 0.0
    y = front_heights(courses, extent, cut_row=0)
    assert y[3] == pytest.approx(4.0 - 0.6)
    assert front_speed(t, y, extent, 2, 10) == pytest.approx(0.8e3)  # 1 - 0.2 course per ms, in the lab
    assert math.isnan(front_speed(t, y, np.minimum(extent, 9), 2, 10))  # it never reached stitch 10
    # arrested at stitch 6 while the cloth goes on moving: the fit ends at the arrival at stitch 6
    stopped = np.minimum(extent, 6)
    assert front_speed(t, front_heights(courses, stopped, cut_row=0), stopped, 2, 6) == pytest.approx(0.8e3)


def test_damage_is_split_into_the_cut_row_the_cut_s_recoil_and_what_the_ladder_released():
    """Eq. 1 counts l0 - l_x per cell released into a loaded course: the cut row's cells and those undone with
    the cut (within 0.1 ms) are counted apart from the ladder's own."""
    from knitlad.fabric.measure import damage_parts

    nan = math.nan
    undone_at = np.array([[nan, 9e-4, nan],   # row 0: the downward ladder, later
                          [nan, 5e-5, nan],   # row 1: undone with the cut
                          [2e-5, 0.0, 3e-4],  # row 2: the cut row, whenever its cells go
                          [nan, 1e-4, nan],   # row 3: at 0.1 ms exactly, still the cut's
                          [nan, 4e-4, 6e-4]])  # row 4: the upward ladder
    assert damage_parts(undone_at, cut_row=2) == {"cut_row": 3, "immediate": 2, "released": 3, "released_taut": -1}
    assert damage_parts(undone_at, cut_row=2, immediate_s=0.0) == {"cut_row": 3, "immediate": 0, "released": 5,
                                                                   "released_taut": -1}
    parts = damage_parts(undone_at, cut_row=0)
    assert parts["cut_row"] + parts["immediate"] + parts["released"] == np.isfinite(undone_at).sum()
    taut = np.zeros_like(undone_at, dtype=bool)
    taut[0, 1] = taut[2, 0] = taut[4, 2] = True  # a released cell, a cut-row cell, a released cell
    assert damage_parts(undone_at, cut_row=2, taut=taut)["released_taut"] == 2


def test_a_cells_bar_is_taut_once_its_head_has_dropped_three_quarters_of_a_course():
    """An intact cell overlaps by +0.2 to +0.4 l_y, a straight bar by about -l_y: laddered from -0.25 l_y,
    taut from -0.75 l_y."""
    from knitlad.fabric.measure import laddered_cells, taut_cells

    overlap = np.array([[0.3, -0.3, -0.7, -0.8, -1.0]])
    assert laddered_cells(overlap, 1.0).tolist() == [[False, True, True, True, True]]
    assert taut_cells(overlap, 1.0).tolist() == [[False, False, False, True, True]]


def test_the_transverse_tension_is_the_mean_pull_of_the_held_nodes_above_and_below_per_column():
    from knitlad.fabric.measure import transverse_tension

    reactions = np.zeros((6, 3))
    reactions[[0, 1], 1] = -2.0  # below the centre line, pulled down by the knit: the support pulls down
    reactions[[4, 5], 1] = 2.0
    held, y = np.array([0, 1, 4, 5]), np.array([-1.0, -1.0, 1.0, 1.0])
    assert transverse_tension(reactions, held, y, n_x=4, f0=0.5) == pytest.approx(4.0 / (4 * 0.5))


def test_the_fronts_arrivals_step_speeds_and_mean_speed_of_a_stick_slip_front():
    """A front that slips a stitch every 0.1 ms but stalls 0.4 ms at stitch 3: the step speeds are l_y/0.1 ms
    but one, l_y/0.5 ms; the mean speed from stitch 1 to the last is 5 l_y over 0.9 ms."""
    arrive = np.array([0.0, 0.1, 0.2, 0.7, 0.8, 0.9]) * 1e-3  # stitches 1 to 6
    t = np.arange(0.0, 1.0e-3, 1e-6)
    front = np.searchsorted(arrive, t, side="right")  # stitches reached by each time
    assert front_arrivals(t, front) == pytest.approx(arrive, abs=1.1e-6)
    l_y = 2.5e-3
    speeds = front_step_speeds(arrive, l_y)
    assert speeds == pytest.approx([25.0, 25.0, 5.0, 25.0, 25.0])
    assert mean_front_speed(arrive, l_y) == pytest.approx(5 * l_y / 0.9e-3)
    assert np.isnan(mean_front_speed(arrive[:1], l_y))


def test_the_threshold_is_the_mean_arrest_tension_of_the_runs_that_laddered_and_its_flatness_a_slope():
    """f_thr = mean f_fin over the runs that laddered and arrested (the paper's definition), its scatter and
    standard error; a flat f_fin has a slope within its error of 0, a rising one does not."""
    from knitlad.fabric.measure import arrest_threshold

    fx_ini = np.array([1.0, 3.0, 5.0, 7.0, 9.0, 11.0])
    flat = np.array([9.9, 2.1, 1.9, 2.0, 2.2, 1.8])  # the first did not ladder: left out
    laddered = np.array([False, True, True, True, True, True])
    r = arrest_threshold(fx_ini, flat, laddered, np.ones(6, dtype=bool))
    assert r["runs"] == 5 and r["fx_thr"] == pytest.approx(2.0) and r["fx_thr_sd"] == pytest.approx(np.std(flat[1:], ddof=1))
    assert abs(r["slope"]) < 2 * r["slope_se"]
    rising = 1.0 + 0.2 * fx_ini
    r = arrest_threshold(fx_ini, rising + np.array([0, 0.01, -0.01, 0.01, -0.01, 0]), laddered,
                         np.array([True] * 5 + [False]))  # the last did not arrest: left out
    assert r["runs"] == 4 and r["slope"] == pytest.approx(0.2, abs=0.01) and r["slope"] > 5 * r["slope_se"]
    assert math.isnan(arrest_threshold([1.0], [2.0], [True], [False])["fx_thr"])
