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
                  margin: float = 0.25, repeat: int = 1) -> tuple[float, float]:
    """(l_x, l_y) [same unit as the positions] measured on the central courses and columns.

    l_y: mean spacing of the courses' mean heights. l_x: slope of the head
    apex x (highest node within l_x/4 of each column's nominal centre) against
    the column index, so an offset of the nominal centres does not bias it. In a pattern whose repeat is
    ``repeat`` columns wide (rib: 2) only the columns of one stitch of the repeat are fitted: a purl head's apex
    sits off its column's centre by another amount than a knit head's, which over an even number of columns tilts
    the slope.
    """
    n = len(course_positions)
    lo, hi = int(margin * n), max(int((1 - margin) * n), int(margin * n) + 2)
    central = course_positions[lo:hi]
    means = np.array([c[:, 1].mean() for c in central])
    l_y = float(np.mean(np.diff(means)))
    n_cols = column_x.shape[0]
    c_lo, c_hi = int(margin * n_cols), max(int((1 - margin) * n_cols), int(margin * n_cols) + 2)
    if repeat > 1 and len(range(c_lo, c_hi, repeat)) < 2:  # too few central columns of one stitch: all of them
        c_lo, c_hi = 0, n_cols
    slopes = []
    for c in central:
        cols, xs = [], []
        for i in range(c_lo, c_hi, repeat):
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


# a course has left a column when none of its yarn lies within GONE_WINDOW l_x of the column's x (its needle loop's
# legs lie about l_x/4 from it); the course above holds a head no more when none of it lies within HOLDER_WINDOW l_x
# (its sinkers, l_x/2 from the column, and a little beyond: a retracting end has passed them)
GONE_WINDOW, HOLDER_WINDOW = 0.4, 0.6


def present_near(x: np.ndarray, targets: np.ndarray, w: float) -> np.ndarray:
    """For each target, whether any of the points ``x`` (1-d) lies within ``w`` of it."""
    ordered = np.sort(x)
    return np.searchsorted(ordered, targets + w, side="right") > np.searchsorted(ordered, targets - w, side="left")


def cell_overlap(course_positions: list[np.ndarray], column_x: np.ndarray, l_x: float) -> np.ndarray:
    """Overlap (n_courses - 1, n_columns) of the head of course r over the sinkers of course r+1 [length].

    ``course_positions`` run bottom to top and include the held edge course on
    top, so every free course has a course above it. Positive: the cell holds.
    The head of column i is the highest point of course r within l_x/4 of the column's x;
    its sinkers are the lowest points of course r+1 within l_x/4 of x -+ l_x/2.
    A cell whose yarn has gone is -inf, destroyed as a photograph shows it: course r has left the column (none
    of it within GONE_WINDOW l_x of its x: a cut course's yarn pulled out), or course r+1 has left both sides
    of it (none within HOLDER_WINDOW l_x: nothing holds the head). NaN: no reading (a head moved off its column), counted as intact.
    """
    n_rows = len(course_positions) - 1
    n_cols = column_x.shape[0]
    w = 0.25 * l_x
    gone_w = GONE_WINDOW * l_x
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
        head_gone = ~present_near(below[:, 0], column_x, gone_w)
        holder_gone = ~present_near(above[:, 0], column_x, HOLDER_WINDOW * l_x)
        out[r, head_gone | holder_gone] = -np.inf
    return out


UNDONE_MARGIN = 0.25  # a cell is undone once its head lies this far below the sinkers above it [l_y]


def laddered_cells(overlap: np.ndarray, l_y: float, margin: float = UNDONE_MARGIN) -> np.ndarray:
    """Boolean map of undone cells: the head has dropped below the course above's sinkers.

    An intact cell overlaps by +0.2 to +0.4 l_y, a laddered one (a straight bar)
    by about -l_y; the threshold -``margin`` l_y keeps a vibrating intact loop
    from flickering into the laddered state. Cells with no data count as intact; cells whose yarn has gone
    (-inf, :func:`cell_overlap`) as undone.
    """
    return overlap < -margin * l_y


def rehooked_cells(overlap: np.ndarray, ever: np.ndarray) -> np.ndarray:
    """Cells once undone (``ever``) whose head is back above the sinkers of the course above (overlap >= 0): hooked
    again, intact on a photograph."""
    return ever & (overlap >= 0.0)


def between_cells(overlap: np.ndarray, ever: np.ndarray, l_y: float, margin: float = UNDONE_MARGIN) -> np.ndarray:
    """Cells once undone whose head lies below the sinkers above it, but by less than the undone margin: neither
    hooked nor a bar."""
    return ever & (overlap < 0.0) & (overlap >= -margin * l_y)


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
    if len(levels) < 2 or np.ptp(arrival) == 0:  # every stitch reached within one observation: no slope to read
        return float("nan")
    slope = np.polyfit(arrival, levels, 1)[0]
    return float(slope * l_y)


def midline_heights(course_positions: list[np.ndarray], column_x: np.ndarray, longest_edge: float) -> np.ndarray:
    """(n_courses, n_columns) the height y of each course's yarn where it crosses each column's mid-line x =
    ``column_x`` (the highest crossing, linearly interpolated along its edges; NaN where it does not cross): the
    "middle point" of the laddering column that the paper's spatio-temporal diagrams follow (Fig. 3b,d and the
    appendix's simulations). A pair of consecutive nodes farther apart than ``longest_edge`` is no edge (the two
    pieces of a cut course)."""
    out = np.full((len(course_positions), column_x.shape[0]), np.nan)
    for r, p in enumerate(course_positions):
        x0, x1, y0, y1 = p[:-1, 0], p[1:, 0], p[:-1, 1], p[1:, 1]
        edge = np.hypot(x1 - x0, y1 - y0) <= longest_edge
        for i, x_mid in enumerate(column_x):
            crosses = edge & ((x0 - x_mid) * (x1 - x_mid) <= 0.0) & (x0 != x1)
            if crosses.any():
                k = np.flatnonzero(crosses)
                out[r, i] = np.max(y0[k] + (x_mid - x0[k]) / (x1[k] - x0[k]) * (y1[k] - y0[k]))
    return out


def front_heights(heights: np.ndarray, extent: np.ndarray, cut_row: int) -> np.ndarray:
    """The ladder's front on the laddering column's mid-line, in the lab's y, at each observation (n_obs,): the
    height (:func:`midline_heights`, ``heights`` (n_obs, n_courses)) of the first course past its reach, course
    ``cut_row`` + ``extent`` + 1 (``extent``: the upward extent in stitches at each observation); NaN where that
    course does not cross the mid-line or lies beyond the knit."""
    extent = np.asarray(extent, dtype=np.int64)
    rows = cut_row + extent + 1
    out = np.full(extent.shape[0], np.nan)
    inside = rows < heights.shape[1]
    out[inside] = heights[np.flatnonzero(inside), rows[inside]]
    return out


def front_speed(times: np.ndarray, front_y: np.ndarray, extent: np.ndarray, first: int = 2, last: int = 10) -> float:
    """v_lad as the paper reads it: the slope of the front's height against time while it runs "from stitch 2 to
    10" (Fig. 3d: "The solid red line on (d) highlights the front of the defect propagation from stitch 2 to 10,
    its slope corresponds to the laddering velocity"), a least-squares line through the observations from the
    front's arrival at stitch ``first`` to its arrival at ``last`` [the heights' unit per the times']. It is the
    front's speed in the lab: the cloth the ladder leaves behind moves too. NaN if the front never reached
    ``last`` or fewer than two such observations have a height."""
    times, front_y, extent = (np.asarray(a, dtype=float) for a in (times, front_y, extent))
    if extent.size == 0 or last < first or np.nanmax(extent) < last:
        return float("nan")
    start, end = int(np.argmax(extent >= first)), int(np.argmax(extent >= last))
    fit = np.zeros(times.shape, dtype=bool)
    fit[start:end + 1] = True
    fit &= np.isfinite(front_y)
    if fit.sum() < 2 or np.ptp(times[fit]) == 0.0:
        return float("nan")
    return float(np.polyfit(times[fit], front_y[fit], 1)[0])


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


def _first(times: np.ndarray) -> float:
    """The earliest of ``times`` [s] (NaN where none is)."""
    done = times[np.isfinite(times)]
    return float(done.min()) if done.size else float("nan")


def loop_sequence(withdrawn_at: np.ndarray, undone_at: np.ndarray, cut_row: int, cut_column: int) -> dict:
    """The freed loops of the paper's Fig. 2d, read from the topology: where the cut thread has gone, and which
    ladders ran from the loops it left.

    The paper (main text): "the cut thread (dashed curve) first releases loop (1), which leads to a ladder
    propagation in the upward (+y) direction. Then, if the tension is high enough, the thread retracts further
    and frees loop (2) and/or (3), which initiates a downward (-y) propagating ladder. Eventually, loop (4) or (5)
    may also be released, leading to a second upward propagation." Here the cut thread is course ``cut_row``, cut
    at its sinker between columns ``cut_column`` - 1 and ``cut_column``; its two ends leave its needle loops one by
    one (``withdrawn_at`` (n_columns,) [s], when the cut course's yarn left each column; NaN: never), the left end
    from ``cut_column`` - 1 leftwards, the right end from ``cut_column`` rightwards.

    * loop (1): the needle loop beside the cut the thread left first; the course above, held by it, ladders up;
    * loops (2)/(3): the heads of course ``cut_row`` - 1 in the two columns beside the cut, which the thread's
      legs passed through: a downward ladder runs from one once the cells below it come undone;
    * loops (4)/(5): the next needle loop of each end (the other one beside the cut, and the one after loop
      (1)): left, they start a second upward ladder; the paper's hindered laddering is the cut thread held in
      both (appendix "Hindered laddering": "the cut thread got pinched in loops (4) and (5)").

    ``undone_at`` (n_rows, n_columns) [s]: when each cell came undone (NaN: never). Returns the loops' columns,
    when each was freed and when its ladder started (NaN: did not), the ladders no loop explains
    (``other_ladders``), the order of the ladders' starts (``sequence``, e.g. "(1), (2)/(3), (4)/(5)"),
    whether it is the paper's (``paper_order``: (1), then (2)/(3), then (4)/(5), each only if it ran), and
    ``hindered``: ladders ran from (1) and from (2) or (3), and the cut thread ends held in both (4) and (5)."""
    n_rows, n_cols = undone_at.shape
    left, right = cut_column - 1, cut_column
    beside = [c for c in (left, right) if 0 <= c < n_cols]
    freed = {c: float(withdrawn_at[c]) for c in beside if np.isfinite(withdrawn_at[c])}
    loop1 = min(freed, key=freed.get) if freed else None
    if loop1 is None:
        next_loops = []
    else:
        after = loop1 - 1 if loop1 == left else loop1 + 1  # the same end's next needle loop
        next_loops = [c for c in (left if loop1 == right else right, after) if 0 <= c < n_cols]

    def up_start(c):  # the cell above the cut course in column c: the ladder's first stitch
        return float(undone_at[cut_row + 1, c]) if cut_row + 1 < n_rows else float("nan")

    def down_start(c):  # the cell below the freed head (2)/(3): the downward ladder's first stitch past it
        return float(undone_at[cut_row - 2, c]) if cut_row >= 2 else float("nan")

    ladders = []
    if loop1 is not None:
        ladders.append({"loop": "(1)", "column": loop1, "direction": 1, "freed_s": freed[loop1],
                        "start_s": up_start(loop1)})
    for c in beside:
        ladders.append({"loop": "(2)/(3)", "column": c, "direction": -1,
                        "freed_s": float(undone_at[cut_row - 1, c]) if cut_row >= 1 else float("nan"),
                        "start_s": down_start(c)})
    for c in next_loops:
        ladders.append({"loop": "(4)/(5)", "column": c, "direction": 1, "freed_s": float(withdrawn_at[c]),
                        "start_s": up_start(c) if np.isfinite(withdrawn_at[c]) else float("nan")})
    explained = {(lad["column"], lad["direction"]) for lad in ladders}
    other = 0
    for c in range(n_cols):
        for direction, rows in ((1, slice(cut_row + 1, None)), (-1, slice(0, max(cut_row - 1, 0)))):
            if (c, direction) not in explained and np.isfinite(undone_at[rows, c]).any():
                other += 1
    ran = sorted((lad for lad in ladders if np.isfinite(lad["start_s"])), key=lambda lad: lad["start_s"])
    order = [lad["loop"] for lad in ran]
    sequence = ", ".join(dict.fromkeys(order))  # each kind once, in the order its first ladder started
    rank = {"(1)": 0, "(2)/(3)": 1, "(4)/(5)": 2}
    paper_order = bool(order) and order[0] == "(1)" and all(rank[a] <= rank[b] for a, b in zip(order, order[1:]))
    held_in_4_and_5 = loop1 is not None and len(next_loops) == 2 and not any(
        np.isfinite(withdrawn_at[c]) for c in next_loops)
    ran_loops = set(order)
    return {
        "ladders": ladders, "loop1_column": -1 if loop1 is None else loop1,
        "loop1_freed_s": freed.get(loop1, float("nan")) if loop1 is not None else float("nan"),
        "up_from_1_s": _first(np.array([lad["start_s"] for lad in ladders if lad["loop"] == "(1)"])),
        "down_from_2_3_s": _first(np.array([lad["start_s"] for lad in ladders if lad["loop"] == "(2)/(3)"])),
        "up_from_4_5_s": _first(np.array([lad["start_s"] for lad in ladders if lad["loop"] == "(4)/(5)"])),
        "other_ladders": other, "sequence": sequence, "paper_order": paper_order,
        "cut_thread_held": held_in_4_and_5,
        "hindered": held_in_4_and_5 and {"(1)", "(2)/(3)"} <= ran_loops and "(4)/(5)" not in ran_loops,
    }


IMMEDIATE_S = 1e-4  # cells undone this soon after the cut come undone with it (the cut's own damage) [s]


def damage_parts(undone_at: np.ndarray, cut_row: int, immediate_s: float = IMMEDIATE_S,
                 taut: np.ndarray | None = None, final: np.ndarray | None = None) -> dict[str, int]:
    """The undone cells split by what they free into the loaded knit (Eq. 1 counts l0 - l_x per cell released
    into a loaded course): ``cut_row``, the cells of the cut's own course (its yarn is cut: it frees no length
    into a loaded course); ``immediate``, the other cells undone within ``immediate_s`` of the cut (its
    recoil, not the ladder's run); ``released``, the rest, the ladder's own; with ``taut`` (the final map of
    :func:`taut_cells`), ``released_taut``: those of them whose bar is taut at the end (-1 without the map).
    ``undone_at`` (n_rows, n_cols) [s since the cut], NaN where a cell never came undone; ``final``: the cells
    undone at the end (the others knit themselves again and are not counted), every cell ever undone if None."""
    done = np.isfinite(undone_at) if final is None else np.isfinite(undone_at) & final
    in_cut_row = np.zeros_like(done)
    in_cut_row[cut_row] = done[cut_row]
    immediate = done & ~in_cut_row & (undone_at <= immediate_s)
    released = done & ~in_cut_row & ~immediate
    return {"cut_row": int(in_cut_row.sum()), "immediate": int(immediate.sum()), "released": int(released.sum()),
            "released_taut": -1 if taut is None else int((released & taut).sum())}


def arrest_threshold(fx_ini, fx_fin, laddered, arrested) -> dict:
    """f_x^thr as the paper defines it: "We take for f_x^thr the mean value of f_x^fin for all experiments:
    f_x^thr = 2.0 +- 0.8" (its +- the scatter), "the value to which the force relaxes once defect propagation is
    complete", over the runs that laddered and arrested (``laddered``, ``arrested``: per run); and the paper's
    "f_x^fin is constant regardless of the destruction level" tested: the slope of f_x^fin against f_x^ini (least
    squares) with its standard error. Returns ``fx_thr`` (mean), ``fx_thr_sd`` (scatter), ``fx_thr_se`` (standard
    error), ``runs``, ``slope``, ``slope_se`` (NaN where too few runs: 1 for the mean, 3 for the slope)."""
    fx_ini, fx_fin = np.asarray(fx_ini, dtype=float), np.asarray(fx_fin, dtype=float)
    use = np.asarray(laddered, dtype=bool) & np.asarray(arrested, dtype=bool) & np.isfinite(fx_fin)
    x, y = fx_ini[use], fx_fin[use]
    n = int(use.sum())
    out = {"runs": n, "fx_thr": float(y.mean()) if n else float("nan"),
           "fx_thr_sd": float(y.std(ddof=1)) if n > 1 else float("nan"),
           "fx_thr_se": float(y.std(ddof=1) / np.sqrt(n)) if n > 1 else float("nan"),
           "slope": float("nan"), "slope_se": float("nan")}
    if n >= 3 and np.ptp(x) > 0:
        slope, intercept = np.polyfit(x, y, 1)
        residual = y - (slope * x + intercept)
        out["slope"] = float(slope)
        out["slope_se"] = float(np.sqrt(residual @ residual / (n - 2) / np.sum((x - x.mean()) ** 2)))
    return out
