"""Observables of the laddering experiment (paper: main text and Fig. 3).

* tension per thread f_x = F_x / (n_y f0), F_x from the reaction forces on the
  held ends of all courses;
* the periodicities l_x (spacing of the heads along a course) and l_y (spacing
  of the courses), measured away from the edges;
* laddered cells: cell (r, i) (course r, column i) holds the loop of course r+1
  while the head of course r at column i rises above the sinker loops of course
  r+1 on either side of that column (the two loops overlap in y). A laddered
  cell is a straight bar and the overlap is about -l_y. The criterion is geometric,
  not by node index, because the yarn slides through the stitches;
* the ladder front along a column, and v_lad as the slope of the front from
  stitch 2 to stitch 10 (paper, Fig. 3d), normalised by c_b.
"""

from __future__ import annotations

import numpy as np


def tension_per_thread(reactions_N: np.ndarray, left_end: np.ndarray, right_end: np.ndarray, f0: float,
                       left_share=1.0, right_share=1.0) -> float:
    """f_x = F_x / (n_y f0) with F_x the mean of the right-end pull and minus the left-end pull [N].

    ``left_end``, ``right_end``: (n_y,) or (n_y, k) node indices, the held nodes of each course's
    ends (k = 2 for clamped ends: their reactions together are the end's force). ``left_share``,
    ``right_share``: the share of each node's reaction its course carries (a clip that joins two
    courses of one yarn: half each), broadcast against the ends.
    """
    F_x = 0.5 * ((reactions_N[right_end, 0] * right_share).sum() - (reactions_N[left_end, 0] * left_share).sum())
    return float(F_x / (len(right_end) * f0))


def transverse_tension(reactions_N: np.ndarray, held: np.ndarray, y: np.ndarray, n_x: int, f0: float) -> float:
    """f_y = F_y / (n_x f0), the pull across the courses per column: F_y the mean of the y-reactions of the held
    nodes above the box's centre line and minus those below it (the bars, and the course ends' clamps, which
    hold y too) [-]. ``held``: node indices, ``y``: their heights [any unit]."""
    centre = 0.5 * (y.min() + y.max())
    F_y = 0.5 * (reactions_N[held[y > centre], 1].sum() - reactions_N[held[y < centre], 1].sum())
    return float(F_y / (n_x * f0))


def course_tensions(reactions_N: np.ndarray, left_end: np.ndarray, right_end: np.ndarray, f0: float,
                    left_share=1.0, right_share=1.0) -> np.ndarray:
    """Each course's own f_x: its right-end pull and minus its left-end pull, averaged, over f0 ((n_y,) [-]).

    Their mean is :func:`tension_per_thread` (the shares as there). A ladder relaxes the courses it crosses
    and leaves the others near f_x^ini, so the mean is a reading of the arrest only where every course was
    crossed.
    """
    right = (reactions_N[right_end, 0] * right_share).reshape(len(right_end), -1).sum(axis=1)
    left = (reactions_N[left_end, 0] * left_share).reshape(len(left_end), -1).sum(axis=1)
    return 0.5 * (right - left) / f0


def periodicities(course_positions: list[np.ndarray], column_x: np.ndarray, l_x_guess: float,
                  margin: float = 0.25) -> tuple[float, float]:
    """(l_x, l_y) [same unit as the positions] measured on the central courses and columns.

    l_y: mean spacing of the courses' mean heights. l_x: slope of the head
    apex x (highest node within l_x/4 of each column's nominal centre) against
    the column index, so an offset of the nominal centres does not bias it.
    """
    n = len(course_positions)
    lo, hi = int(margin * n), max(int((1 - margin) * n), int(margin * n) + 2)
    central = course_positions[lo:hi]
    means = np.array([c[:, 1].mean() for c in central])
    l_y = float(np.mean(np.diff(means)))
    n_cols = column_x.shape[0]
    c_lo, c_hi = int(margin * n_cols), max(int((1 - margin) * n_cols), int(margin * n_cols) + 2)
    slopes = []
    for c in central:
        cols, xs = [], []
        for i in range(c_lo, c_hi):
            near = np.flatnonzero(np.abs(c[:, 0] - column_x[i]) < 0.25 * l_x_guess)
            if near.size:
                cols.append(i)
                xs.append(c[near[np.argmax(c[near, 1])], 0])
        if len(cols) >= 2:
            slopes.append(np.polyfit(cols, xs, 1)[0])
    l_x = float(np.mean(slopes)) if slopes else float("nan")
    return l_x, l_y


def _extreme_near(x: np.ndarray, y: np.ndarray, targets: np.ndarray, w: float, largest: bool) -> np.ndarray:
    """For each of the sorted ``targets``, the max (``largest``) or min of y over the points with
    |x - target| < w; NaN where there is none. Targets at least w apart, so a point is near at
    most the two targets either side of it."""
    n = targets.shape[0]
    out = np.full(n, -np.inf if largest else np.inf)
    after = np.searchsorted(targets, x)
    for k in (after - 1, after):
        near = (k >= 0) & (k < n) & (np.abs(x - targets[np.clip(k, 0, n - 1)]) < w)
        (np.maximum if largest else np.minimum).at(out, k[near], y[near])
    out[np.isinf(out)] = np.nan
    return out


def cell_overlap(course_positions: list[np.ndarray], column_x: np.ndarray, l_x: float) -> np.ndarray:
    """Overlap (n_courses - 1, n_columns) of the head of course r over the sinkers of course r+1 [length].

    ``course_positions`` run bottom to top and include the held edge course on
    top, so every free course has a course above it. Positive: the cell holds.
    The head of column i is the highest point of course r within l_x/4 of the column's x;
    its sinkers are the lowest points of course r+1 within l_x/4 of x -+ l_x/2.
    """
    n_rows = len(course_positions) - 1
    n_cols = column_x.shape[0]
    w = 0.25 * l_x
    out = np.full((n_rows, n_cols), np.nan)
    for r in range(n_rows):
        below = course_positions[r]
        above = course_positions[r + 1]
        head = _extreme_near(below[:, 0], below[:, 1], column_x, w, largest=True)
        left = _extreme_near(above[:, 0], above[:, 1], column_x - 0.5 * l_x, w, largest=False)
        right = _extreme_near(above[:, 0], above[:, 1], column_x + 0.5 * l_x, w, largest=False)
        # the outer side of an edge column is the course's tail, not a sinker
        left[0] = np.nan
        right[-1] = np.nan
        sinker = np.fmax(left, right)  # the higher sinker, or the one there is
        out[r] = head - sinker
    return out


def laddered_cells(overlap: np.ndarray, l_y: float, margin: float = 0.25) -> np.ndarray:
    """Boolean map of undone cells: the head has dropped below the course above's sinkers.

    An intact cell overlaps by +0.2 to +0.4 l_y, a laddered one (a straight bar)
    by about -l_y; the threshold -``margin`` l_y keeps a vibrating intact loop
    from flickering into the laddered state. Cells with no data count as intact.
    """
    return overlap < -margin * l_y


TAUT_BAR = 0.75  # a laddered cell's bar is taut once its head has dropped this far below the sinkers [l_y]


def taut_cells(overlap: np.ndarray, l_y: float, fraction: float = TAUT_BAR) -> np.ndarray:
    """Boolean map of cells whose bar is taut: the head has dropped ``fraction`` l_y below the course above's
    sinkers (a straight bar: about -l_y). A cell counts as laddered from -0.25 l_y (:func:`laddered_cells`),
    before its bar is straight, when it may have released less than l0 - l_x: Eq. 1 counts l0 - l_x per cell."""
    return overlap < -fraction * l_y


def ladder_front(laddered: np.ndarray, column: int, start_row: int, max_gap: int = 2) -> tuple[int, int]:
    """(upward, downward) extent, in stitches from ``start_row``, of the ladder in ``column``.

    The front is the farthest undone cell reached from the cut through gaps of
    at most ``max_gap`` intact cells: a loop next to the cut can hold a little
    longer than the ones the ladder has already passed (seen in 42 x 42 runs),
    and must not stop the front from being seen.
    """
    col = laddered[:, column]

    def reach(step: int) -> int:
        extent = 0
        gap = 0
        r = start_row + step
        k = 1
        while 0 <= r < col.shape[0]:
            if col[r]:
                extent = k
                gap = 0
            else:
                gap += 1
                if gap > max_gap:
                    break
            r += step
            k += 1
        return extent

    return reach(+1), reach(-1)


def laddering_column(final_fronts: list[tuple[int, int]]) -> int:
    """Index of the column to follow, given each candidate's final (upward, downward) extent.

    The column whose ladder ran farthest up (v_lad is the speed of the upward
    front, paper Fig. 3d), its downward extent breaking ties, then the first.
    Ranking by up + down instead lets a longer downward ladder in the column
    beside the upward one take its place (seen on 20 x 20 at f_x 13.6).
    """
    return max(range(len(final_fronts)), key=lambda c: tuple(final_fronts[c]))  # max keeps the first of equals


def laddering_velocity(times: np.ndarray, front: np.ndarray, l_y: float, first: int = 2, last: int = 10) -> float:
    """v_lad = slope of the front from stitch ``first`` to ``last`` (paper Fig. 3d) [l_y / time unit].

    ``front`` is the ladder extent (stitches) at each time; the slope is the
    least-squares fit of front against time over the samples where
    first <= front <= last. NaN if the front never covers that range.
    """
    times = np.asarray(times, dtype=float)
    front = np.asarray(front, dtype=float)
    if front.size == 0 or last < first or np.nanmax(front) < last:
        return float("nan")
    # first arrival at each stitch level: a monotone front, robust to flicker
    levels = np.arange(first, last + 1)
    arrival = np.array([times[np.argmax(front >= k)] for k in levels])
    slope = np.polyfit(arrival, levels, 1)[0]
    return float(slope * l_y)


def front_arrivals(times: np.ndarray, front: np.ndarray) -> np.ndarray:
    """When the front first reached 1, 2, ... stitches (its farthest), from its extent at each time [s]."""
    times = np.asarray(times, dtype=float)
    front = np.asarray(front, dtype=float)
    top = int(np.nanmax(front)) if front.size else 0
    return np.array([times[np.argmax(front >= k)] for k in range(1, top + 1)])


def front_step_speeds(arrivals: np.ndarray, l_y: float) -> np.ndarray:
    """The front's speed over each stitch it crossed, l_y over the time between its arrivals at stitch k and
    k + 1 (``arrivals`` from :func:`front_arrivals`). A stick-slip front is a mixture of fast slips and
    stalls: its distribution, not one fit, is what a resolution study can compare."""
    steps = np.diff(np.asarray(arrivals, dtype=float))
    with np.errstate(divide="ignore"):
        return np.where(steps > 0, l_y / np.where(steps > 0, steps, 1.0), np.inf)


def mean_front_speed(arrivals: np.ndarray, l_y: float, first: int = 1) -> float:
    """The front's mean speed from stitch ``first`` to the farthest it reached: (stitches run) l_y over the
    time it took, stalls included (NaN if it ran no stitch past ``first``). Unlike v_lad's fit over
    stitches 2 to 10 it also measures a ladder that arrested."""
    arrivals = np.asarray(arrivals, dtype=float)
    if arrivals.size <= first:
        return float("nan")
    return float((arrivals.size - first) * l_y / (arrivals[-1] - arrivals[first - 1]))


def node_strain_and_curvature(x: np.ndarray, edges: np.ndarray, rest: np.ndarray):
    """Per node: the mean axial strain of its edges, and the turning angle over the Voronoi length."""
    n = x.shape[0]
    e = x[edges[:, 1]] - x[edges[:, 0]]
    length = np.linalg.norm(e, axis=1)
    strain_e = length / rest - 1.0
    strain = np.zeros(n)
    count = np.zeros(n)
    for side in (0, 1):
        np.add.at(strain, edges[:, side], strain_e)
        np.add.at(count, edges[:, side], 1.0)
    strain /= np.maximum(count, 1.0)
    curvature = np.zeros(n)
    # consecutive edges share a node: edge k ends where edge k + 1 starts
    joined = edges[:-1, 1] == edges[1:, 0]
    k = np.flatnonzero(joined)
    t0 = e[k] / length[k, None]
    t1 = e[k + 1] / length[k + 1, None]
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", t0, t1), -1.0, 1.0))
    curvature[edges[k, 1]] = angle / (0.5 * (length[k] + length[k + 1]))
    return strain, curvature


def ladders_started(undone_at: np.ndarray, cut_row: int) -> list[dict]:
    """The ladders a cut started, read from the time each cell came undone (``undone_at`` (n_rows, n_cols)
    [s], NaN where it never did; rows bottom to top, the cut's row ``cut_row``).

    A ladder is a column's undone cells above the cut row (upward, as :func:`ladder_front` counts) or below
    it (downward). Each gets ``column``, ``direction`` (+1 up, -1 down), ``start_s`` (its first cell),
    ``cells`` and ``loop``, the freed loop of the paper's Fig. 2d that started it: the first upward ladder
    is loop (1), a downward ladder loop (2) or (3), a later upward one loop (4) or (5). Ordered by start.
    """
    ladders = []
    for column in range(undone_at.shape[1]):
        for direction, rows in ((1, slice(cut_row + 1, None)), (-1, slice(0, cut_row))):
            times = undone_at[rows, column]
            done = times[np.isfinite(times)]
            if done.size:
                ladders.append({"column": column, "direction": direction, "start_s": float(done.min()),
                                "cells": int(done.size)})
    ladders.sort(key=lambda lad: lad["start_s"])
    first_up = True
    for lad in ladders:
        if lad["direction"] < 0:
            lad["loop"] = "2/3"
        else:
            lad["loop"], first_up = ("1" if first_up else "4/5"), False
    return ladders


IMMEDIATE_S = 1e-4  # cells undone this soon after the cut come undone with it (the cut's own damage) [s]


def damage_parts(undone_at: np.ndarray, cut_row: int, immediate_s: float = IMMEDIATE_S,
                 taut: np.ndarray | None = None) -> dict[str, int]:
    """The undone cells split by what they free into the loaded knit (Eq. 1 counts l0 - l_x per cell released
    into a loaded course): ``cut_row``, the cells of the cut's own course (its yarn is cut: it frees no length
    into a loaded course); ``immediate``, the other cells undone within ``immediate_s`` of the cut (its
    recoil, not the ladder's run); ``released``, the rest, the ladder's own; with ``taut`` (the final map of
    :func:`taut_cells`), ``released_taut``: those of them whose bar is taut at the end (-1 without the map).
    ``undone_at`` (n_rows, n_cols) [s since the cut], NaN where a cell never came undone."""
    done = np.isfinite(undone_at)
    in_cut_row = np.zeros_like(done)
    in_cut_row[cut_row] = done[cut_row]
    immediate = done & ~in_cut_row & (undone_at <= immediate_s)
    released = done & ~in_cut_row & ~immediate
    return {"cut_row": int(in_cut_row.sum()), "immediate": int(immediate.sum()), "released": int(released.sum()),
            "released_taut": -1 if taut is None else int((released & taut).sum())}
