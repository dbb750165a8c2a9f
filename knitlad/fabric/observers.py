"""Observers and stop rules of the laddering run loop (:func:`knitlad.experiments.laddering.propagate`).

An observer is any object with ``observe(t, run, reading)``, the run loop's one signature
(:class:`knitlad.engine.runloop.Observer`): for the laddering, called after every observation interval
with the time since the cut [s], the running :class:`knitlad.experiments.laddering.Laddering` and a
:class:`CellReading` (the cells undone now, those ever undone since the cut, each cell's overlap). A stop rule
has ``check(t, reading) -> str | None``: a reason to stop, or None. Write your own and pass them to
``propagate``; these are the standard ones.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from knitlad.fabric.measure import ladder_front
from knitlad.engine.units import LENGTH, VELOCITY

MAX_OVERLAP_OVER_D = 0.5  # deeper than this, a yarn may pass through another: the run stops with an error


class CellReading(NamedTuple):
    """The laddering's reading at one observation (every map (n_y, n_x), the cells flagged before the cut left
    out). ``undone``: the cells undone now, as a photograph shows them (the head below the course above's sinkers
    by the undone margin, or its yarn gone: :func:`knitlad.fabric.measure.cell_overlap`); a cell can knit
    itself again. ``ever``: the cells undone at any observation since the cut. ``overlap``: each cell's overlap
    [l_y] (-inf where its yarn has gone, NaN where no head was read)."""

    undone: np.ndarray
    ever: np.ndarray
    overlap: np.ndarray


class Interpenetration(RuntimeError):
    """Two yarns overlap by more than MAX_OVERLAP_OVER_D: the contact is too soft for the forces it carries."""


class OverlapGuard:
    """Stops a run with :class:`Interpenetration` when two yarns overlapped deeper than ``limit`` d
    at any step since the last check (the contact kernel keeps the peak between checks)."""

    def __init__(self, diameter_m: float, limit_over_d: float = MAX_OVERLAP_OVER_D) -> None:
        self.d = diameter_m
        self.limit = limit_over_d
        self.peak_over_d = 0.0

    def check(self, sim, when: str) -> None:
        peak = sim.peak_overlap_m(reset=True) / self.d
        self.peak_over_d = max(self.peak_over_d, peak)
        if peak > self.limit:
            raise Interpenetration(
                f"yarns overlap by {peak:.2f} d {when} (limit {self.limit} d): the contact is too soft for this "
                "tension; raise contact_force_f0"
            )


class FrontRecorder:
    """The ladder's (upward, downward) extent from the cut row, and the column's cells, in each candidate column."""

    def __init__(self, columns: tuple[int, ...], cut_row: int) -> None:
        self.columns = columns
        self.cut_row = cut_row
        self._fronts: list[list[tuple[int, int]]] = [[] for _ in columns]
        self._cells: list[list[np.ndarray]] = [[] for _ in columns]

    def observe(self, t: float, run, reading: CellReading) -> None:
        for c, col in enumerate(self.columns):  # the farthest any cell came undone: the first arrivals
            self._fronts[c].append(ladder_front(reading.ever, col, self.cut_row))
            self._cells[c].append(reading.undone[:, col].copy())

    def extents(self) -> tuple[np.ndarray, ...]:
        return tuple(np.array(f, dtype=np.int64).reshape(-1, 2) for f in self._fronts)

    def reach(self, n_rows: int) -> float:
        """How far the farthest front has gone towards the edge it runs to, 0 to 1: a ladder's progress,
        which ends it sooner than the time limit does."""
        best = 0.0
        for fronts in self._fronts:
            if fronts:
                up, down = fronts[-1]
                best = max(best, up / max(n_rows - 1 - self.cut_row, 1), down / max(self.cut_row, 1))
        return min(best, 1.0)

    def cells(self) -> tuple[np.ndarray, ...]:
        return tuple(np.array(c) for c in self._cells)


class CellTimes:
    """When each cell first came undone, and when its yarn left it (NaN: not yet): the record of which freed
    loops started ladders, and when (:func:`knitlad.fabric.measure.loop_sequence`)."""

    def __init__(self) -> None:
        self.undone_at: np.ndarray | None = None
        self.gone_at: np.ndarray | None = None

    def observe(self, t: float, run, reading: CellReading) -> None:
        if self.undone_at is None:
            self.undone_at = np.full(reading.ever.shape, np.nan)
            self.gone_at = np.full(reading.ever.shape, np.nan)
        self.undone_at[reading.ever & np.isnan(self.undone_at)] = t
        self.gone_at[np.isneginf(reading.overlap) & np.isnan(self.gone_at)] = t


class MidlineRecorder:
    """The paper's spatio-temporal diagram of each followed column: every course's height where it crosses the
    column's mid-line (:func:`knitlad.fabric.measure.midline_heights`), at every observation [l0]."""

    def __init__(self, columns: tuple[int, ...]) -> None:
        self.columns = columns
        self._heights: list[np.ndarray] = []

    def observe(self, t: float, run, reading: CellReading) -> None:
        k = run.knit
        self._heights.append(k.gauge.midline_heights(run.sim.state.x, k.box_lx, self.columns))

    def heights(self) -> tuple[np.ndarray, ...]:
        """Per column, (n_obs, n_courses) mid-line heights [l0]."""
        stacked = np.array(self._heights)  # (n_obs, n_courses, n_columns)
        return tuple(stacked[:, :, c] for c in range(len(self.columns)))


class EnergyRecorder:
    """The energy ledger (:meth:`knitlad.engine.simulation.Simulation.ledger`) at every observation: where the
    cut released energy went, as series [J] (``series``) and at the stop (``last``)."""

    def __init__(self) -> None:
        self.readings: list[dict[str, float]] = []

    def observe(self, t: float, run, reading: CellReading) -> None:
        self.readings.append(run.sim.ledger().as_dict())

    def series(self) -> dict[str, np.ndarray]:
        if not self.readings:
            return {}
        return {k: np.array([r[k] for r in self.readings]) for k in self.readings[0]}

    @property
    def last(self) -> dict[str, float]:
        return self.readings[-1] if self.readings else {}


class FrontRan:
    """A front has run ``stitches`` stitches from the cut row in one of ``columns``: enough for a velocity fit
    over stitches 2 to 10 when ``stitches`` > 10, at a fraction of a whole run's cost (a velocity study's rule)."""

    def __init__(self, stitches: int, columns: tuple[int, ...], cut_row: int) -> None:
        self.stitches, self.columns, self.cut_row = stitches, columns, cut_row

    def check(self, t: float, reading: CellReading) -> str | None:
        ran = max(max(ladder_front(reading.ever, col, self.cut_row)) for col in self.columns)
        return f"a front ran {self.stitches} stitches" if ran >= self.stitches else None


class TensionRecorder:
    """f_x at every observation, and each free course's own (``fx_courses``)."""

    def __init__(self) -> None:
        self.fx: list[float] = []
        self.fx_courses: list[np.ndarray] = []

    def observe(self, t: float, run, reading: CellReading) -> None:
        self.fx.append(run.tension())
        self.fx_courses.append(run.course_tensions())


AUTO_FRAMES = 60  # frames over a ladder's expected duration when no frame interval is given (laddering.frame_interval)
FREE, TOUCHING, SLIDING = 0, 1, 2  # contact state of a node (FrameRecorder.contact)


def node_contact_state(sim) -> np.ndarray:
    """Per node: FREE, TOUCHING (an edge of it touches another yarn) or SLIDING (at the Coulomb limit)."""
    from knitlad.engine.kernels.contact import OVERLAP
    from knitlad.engine.kernels.contact import SLIDING as SLIDING_COLUMN

    state = np.zeros(sim.model.n_nodes, dtype=np.uint8)
    c = sim.contacts
    n = int(c.n_pairs[0])
    if n == 0:
        return state
    results, edges = c.pair_results[:n], c.pairs[:n]
    touching = results[:, OVERLAP] > 0
    # a pair that separated keeps its last sliding flag in the scratch results (and a rebuild moves
    # it onto another pair): sliding counts only where the pair touches now
    for flag, mask in ((TOUCHING, touching), (SLIDING, touching & (results[:, SLIDING_COLUMN] > 0))):
        touched = edges[mask].ravel()
        for ends in (sim.model.edge_a, sim.model.edge_b):
            state[ends[touched]] = np.maximum(state[ends[touched]], flag)
    return state


class FrameRecorder:
    """Node positions [m] and velocities [m/s] as float32, their contact state, and the undone
    cells, every ``every_s``; ``last=True`` records the final state whatever the interval."""

    def __init__(self, every_s: float) -> None:
        self.every_s = every_s
        self.frames: list[np.ndarray] = []
        self.velocities: list[np.ndarray] = []
        self.contact: list[np.ndarray] = []
        self.laddered: list[np.ndarray] = []
        self.times_s: list[float] = []
        self._next = 0.0

    def observe(self, t: float, run, reading: CellReading, last: bool = False) -> None:
        if t >= self._next or (last and (not self.times_s or self.times_s[-1] < t)):
            self.frames.append(run.sim.positions_m().astype(np.float32))
            self.velocities.append((run.sim.state.v * VELOCITY).astype(np.float32))
            self.contact.append(node_contact_state(run.sim))
            self.laddered.append(reading.undone.copy())  # as a photograph of that instant shows them
            self.times_s.append(t)
            while self._next <= t:
                self._next += self.every_s


TOP_ROWS_HELD = 1  # rows of cells under the held top course that cannot ladder


class EdgeReached:
    """The ladder has reached the bottom or the top of the fabric.

    The rows of cells run from course 0 to the top free course, whose cell lies
    under the held top course, whose sinkers cannot move: it comes undone late if
    at all (16 x 16 at f_x^ini 13.6: the ladder reached the row below it at 0.8 ms
    and it still held 2 ms later), so the top is the row below it
    (:data:`TOP_ROWS_HELD`). As a stop rule (``stop_at_edge``), n_lad/n_y and f_x^fin of a
    ladder that reaches an edge are those of that moment, a lower bound of the
    damage it would end with; without it, the run goes on until every front has stopped.
    """

    @staticmethod
    def reached(undone: np.ndarray) -> bool:
        top = undone.shape[0] - 1 - TOP_ROWS_HELD
        return bool(undone[top].any() or undone[0].any())

    def check(self, t: float, reading: CellReading) -> str | None:
        return "ladder reached an edge course" if self.reached(reading.ever) else None


class Arrested:
    """The knit has settled: no cell has changed its state (undone now or not: the photograph the paper counts
    after the arrest) for ``arrest_s``, nor for ``pause_factor`` times the longest pause between two changes
    so far.

    A stick-slip front advances in bursts between pauses of some duration tau; with the second condition it
    is not taken as arrested before it has been still for ``pause_factor`` tau (3 by default), whatever
    ``arrest_s`` says. A cell that knits itself again, or one still crossing the threshold, is a change: the
    run goes on until the photograph stops changing.
    """

    def __init__(self, arrest_s: float, pause_factor: float = 3.0) -> None:
        self.arrest_s, self.pause_factor = arrest_s, pause_factor
        self._map: np.ndarray | None = None
        self._since = 0.0
        self._changed = False  # a change after the first observation: pauses are counted from it on
        self.longest_pause = 0.0

    def check(self, t: float, reading: CellReading) -> str | None:
        now = reading.undone
        if self._map is None or not np.array_equal(now, self._map):
            if self._changed:  # the wait before the first change is the ladder's start, not a pause
                self.longest_pause = max(self.longest_pause, t - self._since)
            self._changed = self._map is not None
            self._map, self._since = now.copy(), t
        wait = max(self.arrest_s, self.pause_factor * self.longest_pause)
        return f"no cell changed for {wait * 1e3:.1f} ms" if t - self._since >= wait else None


class LetGo:
    """A single loop has let go: every reading for ``confirm_s`` said it is no longer held (the reading's
    ``held``: True, False, or None where it was not read). ``since``: the first reading of the run of
    "not held" that fired."""

    def __init__(self, confirm_s: float, what: str) -> None:
        self.confirm_s, self.what = confirm_s, what
        self.since: float | None = None

    def check(self, t: float, reading) -> str | None:
        if reading.held is None:
            return None
        if reading.held:
            self.since = None
        elif self.since is None:
            self.since = t
        elif t - self.since >= self.confirm_s:
            return f"the loop let go ({self.what} for {self.confirm_s * 1e3:.3f} ms)"
        return None


class TimeLimit:
    """``max_time_s`` has passed since the run began (any reading)."""

    def __init__(self, max_time_s: float) -> None:
        self.max_time_s = max_time_s

    def check(self, t: float, reading=None) -> str | None:
        return "max_time_s reached" if t >= self.max_time_s else None


class TrajectoryRecorder:
    """An observer of one's own scene: call it with the simulation (or pass it as ``Simulation.run``'s
    ``observe``, or among an experiment's observers: ``propagate(..., observers=[...])``) and it keeps positions [m], velocities [m/s], each node's contact state (0 free,
    1 touching, 2 sliding), the touching pairs (``Simulation.contact_pairs``: points [m], normal and
    friction forces [N], sliding) and the time [s], as float32 frames, and with obstacles their shapes and
    where each is at every frame [m]; ``knitlad.write_trajectory`` writes them."""

    def __init__(self) -> None:
        self.positions: list[np.ndarray] = []
        self.velocities: list[np.ndarray] = []
        self.contact: list[np.ndarray] = []
        self.pairs: list = []  # one ContactPairs per frame (none without contact)
        self.times: list[float] = []
        self.edges: np.ndarray | None = None
        self.yarn_start: np.ndarray | None = None
        self.node_yarn: np.ndarray | None = None
        self.obstacle_shapes: dict[str, np.ndarray] | None = None  # kind (0 plane, 1 cylinder), direction, radius_m
        self.obstacle_points: list[np.ndarray] = []  # (k, 3) per frame [m]

    def __call__(self, sim) -> None:
        m = sim.model
        if self.edges is None:
            self.edges = np.column_stack([m.edge_a, m.edge_b]).astype(np.int64)
            self.yarn_start, self.node_yarn = m.yarn_start.copy(), m.node_yarn.copy()
        self.positions.append(sim.positions_m().astype(np.float32))
        self.velocities.append((sim.state.v * VELOCITY).astype(np.float32))
        self.contact.append(node_contact_state(sim) if sim.has_contact else np.zeros(m.n_nodes, dtype=np.uint8))
        if sim.has_contact:
            self.pairs.append(sim.contact_pairs())
        if sim.obstacles is not None:
            if self.obstacle_shapes is None:
                o = sim.obstacles
                self.obstacle_shapes = {"kind": o.kind.astype(np.uint8), "direction": o.axis.copy(),
                                        "radius": o.radius * LENGTH}
            self.obstacle_points.append(sim.obstacle_positions_m())
        self.times.append(sim.time_s)

    def observe(self, t: float, run, reading=None) -> None:
        """As an observer of an experiment (the run loop's signature): records ``run.sim``."""
        self(run.sim)
