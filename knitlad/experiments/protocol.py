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

import functools
import math
import time
from dataclasses import dataclass, field, fields
from typing import Callable, Sequence

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import ContactModel, Counting, contact_time_step
from knitlad.engine.dissipation import STITCH_BENDING_HZ, AirDrag, EnergyLedger, MaterialDamping
from knitlad.fabric.measure import (
    cell_overlap,
    course_tensions,
    ladders_started,
    laddered_cells,
    periodicities,
    tension_per_thread,
)
from knitlad.fabric.observers import (
    AUTO_FRAMES,
    Arrested,
    CellTimes,
    EdgeReached,
    EnergyRecorder,
    FrontRan,
    FrameRecorder,
    FrontRecorder,
    Interpenetration,
    Observer,
    OverlapGuard,
    TOP_ROWS_HELD,
    TensionRecorder,
    TimeLimit,
)
from knitlad.fabric.scenes.jersey import BUILD_LX, CourseTooWide, Jersey, KnitScene, build_jersey, widest_fitting_width
from knitlad.engine.runloop import StopRule, run_until
from knitlad.engine.simulation import Simulation, small_scene_threads
from knitlad.experiments.stitch_model import StitchRun, StitchSettings, zero_tension_lx
from knitlad.engine.state import Rods, cut_edge, with_axial_stiffness, with_twist
from knitlad.fabric.stretching import OutOfReach, force_control, relax_to_steady_tension, stretch_to
from knitlad.engine.timestep import DEFAULT_SAFETY, MAX_STEPS, critical_time_steps
from knitlad.engine.units import Material

# The dashpots of the mu = 0 stretch. FIRE ends at a minimum whatever they are, but they shape
# its path and so pick which relaxed state of nearly the same f_x it ends in (16 x 16, target
# 13.6: contact dashpots at 0.1 and 0.6 instead of 0.3 ended at f_x^ini 13.65 and 13.56 instead
# of 13.51); the settings for the dynamics after the cut must not move the stretched knit.
STRETCH_CONTACT_DAMPING = 0.3
STRETCH_AXIAL_DAMPING = 0.2
MIN_BUILD_LX = 0.15  # narrowest l_x/l0 tried when a thick yarn does not fit at build_width
RELAX_TOL_F0 = 1e-3  # FIRE's force tolerance while stretching, in f0


def build_width(ly_over_l0: float, material: Material, nodes_per_stitch: int = 36, sagitta_radius_d: float = 0.0) -> float:
    """l_x/l0 at which to build the knit for this l_y: BUILD_LX, or narrower where the
    periodised stitch's f_x = 0 curve lies left of it (l_y/l0 > 0.25), less 0.01.

    At l_y/l0 = 0.302 a knit built at 0.30 l0 has loops that overlap the next
    course by 0.12 d only: it comes apart while being stretched (seen: f_x never
    reached 13.6 up to l_x/l0 = 0.945). At the stitch's f_x = 0 width (0.263 l0
    there) they overlap by 2.5 d and the knit is neither pulled nor compressed;
    0.01 narrower leaves room for force control below the tension the finite knit
    carries there (6 x 8 stitches, 16 nodes/stitch: f_x = 8 at the f_x = 0 width).
    """
    if ly_over_l0 <= 0.25:
        return BUILD_LX  # the f_x = 0 width is above 0.30 l0 here (0.337 at l_y/l0 = 0.25)
    try:
        return min(BUILD_LX, zero_tension_lx(ly_over_l0, material=material, nodes_per_stitch=nodes_per_stitch,
                                             sagitta_radius_d=sagitta_radius_d) - 0.01)
    except ValueError:
        return BUILD_LX


@dataclass(frozen=True)
class StretchSettings:
    """What makes a stretched knit (from :meth:`knitlad.experiments.config.CutConfig.stretch_settings`). l/l0, f_x, SI."""

    n_x: int
    n_y: int
    lx_over_l0: float | None  # position control ...
    fx_target: float | None  # ... or force control (exactly one of the two)
    ly_over_l0: float
    nodes_per_stitch: int
    contact_force_f0: float  # the contact force (in f0) at which the overlap is overlap_fraction d
    overlap_fraction: float
    edge: str  # how the course ends are held (knitlad.fabric.scenes.jersey.EDGES)
    stretch_increment: float  # l/l0 per affine step
    steps_per_increment: int  # FIRE steps per round
    fx_tolerance: float  # force control: relative
    start: str  # "tiled" from the periodised stitch (clamped ends), or "affine" from the built knit
    natural_curvature: float  # K = mean (kappa_bar/kappa0)^2 the yarn remembers (0: straight at rest)
    material: Material
    sagitta_radius_d: float = 0.0  # the contact's sagitta correction, in d (0: none; knitlad.engine.contact)
    memory_peak_ratio: float | None = None  # max/mean of (kappa_bar/kappa0)^2 (None: the scaled copy's own)

    def __post_init__(self) -> None:
        if (self.lx_over_l0 is None) == (self.fx_target is None):
            raise ValueError("give exactly one of lx_over_l0 (position control) and fx_target (force control)")
        if self.natural_curvature > 0 and (self.start, self.edge) != ("tiled", "clamped"):
            raise ValueError("natural_curvature needs the tiled stretch and clamped ends: it is set in the "
                             "periodised stitch and tiled over the knit")


@dataclass(frozen=True)
class DynamicsSettings:
    """How a stretched knit ladders (from :meth:`knitlad.experiments.config.CutConfig.dynamics_settings`). SI."""

    mu: float
    contact_counting: Counting  # of the dynamics (the stretch, a minimisation, counts UNION)
    contact_damping_ratio: float  # normal and tangential contact dashpots, fraction of critical
    stretch_damping_ratio: float  # the yarn's axial dashpot, fraction of critical
    dt_safety: float  # time step as a fraction of the stability limit
    drag_per_s: float  # global drag on every node [1/s]; 0 is the physics
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
    stop_at_edge: bool = True  # stop when a ladder reaches an edge course (else: when every front has stopped)
    loss_factor: float = 0.0  # the yarn's material damping, peak loss factor (0: none; knitlad.engine.dissipation)
    loss_peak_hz: float = STITCH_BENDING_HZ  # ... at this frequency [Hz]
    air_drag: bool = False  # still air around the yarns
    stop_after_stitches: int | None = None  # stop once a front has run this many stitches (enough for v_lad)

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


@dataclass(frozen=True)
class KnitGauge:
    """The observables of a knit at a box: f_x, course rows, column centres, laddered cells.

    Courses are found by their nodes as built (node indices never change, yarn
    indices do when a course is cut in two).
    """

    knit: KnitScene
    material: Material

    def tension(self, sim: Simulation) -> float:
        k = self.knit
        return tension_per_thread(sim.reaction_forces_N(), k.left_end, k.right_end, self.material.f0)

    def course_tensions(self, sim: Simulation) -> np.ndarray:
        """Each free course's f_x, bottom to top (:func:`knitlad.fabric.measure.course_tensions`)."""
        k = self.knit
        return course_tensions(sim.reaction_forces_N(), k.left_end, k.right_end, self.material.f0)

    def rows(self, x: np.ndarray) -> list[np.ndarray]:
        """Positions of the free courses, bottom to top, then of the held top course, by their
        nodes as built (a cut course is still one row)."""
        return [x[nodes] for nodes in self.knit.row_nodes()]

    def column_centres(self, box_lx: float) -> np.ndarray:
        """Head x of each column [internal]: the built columns, carried by the affine stretch."""
        g = self.knit.geometry
        scale = box_lx * self.material.stitch_length / g.l_x
        return g.column_x(np.arange(g.n_x)) * scale / units.LENGTH

    def periodicities(self, x: np.ndarray, box_lx: float) -> tuple[float, float]:
        """(l_x, l_y)/l0 measured on the free courses at positions ``x`` in the box ``box_lx``
        (:func:`knitlad.fabric.measure.periodicities`)."""
        l0 = self.material.stitch_length / units.LENGTH
        lx_m, ly_m = periodicities(self.rows(x)[:-1], self.column_centres(box_lx), box_lx * l0)
        return lx_m / l0, ly_m / l0

    def laddered(self, x: np.ndarray, box_lx: float, box_ly: float) -> np.ndarray:
        l0 = self.material.stitch_length / units.LENGTH
        overlap = cell_overlap(self.rows(x), self.column_centres(box_lx), box_lx * l0)
        return laddered_cells(overlap, box_ly * l0)


# ------------------------------------------------------------------ stage 1: stretch
@dataclass(frozen=True)
class StretchedKnit:
    """A knit stretched and relaxed at mu = 0: the value the laddering starts from.

    Never changed in place (:func:`cut` works on a copy), so one stretched knit can be
    laddered under several settings of the dynamics. Written and read by
    :func:`knitlad.io.hdf5.write_stretched_knit` and :func:`~knitlad.io.hdf5.read_stretched_knit`.
    """

    settings: StretchSettings
    knit: KnitScene  # geometry, model and the relaxed state, course bookkeeping
    box_lx: float  # the affine stretch of the held ends and edge courses, l/l0
    box_ly: float
    fx_ini: float
    lx_over_l0: float  # measured periodicities
    ly_over_l0: float
    fx_within_tolerance: bool  # force control: f_x^ini within fx_tolerance of the target
    relax_steps: int  # FIRE steps of the stretch and relaxation
    peak_overlap_over_d: float  # deepest yarn-yarn overlap while stretching, in d
    dt_s: float  # the stretch's time step: the dynamics take no larger one
    wall_s: float
    tension_history: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # FIRE steps, box l_x/l0, f_x

    @property
    def gauge(self) -> KnitGauge:
        return KnitGauge(self.knit, self.settings.material)


def stretch_contact(s: StretchSettings, **changes) -> ContactModel:
    """The contact model of the stretch (mu = 0, the stretch's dashpots); ``changes`` for the dynamics' (their mu)."""
    kw = dict(mu=0.0, damping_ratio=STRETCH_CONTACT_DAMPING, tangential_damping_ratio=STRETCH_CONTACT_DAMPING)
    return ContactModel.of_settings(s, **{**kw, **changes})


class KnitBox:
    """The knit in its box while it is stretched (:class:`knitlad.fabric.stretching.Box`)."""

    def __init__(self, s: StretchSettings) -> None:
        self.s = s
        m = s.material
        self.build_lx = build_width(s.ly_over_l0, m, s.nodes_per_stitch, s.sagitta_radius_d)
        self.lx = min(s.lx_over_l0, self.build_lx) if s.lx_over_l0 is not None else self.build_lx
        self.ly = s.ly_over_l0
        lx = widest_fitting_width(self.lx, self.ly, m, s.nodes_per_stitch, lx_min=MIN_BUILD_LX)
        if lx < self.lx:  # thick yarns (d/l0 = 1/20) only fit narrower
            self.lx = self.build_lx = lx
        self.knit = build_jersey(Jersey(
            n_x=s.n_x, n_y=s.n_y, l_x=self.lx * m.stitch_length, l_y=self.ly * m.stitch_length,
            nodes_per_stitch=s.nodes_per_stitch, material=m, edge=s.edge,
        ), stretch_damping_ratio=STRETCH_AXIAL_DAMPING)
        self.sim = Simulation(self.knit.rods, contact=stretch_contact(s))
        self.gauge = KnitGauge(self.knit, m)
        self.relax_steps = 0
        self.guard = OverlapGuard(m.diameter)
        self.readings: list[tuple[float, float, float]] = []  # (FIRE steps so far, box l_x/l0, f_x)

    def deform(self, lx: float, ly: float) -> None:
        x = self.sim.state.x
        x[:, 0] *= lx / self.lx
        x[:, 1] *= ly / self.ly
        self.lx, self.ly = lx, ly

    def relax(self) -> dict:
        info = self.sim.relax(force_tol_N=RELAX_TOL_F0 * self.s.material.f0, max_steps=self.s.steps_per_increment)
        self.relax_steps += info["steps"]
        return info

    def tension(self) -> float:
        fx = self.gauge.tension(self.sim)
        self.readings.append((self.relax_steps, self.lx, fx))
        return fx

    def tile(self, cell: StitchRun) -> None:
        """Every course, the edge courses too, at the relaxed shape of the periodised stitch ``cell``,
        one copy per column and per course, and the box at the cell's (l_x, l_y).

        Course r is built as n_x stitches of ``nodes_per_stitch`` nodes from a sinker, plus
        the closing node (clamped ends): node k of it is the cell's node k mod n shifted by
        (k // n) l_x columns and r l_y courses. The cell is periodic, so the tiled knit is
        the infinite relaxed fabric cut to n_x x n_y: it is at equilibrium but at its two
        edge columns, which miss their neighbours' contacts and relax locally.
        """
        g, n = self.knit.geometry, self.knit.geometry.nodes_per_stitch
        l0 = self.s.material.stitch_length / units.LENGTH
        cell_x = cell.sim.state.x[:n]  # the real yarn's nodes come first
        k = np.arange(g.n_x * n + 1)
        shift = np.zeros((k.size, 3))
        shift[:, 0] = (k // n - 0.5 * (g.n_x - 1)) * cell.lx * l0
        start = self.knit.rods.model.yarn_start  # as built: rows -1 to n_y
        x = self.sim.state.x
        for row, y in enumerate([self.knit.bars[0]] + self.knit.courses + [self.knit.bars[1]], start=-1):
            nodes = slice(int(start[y]), int(start[y + 1]))
            if nodes.stop - nodes.start != k.size:
                raise ValueError("tiling needs clamped course ends (a course of n_x stitches and one node)")
            shift[:, 1] = row * cell.ly * l0
            x[nodes] = cell_x[k % n] + shift
        self.sim.state.v[:] = 0.0
        if cell.sim.twist:
            self.tile_frames(cell)
        self.lx, self.ly = cell.lx, cell.ly

    def tile_frames(self, cell: StitchRun) -> None:
        """The cell's material frames, twist and natural curvature on every course: edge k of a course
        is the cell's edge k mod n, the hinge between edges k - 1 and k the cell's hinge k mod n (the
        cell's hinge j joins its edges j - 1 and j, hinge 0 across the seam). Switches twist on."""
        m = self.s.material
        rods = self.sim.rods if self.sim.twist else with_twist(self.sim.rods, m.twisting_stiffness / m.bending_stiffness)
        n = self.knit.geometry.nodes_per_stitch
        src_model, src = cell.sim.model, cell.sim.state
        model, state = rods.model, rods.state
        edge_yarn = model.edge_yarn
        hinge_yarn = edge_yarn[model.hinge_e1]
        kappa_bar, twist_bar = model.kappa_bar.copy(), model.twist_bar.copy()
        for y in [self.knit.bars[0]] + self.knit.courses + [self.knit.bars[1]]:
            edges = np.flatnonzero(edge_yarn == y)
            hinges = np.flatnonzero(hinge_yarn == y)
            j = np.arange(edges.size) % n
            for name in ("tangent", "ref_u", "theta"):
                getattr(state, name)[edges] = getattr(src, name)[j]
            state.omega[edges] = 0.0
            jh = np.arange(1, hinges.size + 1) % n
            state.ref_twist[hinges] = src.ref_twist[jh]
            kappa_bar[hinges] = src_model.kappa_bar[jh]
            twist_bar[hinges] = src_model.twist_bar[jh]
        rods = rods.replace_model(kappa_bar=kappa_bar, twist_bar=twist_bar, framed=cell.sim.rods.framed)
        self.knit.rods = rods
        self.sim = Simulation(rods, contact=self.sim.contact_model)

    def stretched(self, fx: float, within_tolerance: bool, wall_s: float) -> StretchedKnit:
        """The knit as it is now, as a :class:`StretchedKnit` (its f_x measured: ``fx``); stops on a deep overlap."""
        self.guard.check(self.sim, "while stretching")
        lx, ly = self.gauge.periodicities(self.sim.state.x, self.lx)
        return StretchedKnit(
            settings=self.s, knit=self.knit, box_lx=self.lx, box_ly=self.ly, fx_ini=fx, lx_over_l0=lx,
            ly_over_l0=ly, fx_within_tolerance=within_tolerance, relax_steps=self.relax_steps,
            peak_overlap_over_d=self.guard.peak_over_d, dt_s=self.sim.dt_s, wall_s=wall_s,
            tension_history=np.array(self.readings, dtype=float).reshape(-1, 3),
        )


def stretch(s: StretchSettings, progress: Callable[[str, float], None] | None = None) -> StretchedKnit:
    """Stage 1: build the knit, stretch it at mu = 0 to the target and relax it (module docstring)."""
    t0 = time.perf_counter()
    report = (lambda frac: progress("stretch", frac)) if progress else None
    box = KnitBox(s)
    within, fx = True, None
    if s.start == "tiled" and s.edge == "clamped":
        try:
            fx, within = stretch_tiled(box, report)
        except CourseTooWide:
            # thick yarns (d/l0 = 1/20): no periodised stitch whose loops interlock by d fits, so
            # the knit, built narrower, is stretched affinely (natural curvature needs the stitch)
            if s.natural_curvature > 0:
                raise
    if fx is None and s.lx_over_l0 is not None:
        stretch_to(box, s.lx_over_l0, s.ly_over_l0, s.stretch_increment, progress=report)
        fx = relax_to_steady_tension(box)
    elif fx is None:
        fx, within = force_control(box, s.fx_target, s.fx_tolerance, s.stretch_increment, box.build_lx,
                                   progress=report)
    knit = box.stretched(fx, within, time.perf_counter() - t0)
    check_whole(knit)
    return knit


class KnitCameApart(OutOfReach):
    """A knit stretched past what holds it together: its loops slipped out of each other."""


def check_whole(knit: StretchedKnit) -> None:
    """Refuse a stretched knit that is no knit: no tension (f_x <= 0) at a width 0.02 l0 or more beyond the
    periodised stitch's f_x = 0 curve, where a knit whose loops still hold each other is in tension
    (position control to l_x/l0 = 0.999 gave f_x^ini = -0.98 and every cell undone, exit 0)."""
    s = knit.settings
    if knit.fx_ini > 0 or s.lx_over_l0 is None:
        return
    try:
        unloaded = unloaded_width(s.ly_over_l0, s.nodes_per_stitch, s.material, s.sagitta_radius_d)
    except ValueError:  # no f_x = 0 point on the stitch's range: nothing to hold it against
        return
    if knit.lx_over_l0 > unloaded + 0.02:
        raise KnitCameApart(f"the knit came apart: at l_x/l0 = {knit.lx_over_l0:.3f} it carries f_x = "
                            f"{knit.fx_ini:.3g}, where a knit that holds together is in tension (beyond the "
                            f"f_x = 0 width {unloaded:.3f} at l_y/l0 = {s.ly_over_l0:g}); stretch it less")


def stitch_of(s: StretchSettings, lx_over_l0: float) -> StitchRun:
    """The periodised stitch of the knit ``s`` (its resolution, contact and increments), built at
    min(``lx_over_l0``, 0.30) (:class:`knitlad.experiments.stitch_model.StitchRun`) and relaxed."""
    cell = StitchRun(StitchSettings(
        lx_over_l0=lx_over_l0, ly_over_l0=s.ly_over_l0, nodes_per_stitch=s.nodes_per_stitch,
        material=s.material, contact_force_f0=s.contact_force_f0, overlap_fraction=s.overlap_fraction,
        sagitta_radius_d=s.sagitta_radius_d, stretch_increment=s.stretch_increment))
    cell.relax()
    return cell


def stretch_tiled(box: KnitBox, report: Callable[[float], None] | None = None,
                  corrections: int = 3) -> tuple[float, bool]:
    """The stretch from the periodised stitch (clamped ends); returns (f_x, within the tolerance).

    The stitch, a few hundred nodes, is stretched to the target (l_x, or f_x by force
    control) and relaxed; the knit is tiled with it (:meth:`KnitBox.tile`) and relaxed
    to a steady f_x, which differs from the stitch's by its edges. Force control then
    corrects the stitch's target by the ratio of the two tensions and tiles again
    (at most ``corrections`` times). The stitch takes under a second, and the knit
    relaxes only near its edge columns instead of through every affine increment.
    """
    s = box.s
    report = report or (lambda fraction: None)
    with small_scene_threads():
        # from the knit's build width: tall cells are built narrower (build_width)
        cell = stitch_of(s, box.build_lx)
        stretch_to(cell, cell.lx, s.ly_over_l0, s.stretch_increment, min_increments=0)
        if s.natural_curvature > 0:
            remember_unloaded_shape(cell, s)
        if s.lx_over_l0 is not None:
            stretch_to(cell, s.lx_over_l0, s.ly_over_l0, s.stretch_increment, min_increments=0)
            target = None
        else:
            target = s.fx_target
            force_control(cell, target, 0.25 * s.fx_tolerance, s.stretch_increment, MIN_BUILD_LX)
        cell_fx = settled_tension(cell)
    check_stitch_held(box, cell)
    report(0.2)
    box.tile(cell)
    fx = relax_to_steady_tension(box)
    if target is None:
        report(1.0)
        return fx, True
    for k in range(corrections):
        if abs(fx - target) <= s.fx_tolerance * target or fx <= 0 or cell_fx <= 0:
            break
        with small_scene_threads():
            force_control(cell, target * cell_fx / fx, 0.25 * s.fx_tolerance, s.stretch_increment, MIN_BUILD_LX)
            cell_fx = settled_tension(cell)
        check_stitch_held(box, cell)
        box.tile(cell)
        fx = relax_to_steady_tension(box)
        report(0.2 + 0.8 * (k + 1) / corrections)
    report(1.0)
    return fx, bool(abs(fx - target) <= s.fx_tolerance * target)


class StitchPassedThrough(KnitCameApart, Interpenetration):
    """The periodised stitch's yarns passed through each other while it was stretched: stretched too far,
    or on a contact too soft for the tension (either cause; one error for both handlers)."""


def check_stitch_held(box: KnitBox, cell: StitchRun) -> None:
    """Stop when the stitch's yarns overlapped past the guard's limit while it was stretched: its loops
    went through each other, and a knit tiled from it would read as one that came apart."""
    try:
        box.guard.check(cell.sim, "while stretching the periodised stitch")
    except Interpenetration:
        g = box.guard
        raise StitchPassedThrough(
            f"yarns overlap by {g.peak_over_d:.2f} d while stretching the periodised stitch (limit {g.limit} d): its "
            "loops passed through each other and the knit came apart; stretch it less, or, if the contact is too "
            "soft for this tension, raise contact_force_f0") from None


@functools.lru_cache(maxsize=16)
def unloaded_width(ly_over_l0: float, nodes_per_stitch: int, material: Material, sagitta_radius_d: float = 0.0) -> float:
    """l_x/l0 of the periodised stitch on the f_x = 0 curve at this l_y (cached: a sweep asks it often)."""
    return zero_tension_lx(ly_over_l0, material=material, nodes_per_stitch=nodes_per_stitch,
                           sagitta_radius_d=sagitta_radius_d)


def remember_unloaded_shape(cell: StitchRun, s: StretchSettings) -> None:
    """The stitch is taken to the f_x = 0 curve (the unloaded fabric), relaxed, and remembers that shape
    with mean (kappa_bar/kappa0)^2 = K (:mod:`knitlad.fabric.shape_memory`); relaxed again, twist on."""
    stretch_to(cell, unloaded_width(s.ly_over_l0, s.nodes_per_stitch, s.material, s.sagitta_radius_d), s.ly_over_l0,
               s.stretch_increment, min_increments=0)
    cell.settle()
    try:
        cell.remember_shape(s.natural_curvature, s.memory_peak_ratio)
    except ValueError as e:  # a peak the stitch's hinges cannot give: the settings ask the impossible
        raise InfeasibleRun(f"memory_peak_ratio: {e}") from None
    cell.settle()


def settled_tension(cell: StitchRun) -> float:
    """Relax the stitch to its final tolerance; its f_x."""
    cell.settle()
    return cell.tension()


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
    """The stretched knit's rods as the dynamics run them: their dashpots, axial stiffness and twist."""
    rods = rods.replace_model(
        stretch_damping=rods.model.stretch_damping * (dynamics.stretch_damping_ratio / STRETCH_AXIAL_DAMPING))
    if dynamics.axial_stiffness_factor != 1.0:
        rods = with_axial_stiffness(rods, dynamics.axial_stiffness_factor)
    if dynamics.twist and not rods.twist:  # a yarn with natural curvature carries twist from the stretch
        rods = with_twist(rods, material.twisting_stiffness / material.bending_stiffness)
    if rods.twist and dynamics.twist_inertia_factor != 1.0:
        # a heavier spin, for studies: the yarns roll at the contacts, so the spin inertia enters the ladder
        # (docs/accuracy.md, default 1); the step does not need it (laddering_time_step)
        rods = rods.replace_model(twist_inertia=rods.model.twist_inertia * dynamics.twist_inertia_factor)
    return rods


def dynamics_simulation(rods: Rods, knit: StretchedKnit, dynamics: DynamicsSettings) -> Simulation:
    """A simulation of ``rods`` (:func:`dynamics_rods`) under the dynamics' contact, friction and step."""
    contact = stretch_contact(knit.settings, mu=dynamics.mu, damping_ratio=dynamics.contact_damping_ratio,
                              tangential_damping_ratio=dynamics.contact_damping_ratio,
                              counting=dynamics.contact_counting)
    # a cut frees two end nodes: keep the smaller of the stretch's step (of a yarn as soft) and the new stable step
    stretch_step = math.inf if dynamics.implicit_axial else knit.dt_s / math.sqrt(dynamics.axial_stiffness_factor)
    sim = Simulation(rods, contact=contact, dt_s=min(stretch_step, laddering_time_step(rods, contact, dynamics)),
                     drag_per_s=dynamics.drag_per_s, framed_twist=dynamics.framed_twist,
                     implicit_axial=dynamics.implicit_axial, predicted_dashpots=dynamics.predicted_dashpots,
                     material_damping=dynamics.material_damping, air=dynamics.air)
    check_feasible(sim.dt_s, dynamics)
    return sim


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


class InfeasibleRun(ValueError):
    """Settings whose time step cannot serve the run: longer than what it observes, or absurdly many steps."""


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
    final_laddered: np.ndarray  # cells undone after the cut
    undone_at: np.ndarray  # (n_y, n_x) when each cell came undone after the cut [s], NaN: never
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


def propagate(run: Laddering, observers: Sequence[Observer] = (), progress: Callable[[str, float], None] | None = None,
              stop_rules: Sequence[StopRule] | None = None) -> LadderTrace:
    """Stage 3: run the free dynamics, calling the observers every ``observe_every_s``, until a stop rule fires.

    The standard recorders (fronts, tension, frames, overlap guard) always run; ``observers``
    are called after them with (t, run, undone cells). ``stop_rules``: default the ladder
    reaching an edge course, no cell changed for ``arrest_s``, ``max_time_s``.
    """
    t0 = time.perf_counter()
    d = run.dynamics
    columns = (run.cut_column - 1, run.cut_column)
    guard = OverlapGuard(run.knit.settings.material.diameter)
    fronts, tension, cell_times = FrontRecorder(columns, run.cut_row), TensionRecorder(), CellTimes()
    frames, energy = FrameRecorder(frame_interval(run)), EnergyRecorder()
    rules = list(stop_rules) if stop_rules is not None else (
        [EdgeReached()] * d.stop_at_edge + [Arrested(d.arrest_s), TimeLimit(d.max_time_s)]
        + ([FrontRan(d.stop_after_stitches, columns, run.cut_row)] if d.stop_after_stitches else []))
    undone = np.zeros_like(run.baseline)
    frames.observe(0.0, run, undone)  # the stretched knit just cut, before the first step
    times: list[float] = []

    def observe(t: float) -> np.ndarray:
        guard.check(run.sim, f"at t = {t * 1e3:.3f} ms after the cut")
        undone[...] |= run.laddered() & ~run.baseline  # an undone cell does not knit itself again
        times.append(t)
        for obs in (fronts, tension, cell_times, frames, energy, *observers):
            obs.observe(t, run, undone)
        if progress:  # the ladder's reach (it stops at an edge course) or the time limit, whichever is further
            progress("propagate", max(min(t / d.max_time_s, 1.0), fronts.reach(run.knit.settings.n_y)))
        return undone

    t, rule, reason = run_until(run.sim, max(1, int(round(d.observe_every_s / run.sim.dt_s))), observe, rules)
    frames.observe(t, run, undone, last=True)  # the state at the stop
    return LadderTrace(
        knit=run.knit, dynamics=d, cut_row=run.cut_row, columns=columns, times_s=np.array(times),
        fx=np.array(tension.fx), fx_courses=np.array(tension.fx_courses), fronts=fronts.extents(),
        column_cells=fronts.cells(), frames=frames, energy=energy.series(),
        baseline=run.baseline, final_laddered=undone, undone_at=cell_times.undone_at, stop_reason=reason,
        reached_edge=EdgeReached.reached(undone), steps=run.sim.steps,
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
    n_lad: int = 0
    n_lad_over_ny: float = math.nan
    v_lad_over_cb: float = math.nan
    laddering_column: int = -1  # the column beside the cut whose front is followed (measure.laddering_column)
    reached_edge: bool = False
    stop_reason: str = ""
    v_fit_stitches: tuple = (2, 10)
    wall_s: dict = field(default_factory=dict)
    times_s: list = field(default_factory=list)
    front_up: list = field(default_factory=list)
    front_down: list = field(default_factory=list)
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
    final_laddered: np.ndarray | None = None
    baseline_laddered: np.ndarray | None = None
    undone_at: np.ndarray | None = None  # (n_y, n_x) when each cell came undone [s], NaN: never
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
        out["ledger_residual"] = last["residual"] / last["turnover"] if last["turnover"] > 0 else 0.0
        return out

    def nan_reasons(self) -> dict[str, str]:
        """Why each result that is NaN is NaN (every NaN of the summary has its reason here)."""
        first, last = self.v_fit_stitches
        ran = max(self.front_up) if self.front_up else 0
        reasons = {
            "v_lad_over_cb": f"the front ran {ran} stitch{'es' * (ran != 1)} above the cut, short of the fit's last, "
                             f"{last} ({self.stop_reason})",
            "fx_fin_crossed": "the ladder crossed no course",
            "fx_fin_intact": "the ladder crossed every course",
            "first_down_ms": "no ladder started downwards",
            "second_up_ms": "no second ladder started upwards",
            "fx_fin": "no tension was read after the cut",
        }
        summary_nan = {k for k in reasons if isinstance(getattr(self, k, None), float) and math.isnan(getattr(self, k))}
        record = self.loop_record()
        summary_nan |= {k for k in ("first_down_ms", "second_up_ms") if math.isnan(record[k])}
        return {k: reasons[k] for k in reasons if k in summary_nan}

    def summary(self) -> dict:
        """The scalar results, and the settings a reader needs beside them (mu, twist, drag)."""
        d = self.settings.dynamics
        skip = {"settings", "wall_s", "times_s", "front_up", "front_down", "fx_series", "fx_course_series",
                "column_history", "frames",
                "frame_times_s", "final_laddered", "baseline_laddered", "yarn_start", "frame_velocities",
                "frame_laddered", "frame_contact", "stretch_tension", "node_course", "cut_node", "cell_centres", "edges",
                "undone_at", "energy_series"}
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in skip}
        out["v_fit_stitches"] = list(self.v_fit_stitches)
        out["v_fit_first"], out["v_fit_last"] = (int(k) for k in self.v_fit_stitches)
        out.update(mu=d.mu, twist=d.twist, drag_per_s=d.drag_per_s, loss_factor=d.loss_factor, air_drag=d.air_drag,
                   natural_curvature=self.settings.stretch.natural_curvature, wall_s=float(sum(self.wall_s.values())))
        out.update(self.energy_record())
        out.update({f"wall_{k}_s": v for k, v in self.wall_s.items()})
        out.update(self.loop_record())
        out.update(self.damage_record())
        out["nan_reasons"] = "; ".join(f"{k}: {why}" for k, why in self.nan_reasons().items())
        return out

    def ladders(self) -> list[dict]:
        """The ladders the cut started, by column and direction, and the freed loop of Fig. 2d behind each
        (:func:`knitlad.fabric.measure.ladders_started`)."""
        return [] if self.undone_at is None else ladders_started(self.undone_at, self.cut_row)

    def damage_record(self) -> dict:
        """n_lad split as Eq. 1 reads it (:func:`knitlad.fabric.measure.damage_parts`): the cells of the cut row,
        those undone within 0.1 ms of the cut, and those the ladder released into loaded courses, with the last
        over n_y (``n_lad_released_over_ny``: the damage Eq. 1 predicts, like for like)."""
        from knitlad.fabric.measure import damage_parts

        if self.undone_at is None:
            parts = {"cut_row": self.n_lad, "immediate": 0, "released": 0}  # an older file: nothing to split by
        else:
            parts = damage_parts(self.undone_at, self.cut_row)
        n_y = self.settings.stretch.n_y
        return {"n_lad_cut_row": parts["cut_row"], "n_lad_immediate": parts["immediate"],
                "n_lad_released": parts["released"], "n_lad_released_over_ny": parts["released"] / n_y}

    def loop_record(self) -> dict:
        """Summary of :meth:`ladders`: ladders up and down, when the first downward (loops (2)/(3)) and the
        second upward (loops (4)/(5)) started [ms after the cut; NaN: never], and ``hindered``: the pattern
        the paper calls hindered laddering (appendix "Hindered laddering"), one upward ladder and two or
        more downward, the cut thread held in loops (4) and (5). Read from the cells, as the paper read its
        photographs; the thread's topology is not tested."""
        ladders = self.ladders()
        start = {loop: next((lad["start_s"] * 1e3 for lad in ladders if lad["loop"] == loop), math.nan)
                 for loop in ("2/3", "4/5")}
        up = sum(lad["direction"] > 0 for lad in ladders)
        down = sum(lad["direction"] < 0 for lad in ladders)
        return {"ladders_up": up, "ladders_down": down, "first_down_ms": start["2/3"],
                "second_up_ms": start["4/5"], "hindered": bool(up == 1 and down >= 2)}


def analyse(trace: LadderTrace) -> LadderResult:
    """Stage 4: the laddering column (the one whose ladder ran farthest up, then down, fixed for
    the run as the paper follows one), n_lad/n_y, f_x^fin and v_lad/c_b (paper Fig. 3d)."""
    from knitlad.fabric.measure import laddering_column, laddering_velocity

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
    v_lad = laddering_velocity(trace.times_s, front[:, 0], l_y, first, last)
    n_lad = int(trace.final_laddered.sum())
    fin_courses = trace.fx_courses[window].mean(axis=0)
    crossed = trace.final_laddered.any(axis=1)  # courses with an undone cell: the ladder relaxed them

    def mean_of(rows: np.ndarray) -> float:
        return float(fin_courses[rows].mean()) if rows.any() else math.nan

    return LadderResult(
        settings=LadderSettings(s, d), fx_ini=knit.fx_ini, fx_fin=float(np.mean(trace.fx[window])),
        fx_fin_crossed=mean_of(crossed), fx_fin_intact=mean_of(~crossed), fx_course_series=trace.fx_courses,
        lx_over_l0=knit.lx_over_l0, ly_over_l0=knit.ly_over_l0, n_lad=n_lad, n_lad_over_ny=n_lad / s.n_y,
        v_lad_over_cb=v_lad / s.material.c_b, laddering_column=trace.columns[best], reached_edge=trace.reached_edge,
        stop_reason=trace.stop_reason, v_fit_stitches=(first, last),
        wall_s={"stretch": knit.wall_s, "propagate": trace.wall_s}, times_s=list(trace.times_s),
        front_up=[int(u) for u in front[:, 0]], front_down=[int(v) for v in front[:, 1]], fx_series=list(trace.fx),
        column_history=list(trace.column_cells[best]), frames=trace.frames.frames,
        frame_times_s=trace.frames.times_s, frame_velocities=trace.frames.velocities,
        frame_laddered=trace.frames.laddered, frame_contact=trace.frames.contact, node_course=knit.knit.node_course(), cut_node=trace.cut_node,
        cell_centres=trace.cell_centres, edges=trace.edges, stretch_tension=knit.tension_history,
        final_laddered=trace.final_laddered, baseline_laddered=trace.baseline, yarn_start=trace.yarn_start,
        undone_at=trace.undone_at, cut_row=trace.cut_row,
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
