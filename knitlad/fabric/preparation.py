"""Preparing a knit for an experiment: built, stretched at mu = 0 to a target and relaxed (the paper's protocol,
its first stage), with the box and gauge that measure it.

    stretch(StretchSettings) -> StretchedKnit    the knit at mu = 0, stretched and relaxed

The knit is built at the target l_y and at l_x = min(target, 0.30 l0) (narrower for l_y > 0.25 l0:
:func:`build_width`); from there either every course is tiled with the periodised stitch stretched to
the target (``stretch_start="tiled"``, :func:`stretch_tiled`) or the whole fabric is stretched affinely
(:mod:`knitlad.fabric.stretching`), by position or by force control, and relaxed to a steady f_x. The
laddering (:mod:`knitlad.experiments.laddering`), protocol B (:mod:`knitlad.experiments.cycling`) and any
other test of the fabric start from a :class:`StretchedKnit`.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import ContactModel
from knitlad.engine.deprecation import renamed_arguments, renamed_fields
from knitlad.engine.simulation import Simulation, small_scene_threads
from knitlad.engine.state import with_twist
from knitlad.engine.units import Material
from knitlad.fabric.measure import (
    cell_overlap,
    course_tensions,
    laddered_cells,
    midline_heights,
    periodicities,
    taut_cells,
    tension_per_thread,
    transverse_tension,
)
from knitlad.fabric.observers import Interpenetration, OverlapGuard
from knitlad.fabric.patterns import knit_pattern
from knitlad.fabric.scenes.knit import (
    BUILD_LX,
    CourseTooWide,
    KnitGeometry,
    KnitScene,
    build_knit,
    build_loop_overlap,
    widest_fitting_width,
)
from knitlad.fabric.stitch_model import StitchRun, StitchSettings, zero_tension_lx
from knitlad.fabric.stretching import OutOfReach, force_control, relax_to_steady_tension, stretch_to


class InfeasibleRun(ValueError):
    """Settings that cannot serve the run, found when it is set: a time step longer than what it observes or
    absurdly many steps, a memory the stitch cannot take, a knit not in tension where one is needed."""


# The dashpots of the mu = 0 stretch. FIRE ends at a minimum whatever they are, but they shape
# its path and so pick which relaxed state of nearly the same f_x it ends in (16 x 16, target
# 13.6: contact dashpots at 0.1 and 0.6 instead of 0.3 ended at f_x^ini 13.65 and 13.56 instead
# of 13.51); the settings for the dynamics after the cut must not move the stretched knit.
STRETCH_CONTACT_DAMPING = 0.3
STRETCH_AXIAL_DAMPING = 0.2
MIN_BUILD_LX = 0.15  # narrowest l_x/l0 tried when a thick yarn does not fit at build_width
RELAX_TOL_F0 = 1e-3  # FIRE's force tolerance while stretching, in f0


@renamed_arguments({"ly_over_l0": "ly", "nodes_per_stitch": "resolution", "sagitta_radius_d": "sagitta_radius"},
                   since="0.14.0")
def build_width(ly: float, material: Material, resolution: int = 36, sagitta_radius: float = 0.0) -> float:
    """l_x/l0 at which to build the knit for this l_y: BUILD_LX, or narrower where the
    periodised stitch's f_x = 0 curve lies left of it (l_y/l0 > 0.25), less 0.01.

    At l_y/l0 = 0.302 a knit built at 0.30 l0 has loops that overlap the next
    course by 0.12 d only: it comes apart while being stretched (seen: f_x never
    reached 13.6 up to l_x/l0 = 0.945). At the stitch's f_x = 0 width (0.263 l0
    there) they overlap by 2.5 d and the knit is neither pulled nor compressed;
    0.01 narrower leaves room for force control below the tension the finite knit
    carries there (6 x 8 stitches, 16 nodes/stitch: f_x = 8 at the f_x = 0 width).
    """
    if ly <= 0.25:
        return BUILD_LX  # the f_x = 0 width is above 0.30 l0 here (0.337 at l_y/l0 = 0.25)
    try:
        return min(BUILD_LX, zero_tension_lx(ly, material=material, resolution=resolution,
                                             sagitta_radius=sagitta_radius) - 0.01)
    except ValueError:
        return BUILD_LX


# the stretch's settings' names up to 0.13 -> the config's, which they take since 0.14 (also the stored files')
RENAMED_STRETCH_SETTINGS = {"lx_over_l0": "lx", "fx_target": "fx", "ly_over_l0": "ly", "nodes_per_stitch": "resolution",
                            "start": "stretch_start", "sagitta_radius_d": "sagitta_radius"}


@renamed_fields(RENAMED_STRETCH_SETTINGS, since="0.14.0")
@dataclass(frozen=True)
class StretchSettings:
    """What makes a stretched knit (from :meth:`knitlad.experiments.config.CutConfig.stretch_settings`, where each field
    has its default and unit, under the same name). l/l0, f_x, SI."""

    n_x: int
    n_y: int
    lx: float | None  # l_x/l0: position control ...
    fx: float | None  # ... or f_x^ini: force control (exactly one of the two)
    ly: float  # l_y/l0
    resolution: int
    contact_force_f0: float  # the contact force (in f0) at which the overlap is overlap_fraction d
    overlap_fraction: float
    edge: str  # how the course ends are held (knitlad.fabric.scenes.knit.EDGES)
    stretch_increment: float  # l/l0 per affine step
    steps_per_increment: int  # FIRE steps per round
    fx_tolerance: float  # force control: relative
    stretch_start: str  # "tiled" from the periodised stitch (clamped ends), or "affine" from the built knit
    natural_curvature: float  # K = mean (kappa_bar/kappa0)^2 the yarn remembers (0: straight at rest)
    material: Material
    sagitta_radius: float  # the contact's sagitta correction, in d (0: none; knitlad.engine.contact)
    contact_law: str  # the contact's normal law (knitlad.engine.kernels.contact_law)
    memory_peak_ratio: float | None  # max/mean of (kappa_bar/kappa0)^2 (None: the scaled copy's own)
    pattern: str  # the knit's pattern (knitlad.fabric.patterns.PATTERNS)
    pattern_band: tuple[str, int, int] | None  # (pattern, first course, courses) knitted in another pattern
    # (first course, courses, K): a run-stop band of courses whose yarn remembers K instead of natural_curvature
    memory_band: tuple[int, int, float] | None
    bars: str  # how the edge courses below and above are held (knitlad.fabric.scenes.knit.BARS)
    knit_seed: int | None  # an ensemble member's knit: its yarn displaced at random (perturb_knit; None: none)

    def __post_init__(self) -> None:
        if (self.lx is None) == (self.fx is None):
            raise ValueError("give exactly one of lx (position control) and fx (force control)")
        if self.remembers and (self.stretch_start, self.edge) != ("tiled", "clamped"):
            raise ValueError("natural_curvature (or a memory band) needs the tiled stretch and clamped ends: it is "
                             "set in the periodised stitch and tiled over the knit")
        if (self.pattern != "jersey" or self.pattern_band is not None) and self.stretch_start != "affine":
            raise ValueError(f"pattern {self.pattern} (band {self.pattern_band}): the periodised stitch is "
                             "jersey's; this knit is stretched affinely (stretch_start='affine')")
        if self.memory_band is not None and self.memory_band[2] <= 0:
            raise ValueError(f"memory_band: the band's K must be above 0, not {self.memory_band[2]}")

    @property
    def remembers(self) -> bool:
        """Some yarn of the knit has natural curvature (the whole knit, or a memory band)."""
        return self.natural_curvature > 0 or self.memory_band is not None

    @property
    def cell_memory(self) -> float:
        """K the periodised stitch remembers: the band's, if there is one (the other courses take theirs
        from it by scaling, :meth:`KnitBox.tile_frames`), else the knit's."""
        return self.natural_curvature if self.memory_band is None else self.memory_band[2]


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
        return tension_per_thread(sim.reaction_forces_N(), k.left_end, k.right_end, self.material.f0,
                                  k.left_share, k.right_share)

    def tension_y(self, sim: Simulation) -> float:
        """f_y per column (:func:`knitlad.fabric.measure.transverse_tension`)."""
        held = np.union1d(np.flatnonzero(sim.model.held), sim.model.rail_node)  # sliding bars: their rails
        return transverse_tension(sim.reaction_forces_N(), held, sim.state.x[held, 1], self.knit.geometry.n_x,
                                  self.material.f0)

    def course_tensions(self, sim: Simulation) -> np.ndarray:
        """Each free course's f_x, bottom to top (:func:`knitlad.fabric.measure.course_tensions`)."""
        k = self.knit
        return course_tensions(sim.reaction_forces_N(), k.left_end, k.right_end, self.material.f0,
                               k.left_share, k.right_share)

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
        repeat = knit_pattern(self.knit.geometry.pattern).period[0]
        lx_m, ly_m = periodicities(self.rows(x)[:-1], self.column_centres(box_lx), box_lx * l0, repeat=repeat)
        return lx_m / l0, ly_m / l0

    def overlap_over_ly(self, x: np.ndarray, box_lx: float, box_ly: float) -> np.ndarray:
        """Each cell's overlap (:func:`knitlad.fabric.measure.cell_overlap`) in l_y: > 0 holds, -inf its yarn gone."""
        l0 = self.material.stitch_length / units.LENGTH
        return cell_overlap(self.rows(x), self.column_centres(box_lx), box_lx * l0) / (box_ly * l0)

    def laddered(self, x: np.ndarray, box_lx: float, box_ly: float) -> np.ndarray:
        return laddered_cells(self.overlap_over_ly(x, box_lx, box_ly), 1.0)

    def taut(self, x: np.ndarray, box_lx: float, box_ly: float) -> np.ndarray:
        """Cells whose bar is taut (:func:`knitlad.fabric.measure.taut_cells`)."""
        return taut_cells(self.overlap_over_ly(x, box_lx, box_ly), 1.0)

    def midline_heights(self, x: np.ndarray, box_lx: float, columns) -> np.ndarray:
        """(n_y + 1, len(columns)) each course's height where it crosses each column's mid-line [l0] (the held
        top course last; :func:`knitlad.fabric.measure.midline_heights`), the columns' x fixed as the box's."""
        l0 = self.material.stitch_length / units.LENGTH
        centres = self.column_centres(box_lx)[np.asarray(columns, dtype=np.int64)]
        return midline_heights(self.rows(x), centres, 0.5 * box_lx * l0) / l0


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
        self.build_lx = build_width(s.ly, m, s.resolution, s.sagitta_radius)
        self.lx = min(s.lx, self.build_lx) if s.lx is not None else self.build_lx
        self.ly = s.ly
        try:
            band = None if s.pattern_band is None else s.pattern_band[0]
            lx = widest_fitting_width(self.lx, self.ly, m, s.resolution,
                                      min_loop_overlap=build_loop_overlap(m, s.pattern, band), lx_min=MIN_BUILD_LX,
                                      pattern=s.pattern)
        except CourseTooWide:
            if s.pattern != "jersey" or s.pattern_band is not None:
                raise
            # the thickest jersey yarns (d/l0 = 1/20): built where a stitch holds l0 at all; the first
            # relaxation pushes their touching loops apart (docs/history.md: peak overlap 0.005 d)
            lx = widest_fitting_width(self.lx, self.ly, m, s.resolution, lx_min=MIN_BUILD_LX)
        if lx < self.lx:  # thick yarns and purl stitches only fit narrower
            self.lx = self.build_lx = lx
        self.knit = build_knit(KnitGeometry(
            n_x=s.n_x, n_y=s.n_y, l_x=self.lx * m.stitch_length, l_y=self.ly * m.stitch_length,
            resolution=s.resolution, material=m, edge=s.edge, bars=s.bars, pattern=s.pattern,
            band=None if s.pattern_band is None else tuple(s.pattern_band),
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

        Course r is built as n_x stitches of ``resolution`` nodes from a sinker, plus
        the closing node (clamped ends): node k of it is the cell's node k mod n shifted by
        (k // n) l_x columns and r l_y courses. The cell is periodic, so the tiled knit is
        the infinite relaxed fabric cut to n_x x n_y: it is at equilibrium but at its two
        edge columns, which miss their neighbours' contacts and relax locally. On the continuous
        edge the odd courses are the same, run backwards, and the turning loops are laid again
        between the courses' new ends (:meth:`KnitScene.place_turning_loops`).
        """
        g, n = self.knit.geometry, self.knit.geometry.resolution
        l0 = self.s.material.stitch_length / units.LENGTH
        cell_x = cell.sim.state.x[:n]  # the real yarn's nodes come first
        k = np.arange(g.n_x * n + 1)
        shift = np.zeros((k.size, 3))
        shift[:, 0] = (k // n - 0.5 * (g.n_x - 1)) * cell.lx * l0
        x = self.sim.state.x
        for row, nodes in enumerate([self.knit.yarn_nodes(self.knit.bars[0])] + self.knit.row_nodes(), start=-1):
            if nodes.stop - nodes.start != k.size:
                raise ValueError("tiling needs clamped course ends (a course of n_x stitches and one node)")
            shift[:, 1] = row * cell.ly * l0
            tiled = cell_x[k % n] + shift
            backwards = x[nodes.start, 0] > x[nodes.stop - 1, 0]
            x[nodes] = tiled[::-1] if backwards else tiled
        self.knit.place_turning_loops(x)
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
        n = self.knit.geometry.resolution
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
        if self.s.memory_band is not None:
            self.scale_memory_outside_band(model.hinge_e1, edge_yarn, kappa_bar, twist_bar)
        rods = rods.replace_model(kappa_bar=kappa_bar, twist_bar=twist_bar, framed=cell.sim.rods.framed)
        self.knit.rods = rods
        self.sim = Simulation(rods, contact=self.sim.contact_model)

    def scale_memory_outside_band(self, hinge_e1, edge_yarn, kappa_bar, twist_bar) -> None:
        """The courses outside the memory band (and the held bars) remember the knit's K instead of the
        band's: their natural curvature, tiled from the stitch that remembered the band's K, is scaled by
        sqrt(K / K_band) (the memory is proportional to alpha, :mod:`knitlad.fabric.shape_memory`, and a
        uniform scale keeps its max/mean peak ratio); a yarn that remembers nothing (K = 0) has no natural
        twist either. In place."""
        first, courses, k_band = self.s.memory_band
        band = set(self.knit.courses[first:first + courses])
        outside = np.isin(edge_yarn[hinge_e1], [y for y in self.knit.courses + self.knit.bars if y not in band])
        kappa_bar[outside] *= math.sqrt(self.s.natural_curvature / k_band)
        if self.s.natural_curvature == 0:
            twist_bar[outside] = 0.0

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
    if s.stretch_start == "tiled" and s.edge in ("clamped", "continuous"):
        try:
            fx, within = stretch_tiled(box, report)
        except CourseTooWide:
            # thick yarns (d/l0 = 1/20): no periodised stitch whose loops interlock by d fits, so
            # the knit, built narrower, is stretched affinely (natural curvature needs the stitch)
            if s.remembers:
                raise
    if fx is None and s.lx is not None:
        stretch_to(box, s.lx, s.ly, s.stretch_increment, progress=report)
        fx = relax_to_steady_tension(box)
    elif fx is None:
        fx, within = force_control(box, s.fx, s.fx_tolerance, s.stretch_increment, box.build_lx,
                                   progress=report)
    if s.knit_seed is not None:
        perturb_knit(box.sim, s.knit_seed, KNIT_NOISE * s.material.diameter)
        fx = box.gauge.tension(box.sim)
    knit = box.stretched(fx, within, time.perf_counter() - t0)
    check_whole(knit)
    return knit


KNIT_NOISE = 0.001  # an ensemble member's knit: each free node displaced across its yarn by this many d, rms


def perturb_knit(sim: Simulation, seed: int, rms_m: float) -> None:
    """Displace every free node of ``sim`` across its yarn (normal to its local tangent, which keeps every
    segment's length to second order) by a Gaussian of ``rms_m`` [m] per direction, drawn from ``seed``; the
    forces are evaluated anew. Two seeds give two knits: the paper's ensemble of samples, where one knit
    ladders by chance as it does (run-to-run scatter of about 20 % at low tension)."""
    m, x = sim.model, sim.state.x
    rng = np.random.default_rng(seed)
    tangent = np.zeros_like(x)
    for y in range(m.n_yarns):
        a, b = int(m.yarn_start[y]), int(m.yarn_start[y + 1])
        if b - a >= 2:
            tangent[a:b] = np.gradient(x[a:b], axis=0)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-300)
    kick = rng.normal(scale=rms_m / units.LENGTH, size=x.shape)  # [internal length]
    kick -= np.sum(kick * tangent, axis=1, keepdims=True) * tangent
    sim.displace_free(kick * units.LENGTH)


class KnitCameApart(OutOfReach):
    """A knit stretched past what holds it together: its loops slipped out of each other."""


def check_whole(knit: StretchedKnit) -> None:
    """Refuse a stretched knit that is no knit: no tension (f_x <= 0) at a width 0.02 l0 or more beyond the
    periodised stitch's f_x = 0 curve, where a knit whose loops still hold each other is in tension
    (position control to l_x/l0 = 0.999 gave f_x^ini = -0.98 and every cell undone, exit 0)."""
    s = knit.settings
    if knit.fx_ini > 0 or s.lx is None or s.pattern != "jersey" or s.pattern_band is not None:
        # the f_x = 0 width is jersey's
        return
    try:
        unloaded = unloaded_width(s.ly, s.resolution, s.material, s.sagitta_radius, s.contact_law)
    except ValueError:  # no f_x = 0 point on the stitch's range: nothing to hold it against
        return
    if knit.lx_over_l0 > unloaded + 0.02:
        raise KnitCameApart(f"the knit came apart: at l_x/l0 = {knit.lx_over_l0:.3f} it carries f_x = "
                            f"{knit.fx_ini:.3g}, where a knit that holds together is in tension (beyond the "
                            f"f_x = 0 width {unloaded:.3f} at l_y/l0 = {s.ly:g}); stretch it less")


def stitch_of(s: StretchSettings, lx: float) -> StitchRun:
    """The periodised stitch of the knit ``s`` (its resolution, contact and increments), built at
    min(``lx``, 0.30) (:class:`knitlad.fabric.stitch_model.StitchRun`) and relaxed."""
    cell = StitchRun(StitchSettings(
        lx=lx, ly=s.ly, resolution=s.resolution,
        material=s.material, contact_force_f0=s.contact_force_f0, overlap_fraction=s.overlap_fraction,
        sagitta_radius=s.sagitta_radius, stretch_increment=s.stretch_increment, contact_law=s.contact_law))
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
        stretch_to(cell, cell.lx, s.ly, s.stretch_increment, min_increments=0)
        if s.remembers:
            remember_unloaded_shape(cell, s)
        if s.lx is not None:
            stretch_to(cell, s.lx, s.ly, s.stretch_increment, min_increments=0)
            target = None
        else:
            target = s.fx
            force_control(cell, target, 0.25 * s.fx_tolerance, s.stretch_increment, MIN_BUILD_LX)
        cell_fx = settled_tension(cell)
    check_stitch_held(box, cell)
    report(0.2)
    box.tile(cell)
    fx = relax_to_steady_tension(box)
    if target is None:
        report(1.0)
        return fx, True
    # the continuous edge's turning loops pull on their clips with a force of their own, so its f_x is not
    # proportional to the stitch's (16 x 16, default preset, target 1.58: 2.22, 1.82, 1.65, 1.54 after three ratio
    # corrections); from the second correction on it takes the secant through the last two tilings, and two
    # more tries (1.47, 1.54, 1.65, 1.55: at f_x 1.6 a tiling relaxes to within about 4 % of the line)
    secant = s.edge == "continuous"
    tried: list[tuple[float, float]] = [(cell_fx, fx)]
    for k in range(corrections + (2 if secant else 0)):
        if abs(fx - target) <= s.fx_tolerance * target or fx <= 0 or cell_fx <= 0:
            break
        aim = target * cell_fx / fx
        if secant and len(tried) > 1 and tried[-1][1] != tried[-2][1]:
            (cell_a, knit_a), (cell_b, knit_b) = tried[-2:]
            aim = cell_b + (target - knit_b) * (cell_b - cell_a) / (knit_b - knit_a)
            if aim <= 0:
                aim = target * cell_fx / fx
        with small_scene_threads():
            force_control(cell, aim, 0.25 * s.fx_tolerance, s.stretch_increment, MIN_BUILD_LX)
            cell_fx = settled_tension(cell)
        check_stitch_held(box, cell)
        box.tile(cell)
        fx = relax_to_steady_tension(box)
        tried.append((cell_fx, fx))
        report(min(1.0, 0.2 + 0.8 * (k + 1) / corrections))
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


@renamed_arguments({"ly_over_l0": "ly", "nodes_per_stitch": "resolution", "sagitta_radius_d": "sagitta_radius"},
                   since="0.14.0")
@functools.lru_cache(maxsize=16)
def unloaded_width(ly: float, resolution: int, material: Material, sagitta_radius: float = 0.0,
                   contact_law: str = "linear") -> float:
    """l_x/l0 of the periodised stitch on the f_x = 0 curve at this l_y (cached: a sweep asks it often)."""
    return zero_tension_lx(ly, material=material, resolution=resolution,
                           sagitta_radius=sagitta_radius, contact_law=contact_law)


def remember_unloaded_shape(cell: StitchRun, s: StretchSettings) -> None:
    """The stitch is taken to the f_x = 0 curve (the unloaded fabric), relaxed, and remembers that shape
    with mean (kappa_bar/kappa0)^2 = K (:mod:`knitlad.fabric.shape_memory`; K the band's if the knit has a
    memory band, :attr:`StretchSettings.cell_memory`); relaxed again, twist on."""
    stretch_to(cell, unloaded_width(s.ly, s.resolution, s.material, s.sagitta_radius, s.contact_law),
               s.ly, s.stretch_increment, min_increments=0)
    cell.settle()
    try:
        cell.remember_shape(s.cell_memory, s.memory_peak_ratio)
    except ValueError as e:  # a peak the stitch's hinges cannot give: the settings ask the impossible
        raise InfeasibleRun(f"memory_peak_ratio: {e}") from None
    cell.settle()


def settled_tension(cell: StitchRun) -> float:
    """Relax the stitch to its final tolerance; its f_x."""
    cell.settle()
    return cell.tension()
