"""The laddering experiment (paper, "Simulations" and appendix), as stages that hand each other values.

    stretch(StretchSettings)                 -> StretchedKnit   the knit at mu = 0, stretched and relaxed
    cut(StretchedKnit, DynamicsSettings)     -> Laddering       friction on, the sinker loop cut
    propagate(Laddering, observers)          -> LadderTrace     the free dynamics, observed
    analyse(LadderTrace)                     -> LadderResult    f_x^fin, n_lad/n_y, v_lad/c_b

1. **stretch** at mu = 0 to the target: the knit is built at the target l_y and
   at l_x = min(target, 0.30 l0) (narrower for l_y > 0.25 l0: :func:`build_width`).
   It is not built at the paper's 0.245 l0 because there the fabric is in compression
   (f_x < 0) and buckles out of plane, and the buckled structure survives the stretch
   (measured: the knit tangles). From there the whole fabric is stretched affinely
   (:mod:`knitlad.fabric.stretching`) with the held ends and edge courses fixed, by position
   or by force control, and relaxed to a steady f_x; f_x^ini, l_x and l_y are measured.
2. **cut**: friction on (mu), the sinker loop (the loop pointing -y) of the central
   course cut at the central column. A stretched knit is never changed: cutting it
   twice gives two independent runs (studies of the dynamics' settings do so).
3. **propagate**: free dynamics; every ``observe_every_s`` the observers
   (:mod:`knitlad.fabric.observers`) record the laddered cells, the fronts, f_x and frames,
   and the stop rules end the run when no cell has changed for ``arrest_s``, when the
   ladder reaches an edge course, or at ``max_time_s``.
4. **analyse**: the laddering column, n_lad/n_y, f_x^fin and v_lad/c_b.

Settings are built from :class:`knitlad.experiments.config.CutConfig`, the one declaration of
each setting with its default and unit (``CutConfig(...).settings()``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, fields
from typing import Callable, Sequence

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import ContactModel, Counting, contact_time_step, dashpot_ratio
from knitlad.engine.dissipation import AirDrag, EnergyLedger, MaterialDamping, authors_contact_dashpot
from knitlad.engine.runloop import Observer, StopRule, run_until
from knitlad.engine.simulation import Simulation
from knitlad.engine.state import Rods, cut_edge, with_axial_stiffness, with_twist
from knitlad.engine.timestep import DEFAULT_SAFETY, MAX_STEPS, critical_time_steps
from knitlad.engine.units import Material
from knitlad.fabric.measure import (
    between_cells,
    laddered_cells,
    laddering_velocity,
    loop_sequence,
    front_heights,
    front_speed,
    rehooked_cells,
    taut_cells,
)
from knitlad.fabric.observers import (
    AUTO_FRAMES,
    Arrested,
    CellReading,
    CellTimes,
    EdgeReached,
    EnergyRecorder,
    FrameRecorder,
    FrontRan,
    FrontRecorder,
    MidlineRecorder,
    OverlapGuard,
    TOP_ROWS_HELD,
    TensionRecorder,
    TimeLimit,
)
from knitlad.fabric.preparation import (
    STRETCH_AXIAL_DAMPING,
    InfeasibleRun,
    StretchSettings,
    StretchedKnit,
    stretch,
    stretch_contact,
)


@dataclass(frozen=True)
class DynamicsSettings:
    """How a stretched knit ladders (from :meth:`knitlad.experiments.config.CutConfig.dynamics_settings`, where each
    field has its default and unit, under the same name or its SI twin: ``observe_every_us`` -> ``observe_every_s``). SI."""

    mu: float
    contact_counting: Counting  # of the dynamics (the stretch, a minimisation, counts UNION)
    contact_damping_ratio: float  # normal and tangential contact dashpots, fraction of critical
    stretch_damping_ratio: float  # the yarn's axial dashpot, fraction of critical
    dt_safety: float  # time step as a fraction of the stability limit
    drag_per_s: float  # global drag on every node [1/s]; 0 is the physics
    spin_drag: bool  # the global drag also damps each edge's spin, at the same rate (the authors' engine)
    contact_dashpot: str  # "critical": contact_damping_ratio on both; "absolute": the authors' c_n, no tangential
    twist: bool  # the yarns carry twist: friction also turns them (the friction couple)
    axial_stiffness_factor: float  # EA of the dynamics over the yarn's, every edge keeping its tension at the cut
    twist_inertia_factor: float  # the yarn's inertia about its axis in the dynamics over rho_L d^2/8 per length
    framed_twist: bool  # twist through material frames even for yarns straight at rest (for comparisons)
    implicit_axial: bool  # the axial springs at the end of each kick: the step set by contact and bending
    predicted_dashpots: bool  # the dashpots act on the velocities predicted at the end of each step
    observe_every_s: float
    arrest_s: float
    max_time_s: float
    frame_every_s: float | None  # None: AUTO_FRAMES over the expected ladder duration (frame_interval)
    stop_at_edge: bool  # stop when a ladder reaches an edge course (else: when every front has stopped)
    loss_factor: float  # the yarn's material damping, peak loss factor (0: none; knitlad.engine.dissipation)
    loss_peak_hz: float  # ... at this frequency [Hz]
    air_drag: bool  # still air around the yarns
    stop_after_stitches: int | None  # stop once a front has run this many stitches (enough for v_lad)
    friction_band: tuple[int, int, float] | None  # (first course, courses, factor on mu): a run-stop band
    clip_friction: float  # Coulomb coefficient of the clips on the bars they slide along (0: frictionless)

    @property
    def material_damping(self) -> MaterialDamping | None:
        return MaterialDamping(self.loss_factor, self.loss_peak_hz) if self.loss_factor > 0 else None

    @property
    def air(self) -> AirDrag | None:
        return AirDrag() if self.air_drag else None


@dataclass(frozen=True)
class LadderSettings:
    """Both halves of one laddering run."""

    stretch: StretchSettings
    dynamics: DynamicsSettings

    @property
    def material(self) -> Material:
        return self.stretch.material



# ------------------------------------------------------------------ stage 2: cut
@dataclass
class Laddering:
    """A knit cut and running: the simulation and what the observers need to read it."""

    knit: StretchedKnit
    dynamics: DynamicsSettings
    sim: Simulation
    cut_edge: int
    cut_row: int
    cut_column: int
    baseline: np.ndarray  # cells flagged before the cut: not damage
    wall_s: float  # of the cut

    def laddered(self) -> np.ndarray:
        """Cells laddered at the current positions (including the baseline)."""
        k = self.knit
        return k.gauge.laddered(self.sim.state.x, k.box_lx, k.box_ly)

    def overlap_over_ly(self) -> np.ndarray:
        """Each cell's overlap at the current positions [l_y] (:meth:`KnitGauge.overlap_over_ly`)."""
        k = self.knit
        return k.gauge.overlap_over_ly(self.sim.state.x, k.box_lx, k.box_ly)

    def tension(self) -> float:
        return self.knit.gauge.tension(self.sim)

    def course_tensions(self) -> np.ndarray:
        return self.knit.gauge.course_tensions(self.sim)


def sinker_edge(knit: StretchedKnit, row: int, column: int) -> int:
    """The edge at the apex of the sinker loop of course ``row`` on the -x side of ``column``."""
    k, rods = knit.knit, knit.knit.rods
    nodes = k.course_nodes(row)
    x = rods.state.x[nodes]
    l_x = knit.box_lx * knit.settings.material.stitch_length / units.LENGTH
    target = knit.gauge.column_centres(knit.box_lx)[column] - 0.5 * l_x
    near = np.flatnonzero(np.abs(x[:, 0] - target) < 0.25 * l_x)
    apex = nodes.start + near[np.argmin(x[near, 1])]
    return int(np.flatnonzero(rods.model.edge_a == apex)[0])


def laddering_time_step(rods: Rods, contact: ContactModel, dynamics: DynamicsSettings) -> float:
    """The step [s] of the laddering dynamics: ``dt_safety`` x the stability limit of the yarns' sliding.

    That limit is the rods' and the contact springs' acting on the nodes (:func:`critical_time_steps`
    without twist). ``dt_safety`` is a factor of accuracy: it sets how well the ladder's stick-slip
    releases are timed (0.35, ``docs/accuracy.md``). With twist, the friction couple's spin mode
    (omega^2 gains 2 z k_t r^2 / I) and the twist waves are faster than the sliding, but the
    ladder needs them only stable: they are held to ``DEFAULT_SAFETY`` of the limit with them. So
    a twisting yarn ladders at the twist-free step (on 16 x 16, paired against half of it: v_lad
    -3.9 +- 1.6 % at f_x 4 and -1.3 +- 1.1 % at 13.6, the size of the twist-free default's own step
    error, ``docs/accuracy.md``).
    """
    predicted = dynamics.predicted_dashpots

    material = dynamics.material_damping
    ratio = material.branch_ratio if material else 0.0

    def limit_s(twist: bool) -> float:
        contact_limit = contact_time_step(rods.model, contact, spin=twist, predicted=predicted)
        return critical_time_steps(rods.model, twist, contact_limit, dynamics.implicit_axial,
                                   predicted, ratio).combined * units.TIME

    dt = dynamics.dt_safety * limit_s(False)
    return min(dt, DEFAULT_SAFETY * limit_s(True)) if rods.twist else dt


def dynamics_rods(rods: Rods, dynamics: DynamicsSettings, material: Material) -> Rods:
    """The stretched knit's rods as the dynamics run them: their dashpots, clip friction, axial stiffness and twist."""
    rods = rods.replace_model(
        stretch_damping=rods.model.stretch_damping * (dynamics.stretch_damping_ratio / STRETCH_AXIAL_DAMPING))
    if dynamics.clip_friction > 0:  # the stretch ran at mu = 0, the clips' friction too: both come on at the cut
        rods = rods.replace_model(rail_friction=np.full(rods.model.rail_node.shape[0], dynamics.clip_friction))
    if dynamics.axial_stiffness_factor != 1.0:
        rods = with_axial_stiffness(rods, dynamics.axial_stiffness_factor)
    if dynamics.twist and not rods.twist:  # a yarn with natural curvature carries twist from the stretch
        rods = with_twist(rods, material.twisting_stiffness / material.bending_stiffness)
    if rods.twist and dynamics.twist_inertia_factor != 1.0:
        # a heavier spin, for studies: the yarns roll at the contacts, so the spin inertia enters the ladder
        # (docs/accuracy.md, default 1); the step does not need it (laddering_time_step)
        rods = rods.replace_model(twist_inertia=rods.model.twist_inertia * dynamics.twist_inertia_factor)
    return rods


def dynamics_simulation(rods: Rods, knit: StretchedKnit, dynamics: DynamicsSettings, obstacles=()) -> Simulation:
    """A simulation of ``rods`` (:func:`dynamics_rods`) under the dynamics' contact, friction and step, with
    ``obstacles`` (a snag's pin) if any."""
    zeta_n = zeta_t = dynamics.contact_damping_ratio
    if dynamics.contact_dashpot == "absolute":
        # the authors' normal dashpot is a coefficient, not a ratio: the ratio it is on these nodes, and no
        # tangential dashpot (their lambda_contact_t = 0)
        node_kg = float(np.median(rods.model.mass[~rods.model.held])) * units.MASS
        zeta_n = dashpot_ratio(authors_contact_dashpot(knit.settings.material),
                               stretch_contact(knit.settings).stiffness, node_kg)
        zeta_t = 0.0
    contact = stretch_contact(knit.settings, mu=dynamics.mu, damping_ratio=zeta_n, tangential_damping_ratio=zeta_t,
                              counting=dynamics.contact_counting, yarn_friction=band_yarns(knit, dynamics))
    # a cut frees two end nodes: keep the smaller of the stretch's step (of a yarn as soft) and the new stable step
    stretch_step = math.inf if dynamics.implicit_axial else knit.dt_s / math.sqrt(dynamics.axial_stiffness_factor)
    sim = Simulation(rods, contact=contact, dt_s=min(stretch_step, laddering_time_step(rods, contact, dynamics)),
                     drag_per_s=dynamics.drag_per_s, framed_twist=dynamics.framed_twist,
                     spin_drag_per_s=dynamics.drag_per_s if dynamics.spin_drag else 0.0,
                     implicit_axial=dynamics.implicit_axial, predicted_dashpots=dynamics.predicted_dashpots,
                     material_damping=dynamics.material_damping, air=dynamics.air, obstacles=obstacles)
    check_feasible(sim.dt_s, dynamics)
    return sim


def band_yarns(knit: StretchedKnit, dynamics: DynamicsSettings) -> tuple:
    """The ``ContactModel.yarn_friction`` of the dynamics' friction band: its courses' yarns (as built) with
    their factor on mu; none without a band."""
    if dynamics.friction_band is None:
        return ()
    first, courses, factor = dynamics.friction_band
    return tuple((knit.knit.courses[row], factor) for row in range(first, first + courses))


def cut(knit: StretchedKnit, dynamics: DynamicsSettings, rods_ready: bool = False) -> Laddering:
    """Stage 2: a copy of the knit with the sinker loop of the central course cut at the central
    column, its dashpots, twist and friction those of ``dynamics``, ready to run (``rods_ready``: the
    knit's rods already have them, :func:`dynamics_rods`, as a knit loaded under the dynamics has)."""
    s, m = knit.settings, knit.settings.material
    t0 = time.perf_counter()
    row, column = s.n_y // 2, s.n_x // 2
    rods = knit.knit.rods
    baseline = knit.gauge.laddered(rods.state.x, knit.box_lx, knit.box_ly)
    edge = sinker_edge(knit, row, column)
    rods = cut_edge(rods, edge)
    if not rods_ready:
        rods = dynamics_rods(rods, dynamics, m)
    sim = dynamics_simulation(rods, knit, dynamics)
    return Laddering(knit, dynamics, sim, edge, row, column, baseline, time.perf_counter() - t0)


MAX_LADDER_STEPS = MAX_STEPS  # a 42 x 42 run at 96 nodes per stitch takes a few 1e6


STEP_SETTINGS = ("d_over_l0, contact_force_f0, overlap_fraction, contact_damping_ratio, stretch_damping_ratio, "
                 "dt_safety")


def check_feasible(dt_s: float, dynamics: DynamicsSettings) -> None:
    """Refuse, before the first step, a laddering whose step [s] is longer than its observation interval
    (it would "finish" in a few steps and report nothing real) or that would need over MAX_LADDER_STEPS."""
    if dt_s > dynamics.observe_every_s:
        raise InfeasibleRun(f"the time step ({dt_s:.3g} s) is longer than the observation interval "
                            f"({dynamics.observe_every_s:.3g} s): check {STEP_SETTINGS}")
    steps = dynamics.max_time_s / dt_s
    if steps > MAX_LADDER_STEPS:
        raise InfeasibleRun(f"max_time_ms {dynamics.max_time_s * 1e3:g} at a time step of {dt_s:.2g} s is "
                            f"{steps:.1e} steps, over {MAX_LADDER_STEPS:.0e}: check {STEP_SETTINGS}")


# ------------------------------------------------------------------ stage 3: propagate
@dataclass(frozen=True)
class LadderTrace:
    """What the observers recorded from the cut to the stop."""

    knit: StretchedKnit
    dynamics: DynamicsSettings
    cut_row: int
    columns: tuple[int, ...]  # the columns beside the cut sinker loop, each followed
    times_s: np.ndarray  # observation times since the cut
    fx: np.ndarray  # f_x at each observation
    fx_courses: np.ndarray  # (n_obs, n_y) each free course's f_x at each observation
    fronts: tuple[np.ndarray, ...]  # per column: (n_obs, 2) upward and downward extents [stitches]
    column_cells: tuple[np.ndarray, ...]  # per column: (n_obs, n_y) laddered flags
    frames: FrameRecorder  # positions, velocities and undone cells at the frame times
    baseline: np.ndarray
    final_laddered: np.ndarray  # cells undone at the stop, as a photograph shows them (the baseline left out)
    ever_laddered: np.ndarray  # cells undone at any observation after the cut
    final_overlap: np.ndarray  # (n_y, n_x) each cell's overlap at the stop [l_y]
    undone_at: np.ndarray  # (n_y, n_x) when each cell first came undone after the cut [s], NaN: never
    gone_at: np.ndarray  # (n_y, n_x) when each cell's yarn left it [s], NaN: never
    midlines: tuple[np.ndarray, ...]  # per column, (n_obs, n_y + 1) each course's mid-line height [l0]
    stop_reason: str
    reached_edge: bool
    steps: int
    yarn_start: np.ndarray  # of the cut knit (the frames' topology)
    edges: np.ndarray  # (ne, 2) node pairs of its edges
    cut_node: int  # the node at the start of the cut edge
    cell_centres: np.ndarray  # (n_y, n_x, 2) x, y of each cell at the cut [m]
    peak_overlap_over_d: float
    wall_s: float
    energy: dict  # the energy ledger's series [J] (EnergyRecorder.series), one reading per observation
    final_taut: np.ndarray | None = None  # of the undone cells, those whose bar is taut at the stop


def cell_centres(run: Laddering) -> np.ndarray:
    """(n_y, n_x, 2) centre of each cell [m] in the stretched knit: the column's head x, and
    halfway between the mean heights of the cell's course and the one above."""
    k = run.knit
    x = k.knit.rods.state.x
    rows = k.gauge.rows(x)
    heights = np.array([r[:, 1].mean() for r in rows])
    centre_y = 0.5 * (heights[:-1] + heights[1:])
    centre_x = k.gauge.column_centres(k.box_lx)
    out = np.empty((len(centre_y), len(centre_x), 2))
    out[:, :, 0] = centre_x[None, :]
    out[:, :, 1] = centre_y[:, None]
    return out * units.LENGTH


def frame_interval(run: Laddering) -> float:
    """The frame interval [s]: the dynamics' setting, or AUTO_FRAMES frames over the ladder's
    expected duration: half the courses at the paper's velocity line 0.1 f_x^ini c_b (at
    least 1), no longer than max_time_s, no shorter than the observation interval."""
    d, k = run.dynamics, run.knit
    if d.frame_every_s is not None:
        return d.frame_every_s
    m = k.settings.material
    expected = 0.5 * k.settings.n_y * k.box_ly * m.stitch_length / (0.1 * max(k.fx_ini, 1.0) * m.c_b)
    return max(min(expected, d.max_time_s) / AUTO_FRAMES, d.observe_every_s)


class PropagateProgress:
    """The progress of a ladder's run: its reach (it stops at an edge course) or the time limit, whichever is
    further, as ``progress("propagate", fraction)``."""

    def __init__(self, progress: Callable[[str, float], None], fronts) -> None:
        self.progress, self.fronts = progress, fronts

    def observe(self, t: float, run: Laddering, undone: np.ndarray) -> None:
        self.progress("propagate", max(min(t / run.dynamics.max_time_s, 1.0), self.fronts.reach(run.knit.settings.n_y)))


def propagate(run: Laddering, observers: Sequence[Observer] = (), progress: Callable[[str, float], None] | None = None,
              stop_rules: Sequence[StopRule] | None = None) -> LadderTrace:
    """Stage 3: run the free dynamics, calling the observers every ``observe_every_s``, until a stop rule fires.

    The standard recorders (fronts, mid-lines, tension, frames, overlap guard) always run; ``observers``
    are called after them with (t, run, :class:`~knitlad.fabric.observers.CellReading`): the run loop's one
    signature (:func:`knitlad.engine.runloop.run_until`). ``stop_rules``: default the ladder
    reaching an edge course, no cell changed its state for ``arrest_s`` (:class:`Arrested`), ``max_time_s``.
    """
    t0 = time.perf_counter()
    d = run.dynamics
    columns = (run.cut_column - 1, run.cut_column)
    guard = OverlapGuard(run.knit.settings.material.diameter)
    fronts, tension, cell_times = FrontRecorder(columns, run.cut_row), TensionRecorder(), CellTimes()
    frames, energy, midlines = FrameRecorder(frame_interval(run)), EnergyRecorder(), MidlineRecorder(columns)
    rules = list(stop_rules) if stop_rules is not None else (
        [EdgeReached()] * d.stop_at_edge + [Arrested(d.arrest_s), TimeLimit(d.max_time_s)]
        + ([FrontRan(d.stop_after_stitches, columns, run.cut_row)] if d.stop_after_stitches else []))
    ever = np.zeros_like(run.baseline)
    reading = CellReading(ever.copy(), ever, np.zeros(run.baseline.shape))
    frames.observe(0.0, run, reading)  # the stretched knit just cut, before the first step
    times: list[float] = []

    def observe(t: float) -> CellReading:
        nonlocal reading
        guard.check(run.sim, f"at t = {t * 1e3:.3f} ms after the cut")
        overlap = run.overlap_over_ly()
        now = laddered_cells(overlap, 1.0) & ~run.baseline  # a cell may knit itself again
        ever[...] |= now
        times.append(t)
        reading = CellReading(now, ever, overlap)
        return reading

    shown = [fronts, midlines, tension, cell_times, frames, energy, *observers]
    if progress:
        shown.append(PropagateProgress(progress, fronts))
    t, rule, reason = run_until(run.sim, max(1, int(round(d.observe_every_s / run.sim.dt_s))), observe, rules,
                                shown, run)
    frames.observe(t, run, reading, last=True)  # the state at the stop
    taut = taut_cells(reading.overlap, 1.0) & reading.undone
    return LadderTrace(
        knit=run.knit, dynamics=d, cut_row=run.cut_row, columns=columns, times_s=np.array(times),
        fx=np.array(tension.fx), fx_courses=np.array(tension.fx_courses), fronts=fronts.extents(),
        column_cells=fronts.cells(), frames=frames, energy=energy.series(),
        baseline=run.baseline, final_laddered=reading.undone, ever_laddered=ever.copy(),
        final_overlap=reading.overlap, undone_at=cell_times.undone_at, gone_at=cell_times.gone_at,
        midlines=midlines.heights(), stop_reason=reason,
        final_taut=taut, reached_edge=EdgeReached.reached(ever), steps=run.sim.steps,
        yarn_start=run.sim.model.yarn_start.copy(), peak_overlap_over_d=guard.peak_over_d,
        edges=np.column_stack([run.sim.model.edge_a, run.sim.model.edge_b]),
        cut_node=int(run.knit.knit.rods.model.edge_a[run.cut_edge]), cell_centres=cell_centres(run),
        wall_s=run.wall_s + time.perf_counter() - t0,
    )


# ------------------------------------------------------------------ stage 4: analyse
@dataclass
class LadderResult:
    """The observables of one laddering run (paper, Fig. 3 and 5a) and the series they come from."""

    settings: LadderSettings
    fx_ini: float = math.nan
    fx_fin: float = math.nan
    fx_fin_crossed: float = math.nan  # f_x at the stop of the courses with an undone cell (the ladder crossed them)
    fx_fin_intact: float = math.nan  # ... and of the others
    lx_over_l0: float = math.nan
    ly_over_l0: float = math.nan
    n_lad: int = 0  # cells undone at the stop, as the paper counts them on its photograph after the arrest
    n_lad_over_ny: float = math.nan
    n_lad_ever: int = 0  # cells undone at any time after the cut (some knit themselves again)
    n_lad_rehooked: int = 0  # ... of them hooked again at the stop (head above the sinkers: intact on a photograph)
    n_lad_between: int = 0  # ... of them neither: the head below the sinkers by less than the undone margin
    v_lad_over_cb: float = math.nan  # the paper's: slope of the laddering column's mid-point front, stitches 2-10
    v_lad_first_arrival_over_cb: float = math.nan  # slope of the cells' first arrival (overlap threshold), same fit
    laddering_column: int = -1  # the column beside the cut whose front is followed (measure.laddering_column)
    reached_edge: bool = False
    stop_reason: str = ""
    v_fit_stitches: tuple = (2, 10)
    wall_s: dict = field(default_factory=dict)
    times_s: list = field(default_factory=list)
    front_up: list = field(default_factory=list)  # the cells' first arrival [stitches]
    front_down: list = field(default_factory=list)
    front_y: list = field(default_factory=list)  # the front's height on the column's mid-line [l0] (front_heights)
    midline: np.ndarray | None = None  # (n_obs, n_y + 1) the laddering column's mid-line heights [l0]
    fx_series: list = field(default_factory=list)
    fx_course_series: np.ndarray | None = None  # (n_obs, n_y) each course's f_x
    column_history: list = field(default_factory=list)  # laddered flags of the laddering column over time
    frames: list = field(default_factory=list)
    frame_times_s: list = field(default_factory=list)
    frame_velocities: list = field(default_factory=list)  # (n, 3) float32 [m/s] at each frame
    frame_laddered: list = field(default_factory=list)  # (n_y, n_x) undone cells at each frame
    frame_contact: list = field(default_factory=list)  # (n,) FREE, TOUCHING or SLIDING at each frame
    node_course: np.ndarray | None = None  # course of each node (-1: the held bottom course, n_y: the top one)
    cut_node: int = -1  # the node at the start of the cut edge
    cell_centres: np.ndarray | None = None  # (n_y, n_x, 2) x, y of each cell [m] at the cut
    edges: np.ndarray | None = None  # (ne, 2) node pairs of the edges after the cut
    stretch_tension: np.ndarray | None = None  # (k, 3) FIRE steps, box l_x/l0, f_x of the stretch's readings
    final_laddered: np.ndarray | None = None  # cells undone at the stop
    ever_laddered: np.ndarray | None = None  # cells undone at any time after the cut
    final_overlap: np.ndarray | None = None  # (n_y, n_x) each cell's overlap at the stop [l_y]
    baseline_laddered: np.ndarray | None = None
    undone_at: np.ndarray | None = None  # (n_y, n_x) when each cell first came undone [s], NaN: never
    gone_at: np.ndarray | None = None  # (n_y, n_x) when each cell's yarn left it [s], NaN: never
    cut_column: int = -1  # the column right of the cut sinker
    final_taut: np.ndarray | None = None  # (n_y, n_x) undone cells whose bar is taut at the stop
    cut_row: int = -1
    yarn_start: np.ndarray | None = None  # topology of the frames
    nodes: int = 0
    steps: int = 0
    relax_steps: int = 0  # FIRE steps of the stretch and relaxation
    fx_within_tolerance: bool = True  # force control: f_x^ini within fx_tolerance of the target
    box_lx_over_l0: float = math.nan  # the affine stretch of the held ends and edge courses
    peak_overlap_over_d: float = 0.0  # deepest yarn-yarn overlap at any step (stretch, relaxation, laddering), in d
    energy_series: dict = field(default_factory=dict)  # the energy ledger at each observation [J] (EnergyLedger)

    def energy_record(self) -> dict:
        """The ledger at the stop [J]: the energy stored at the cut and now, what each mechanism took out,
        and the balance's residual over the energy turned over (the integrator's error)."""
        if not self.energy_series:
            return {}
        last = {k: float(v[-1]) for k, v in self.energy_series.items()}
        out = {"energy_start_J": last["start"], "energy_end_J": last["stored"]}
        out.update({f"dissipated_{k}_J": last[k] for k in EnergyLedger.DISSIPATED})
        out["owner_changes_J"] = last.get("owner_changes", 0.0)
        out["ledger_residual"] = last["residual"] / last["turnover"] if last["turnover"] > 0 else 0.0
        return out

    def nan_reasons(self) -> dict[str, str]:
        """Why each result that is NaN is NaN (every NaN of the summary has its reason here)."""
        first, last = self.v_fit_stitches
        ran = max(self.front_up) if self.front_up else 0
        reasons = {
            "v_lad_over_cb": f"the front ran {ran} stitch{'es' * (ran != 1)} above the cut, short of the fit's last, "
                             f"{last} ({self.stop_reason})",
            "v_lad_first_arrival_over_cb": f"the cells' first arrival ran {ran} stitch{'es' * (ran != 1)} above the "
                                           f"cut, short of the fit's last, {last} ({self.stop_reason})",
            "fx_fin_crossed": "the ladder crossed no course",
            "fx_fin_intact": "the ladder crossed every course",
            "loop1_freed_ms": "the cut thread left neither needle loop beside the cut",
            "up_from_1_ms": "no ladder ran up from loop (1)",
            "down_from_2_3_ms": "no ladder ran down from loops (2)/(3)",
            "up_from_4_5_ms": "no ladder ran up from loops (4)/(5)",
            "fx_fin": "no tension was read after the cut",
        }
        # the results in SI are the paper's times a scale: NaN for the same reason
        reasons.update(v_lad_m_s=reasons["v_lad_over_cb"], force_fin_N=reasons["fx_fin"],
                       force_fin_N_per_cm=reasons["fx_fin"])
        summary_nan = {k for k in reasons if isinstance(getattr(self, k, None), float) and math.isnan(getattr(self, k))}
        record = {**self.loop_record(), **self.si_record()}
        summary_nan |= {k for k in reasons if k in record and isinstance(record[k], float) and math.isnan(record[k])}
        return {k: reasons[k] for k in reasons if k in summary_nan}

    def summary(self) -> dict:
        """The scalar results, and the settings a reader needs beside them (mu, twist, drag)."""
        d = self.settings.dynamics
        skip = {"settings", "wall_s", "times_s", "front_up", "front_down", "fx_series", "fx_course_series",
                "column_history", "frames", "front_y", "midline", "ever_laddered",
                "final_overlap", "gone_at",
                "frame_times_s", "final_laddered", "baseline_laddered", "yarn_start", "frame_velocities",
                "frame_laddered", "frame_contact", "stretch_tension", "node_course", "cut_node", "cell_centres", "edges",
                "undone_at", "final_taut", "energy_series"}
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in skip}
        out["v_fit_stitches"] = list(self.v_fit_stitches)
        out["v_fit_first"], out["v_fit_last"] = (int(k) for k in self.v_fit_stitches)
        out.update(mu=d.mu, twist=d.twist, drag_per_s=d.drag_per_s, loss_factor=d.loss_factor, air_drag=d.air_drag,
                   natural_curvature=self.settings.stretch.natural_curvature, wall_s=float(sum(self.wall_s.values())))
        out.update(self.energy_record())
        out.update({f"wall_{k}_s": v for k, v in self.wall_s.items()})
        out.update(self.loop_record())
        out.update(self.damage_record())
        out.update(self.si_record())
        out["nan_reasons"] = "; ".join(f"{k}: {why}" for k, why in self.nan_reasons().items())
        return out

    def si_record(self) -> dict:
        """The results in a textile engineer's units beside the paper's: the knit's pull F_x = f_x n_y f0 [N] and per
        cm of its width n_x l_x [N/cm], the ladder's speed v_lad = (v_lad/c_b) c_b [m/s], the stitch length and the
        stitch's width and height [mm] (the yarn's f0 and c_b: knitlad scales)."""
        m, s = self.settings.stretch.material, self.settings.stretch
        width_cm = s.n_x * self.lx_over_l0 * m.stitch_length * 100.0
        force = {name: getattr(self, f"fx_{name}") * s.n_y * m.f0 for name in ("ini", "fin")}
        return {"force_ini_N": force["ini"], "force_fin_N": force["fin"],
                "force_ini_N_per_cm": force["ini"] / width_cm, "force_fin_N_per_cm": force["fin"] / width_cm,
                "v_lad_m_s": self.v_lad_over_cb * m.c_b, "l0_mm": m.stitch_length * 1e3,
                "lx_mm": self.lx_over_l0 * m.stitch_length * 1e3, "ly_mm": self.ly_over_l0 * m.stitch_length * 1e3}

    def loops(self) -> dict:
        """The freed loops of the paper's Fig. 2d and the ladders that ran from them, read from where the cut thread
        went (:func:`knitlad.fabric.measure.loop_sequence`); empty for a file without the record."""
        if self.undone_at is None or self.gone_at is None or self.cut_column < 0:
            return {}
        # a ladder is what the photograph at the stop shows: the cells undone then, with when each first came undone
        at_stop = np.where(self.final_laddered, self.undone_at, np.nan) if self.final_laddered is not None \
            else self.undone_at
        return loop_sequence(self.gone_at[self.cut_row], at_stop, self.cut_row, self.cut_column)

    def damage_record(self) -> dict:
        """n_lad, the cells undone at the stop, split as Eq. 1 reads it (:func:`knitlad.fabric.measure.damage_parts`):
        the cells of the cut row, those undone within 0.1 ms of the cut, and those the ladder released into loaded
        courses, with the last over n_y (``n_lad_released_over_ny``), and of those the cells whose bar is taut at
        the stop (``n_lad_released_taut``: -1 and NaN for a run without the final map). Every part is counted in
        n_lad, as on the photograph."""
        from knitlad.fabric.measure import damage_parts

        if self.undone_at is None:
            parts = {"cut_row": self.n_lad, "immediate": 0, "released": 0, "released_taut": -1}  # an older file
        else:
            parts = damage_parts(self.undone_at, self.cut_row, taut=self.final_taut, final=self.final_laddered)
        n_y = self.settings.stretch.n_y
        taut = parts["released_taut"]
        return {"n_lad_cut_row": parts["cut_row"], "n_lad_immediate": parts["immediate"],
                "n_lad_released": parts["released"], "n_lad_released_over_ny": parts["released"] / n_y,
                "n_lad_released_taut": taut, "n_lad_released_taut_over_ny": taut / n_y if taut >= 0 else math.nan}

    def loop_record(self) -> dict:
        """Summary of :meth:`loops`: the column of loop (1), when the cut thread freed it and when the ladders from
        loops (1), (2)/(3) and (4)/(5) started [ms after the cut; NaN: none did], the ladders no freed loop
        explains, the order the ladders started in, whether that is the paper's, whether the cut thread ends held
        in loops (4) and (5), and ``hindered``: the paper's hindered laddering (appendix), ladders from (1) and
        (2)/(3) and the cut thread held in (4) and (5)."""
        r = self.loops()
        if not r:
            return {"loop1_column": -1, "loop1_freed_ms": math.nan, "up_from_1_ms": math.nan,
                    "down_from_2_3_ms": math.nan, "up_from_4_5_ms": math.nan, "other_ladders": 0,
                    "loop_sequence": "", "paper_order": False, "cut_thread_held": False, "hindered": False}
        return {"loop1_column": r["loop1_column"], "loop1_freed_ms": r["loop1_freed_s"] * 1e3,
                "up_from_1_ms": r["up_from_1_s"] * 1e3, "down_from_2_3_ms": r["down_from_2_3_s"] * 1e3,
                "up_from_4_5_ms": r["up_from_4_5_s"] * 1e3, "other_ladders": r["other_ladders"],
                "loop_sequence": r["sequence"], "paper_order": r["paper_order"],
                "cut_thread_held": r["cut_thread_held"], "hindered": r["hindered"]}


def analyse(trace: LadderTrace) -> LadderResult:
    """Stage 4: the laddering column (the one whose ladder ran farthest up, then down, fixed for
    the run as the paper follows one), n_lad/n_y, f_x^fin and v_lad/c_b, each as the paper reads it.

    * n_lad: "the total number of destroyed cells", counted "after its arrest" on a photograph: the cells undone
      at the stop (with those whose yarn has gone); the cells undone at any time are ``n_lad_ever``, those that
      knit themselves again ``n_lad_rehooked``, those left between the two states ``n_lad_between``.
    * v_lad: "the slope" of "the front of the defect propagation from stitch 2 to 10" in "spatio-temporal
      diagrams of the central point column of the ladder" (Fig. 3d, appendix "Simulations"): the front of the
      laddering column's mid-line (:func:`knitlad.fabric.measure.front_speed`): the lab's y of the first course
      past the ladder's reach against time, while the reach runs from stitch 2 to 10. The cells' first arrival
      over the same stitches (stitches l_y over time: the cloth's own frame) is ``v_lad_first_arrival_over_cb``.
    * f_x^fin: the tension "just after" the sharp drop, once the ladder stopped: the mean over the last half
      arrest window.
    """
    from knitlad.fabric.measure import laddering_column

    knit, d = trace.knit, trace.dynamics
    s = knit.settings
    best = laddering_column([tuple(f[-1]) for f in trace.fronts])
    front = trace.fronts[best]
    # f_x after arrest: mean over the last arrest window (the force rings after the cut)
    window = trace.times_s >= trace.times_s[-1] - 0.5 * d.arrest_s
    # the paper fits stitches 2 to 10; a small knit offers fewer rows above the cut
    last = min(10, s.n_y - 1 - TOP_ROWS_HELD - trace.cut_row)
    first = min(2, max(last - 2, 1))
    l_y = knit.box_ly * s.material.stitch_length
    v_first = laddering_velocity(trace.times_s, front[:, 0], l_y, first, last)
    midline = trace.midlines[best]
    front_y = front_heights(midline, front[:, 0], trace.cut_row)  # [l0]
    v_lad = front_speed(trace.times_s, front_y, front[:, 0], first, last) * s.material.stitch_length
    n_lad = int(trace.final_laddered.sum())
    fin_courses = trace.fx_courses[window].mean(axis=0)
    crossed = trace.final_laddered.any(axis=1)  # courses with an undone cell: the ladder relaxed them

    def mean_of(rows: np.ndarray) -> float:
        return float(fin_courses[rows].mean()) if rows.any() else math.nan

    return LadderResult(
        settings=LadderSettings(s, d), fx_ini=knit.fx_ini, fx_fin=float(np.mean(trace.fx[window])),
        fx_fin_crossed=mean_of(crossed), fx_fin_intact=mean_of(~crossed), fx_course_series=trace.fx_courses,
        lx_over_l0=knit.lx_over_l0, ly_over_l0=knit.ly_over_l0, n_lad=n_lad, n_lad_over_ny=n_lad / s.n_y,
        n_lad_ever=int(trace.ever_laddered.sum()),
        n_lad_rehooked=int(rehooked_cells(trace.final_overlap, trace.ever_laddered).sum()),
        n_lad_between=int(between_cells(trace.final_overlap, trace.ever_laddered, 1.0).sum()),
        v_lad_over_cb=v_lad / s.material.c_b, v_lad_first_arrival_over_cb=v_first / s.material.c_b,
        laddering_column=trace.columns[best], reached_edge=trace.reached_edge,
        stop_reason=trace.stop_reason, v_fit_stitches=(first, last),
        wall_s={"stretch": knit.wall_s, "propagate": trace.wall_s}, times_s=list(trace.times_s),
        front_up=[int(u) for u in front[:, 0]], front_down=[int(v) for v in front[:, 1]], fx_series=list(trace.fx),
        front_y=[float(y) for y in front_y], midline=midline,
        column_history=list(trace.column_cells[best]), frames=trace.frames.frames,
        frame_times_s=trace.frames.times_s, frame_velocities=trace.frames.velocities,
        frame_laddered=trace.frames.laddered, frame_contact=trace.frames.contact, node_course=knit.knit.node_course(), cut_node=trace.cut_node,
        cell_centres=trace.cell_centres, edges=trace.edges, stretch_tension=knit.tension_history,
        final_laddered=trace.final_laddered, ever_laddered=trace.ever_laddered, final_overlap=trace.final_overlap,
        baseline_laddered=trace.baseline, yarn_start=trace.yarn_start, undone_at=trace.undone_at,
        gone_at=trace.gone_at, cut_column=trace.columns[1], cut_row=trace.cut_row, final_taut=trace.final_taut,
        nodes=knit.knit.rods.model.n_nodes, steps=trace.steps, relax_steps=knit.relax_steps,
        fx_within_tolerance=knit.fx_within_tolerance, box_lx_over_l0=knit.box_lx,
        peak_overlap_over_d=max(knit.peak_overlap_over_d, trace.peak_overlap_over_d), energy_series=trace.energy,
    )


class KnitTooLarge(MemoryError):
    """The run would need more memory than the machine has available."""


def available_memory_bytes() -> int | None:
    """MemAvailable of /proc/meminfo (Linux), else None."""
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def require_memory(needed: int, what: str) -> None:
    """Refuse, before allocating anything, a run that needs more than the available memory."""
    available = available_memory_bytes()
    if available is not None and needed > available:
        raise KnitTooLarge(f"{what} needs about {needed / 2**30:.1f} GiB, more than the {available / 2**30:.1f} GiB "
                           "available: fewer stitches, a coarser resolution, or fewer frames (frame_every_us)")


def require_tension(knit: StretchedKnit) -> None:
    """InfeasibleRun if ``knit`` is not in tension: nothing pulls a freed loop out of a compressed knit, so its
    "ladder" is no result (``cut`` itself still cuts one, for studies of the dynamics)."""
    if not knit.fx_ini > 0:
        raise InfeasibleRun(f"the stretched knit is not in tension (f_x^ini = {knit.fx_ini:.3f} at l_x/l0 = "
                            f"{knit.lx_over_l0:.4f}, l_y/l0 = {knit.ly_over_l0:.4f}): below the width where f_x = 0 "
                            "(knitlad diagram) the fabric is compressed; a wider lx or a positive fx")


def run_ladder(settings: LadderSettings, progress: Callable[[str, float], None] | None = None) -> LadderResult:
    """The four stages in a row (refused after the stretch if the knit is not in tension: ``require_tension``)."""
    knit = stretch(settings.stretch, progress)
    require_tension(knit)
    trace = propagate(cut(knit, settings.dynamics), progress=progress)
    return analyse(trace)
