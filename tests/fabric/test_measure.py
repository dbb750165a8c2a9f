"""Observables on synthetic data: laddered-cell detection, the front, v_lad, tension, periodicity."""

from __future__ import annotations

import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.fabric.measure import (
    cell_overlap,
    ladder_front,
    ladders_started,
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


def test_the_loop_record_names_each_ladder_by_the_freed_loop_that_started_it():
    """A cut at row 4 between columns 2 and 3: column 2 ladders up first (loop 1), then both columns
    down (loops 2 and 3), then column 3 up (loop 4 or 5); cells of the cut row start no ladder."""
    at = np.full((9, 6), np.nan)
    at[5:8, 2] = [1e-4, 2e-4, 3e-4]           # up in column 2 from 0.1 ms
    at[4, 2] = 0.5e-4                           # the cut row's own cell
    at[2:4, 2] = [6e-4, 5e-4]                   # down in column 2 from 0.5 ms
    at[1:4, 3] = [9e-4, 8e-4, 7e-4]             # down in column 3 from 0.7 ms
    at[5, 3] = 1.2e-3                           # up in column 3 at 1.2 ms
    ladders = ladders_started(at, cut_row=4)
    assert [(lad["column"], lad["direction"], lad["loop"], lad["cells"]) for lad in ladders] == [
        (2, 1, "1", 3), (2, -1, "2/3", 2), (3, -1, "2/3", 3), (3, 1, "4/5", 1)]
    assert [lad["start_s"] for lad in ladders] == pytest.approx([1e-4, 5e-4, 7e-4, 1.2e-3])
    assert ladders_started(np.full((9, 6), np.nan), cut_row=4) == []


def test_one_upward_and_two_downward_ladders_are_the_hindered_pattern():
    """The paper's hindered laddering: the second upward ladder never starts (loops (4) and (5) held)."""
    at = np.full((9, 6), np.nan)
    at[5:8, 2] = 1e-4                      # loop (1): up in column 2
    at[2:4, 2], at[1:4, 3] = 5e-4, 7e-4    # loops (2) and (3): down in columns 2 and 3
    record = kl.LadderResult(settings=None, undone_at=at, cut_row=4).loop_record()
    assert record["hindered"] and (record["ladders_up"], record["ladders_down"]) == (1, 2)
    assert math.isnan(record["second_up_ms"]) and record["first_down_ms"] == pytest.approx(0.5)
    at[5, 3] = 1.2e-3                      # loop (4)/(5) lets go: a second upward ladder
    record = kl.LadderResult(settings=None, undone_at=at, cut_row=4).loop_record()
    assert not record["hindered"] and record["second_up_ms"] == pytest.approx(1.2)


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
