"""The laddering experiment (paper, "Simulations" and appendix): stretch, relax, cut, propagate.

Stages, each driven here and measured by :mod:`knitlad.measure`:

1. **stretch** at mu = 0 to the target: the knit is built at the target l_y and
   at l_x = min(target, 0.30 l0) (narrower for l_y > 0.25 l0: :func:`build_width`).
   It is not built at the paper's 0.245 l0 because there the fabric is in compression (f_x < 0) and buckles out of plane,
   and the buckled structure survives the stretch (measured: the knit tangles).
   From there the whole fabric is stretched affinely in small increments, each
   followed by FIRE relaxation with the held ends and edge courses fixed. With
   mu = 0 the state is history-free, and an affine increment leaves the yarn in
   the bulk only a local rearrangement to make (yarn drawn from its own loop)
   instead of sliding from the held ends across the fabric. Force control
   (target f_x^ini) continues stretching until f_x passes the target, then
   brackets it by secant steps to within ``fx_tolerance``.
2. **relax** to f_x steady, then measure f_x^ini, l_x, l_y.
3. **friction on** (mu), **cut** the sinker loop (the loop pointing -y) of the
   central course at the central column.
4. **propagate**: free dynamics; every ``observe_every_s`` the laddered cells,
   the ladder front and f_x are recorded. Stop when no cell has changed for
   ``arrest_s``, when the ladder reaches an edge course, or at ``max_time_s``.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from knitlad import units
from knitlad.contact import COUNTING, ContactModel, contact_time_step
from knitlad.measure import (
    cell_overlap,
    course_rows,
    ladder_front,
    laddered_cells,
    laddering_column,
    laddering_velocity,
    periodicities,
    tension_per_thread,
)
from knitlad.scenes.jersey import EDGES, Jersey, KnitScene, build_jersey, widest_fitting_width
from knitlad.simulation import Simulation
from knitlad.state import cut_edge, with_twist
from knitlad.timestep import DEFAULT_SAFETY, critical_time_steps
from knitlad.units import NYLON, Material

MAX_OVERLAP_OVER_D = 0.5  # deeper than this, a yarn may pass through another: the run stops with an error
# The dashpots of the mu = 0 stretch. FIRE ends at a minimum whatever they are, but they shape
# its path and so pick which relaxed state of nearly the same f_x it ends in (16 x 16, target
# 13.6: contact dashpots at 0.1 and 0.6 instead of 0.3 ended at f_x^ini 13.65 and 13.56 instead
# of 13.51); the settings for the dynamics after the cut must not move the stretched knit.
STRETCH_CONTACT_DAMPING = 0.3
STRETCH_AXIAL_DAMPING = 0.2
MIN_BUILD_LX = 0.15  # narrowest l_x/l0 tried when a thick yarn does not fit at build_width
BUILD_LX = 0.30  # widest l_x/l0 at which the built knit is in tension and its loops still overlap well


def build_width(ly_over_l0: float, material: Material, nodes_per_stitch: int = 36) -> float:
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
    from knitlad.stitch_model import zero_tension_lx

    try:
        return min(BUILD_LX, zero_tension_lx(ly_over_l0, material=material, nodes_per_stitch=nodes_per_stitch) - 0.01)
    except ValueError:
        return BUILD_LX


@dataclass
class LadderSettings:
    """Inputs of one laddering run. Lengths as l/l0, tension as f_x, SI otherwise."""

    n_x: int = 42
    n_y: int = 42
    lx_over_l0: float | None = None  # position control ...
    fx_target: float | None = 13.6  # ... or force control (exactly one of the two)
    ly_over_l0: float = 0.25
    mu: float = 0.4
    nodes_per_stitch: int = 24
    contact_force_f0: float = 20.0  # the contact force (in f0) at which the overlap is overlap_fraction d
    overlap_fraction: float = 0.05
    # ContactModel.counting of the dynamics after the cut (the stretch, a minimisation, counts "union"):
    # "union" or "all_pairs", which conserves energy (docs/accuracy.md, "Contact counting")
    contact_counting: str = "union"
    edge: str = "clamped"  # how the course ends are held (knitlad.scenes.jersey.EDGES)
    # dashpots of the dynamics after the cut, fractions of critical (the stretch uses STRETCH_*)
    contact_damping_ratio: float = STRETCH_CONTACT_DAMPING  # normal and tangential contact dashpots
    stretch_damping_ratio: float = STRETCH_AXIAL_DAMPING  # the yarn's axial dashpot
    stretch_increment: float = 0.005  # l/l0 per affine step
    steps_per_increment: int = 750
    fx_tolerance: float = 0.02
    observe_every_s: float = 20e-6
    arrest_s: float = 2e-3
    max_time_s: float = 30e-3
    frame_every_s: float = 100e-6
    # time step of the laddering dynamics, as a fraction of the stability limit; 0.35, not the
    # 0.7 of a smooth problem: from the same stretched 16 x 16 knit at f_x^ini = 3.92, v_lad was
    # 0.312 at 0.7, 0.270 at 0.35 and 0.266 at 0.175 (at 13.5 the step moved it by 0.3 %;
    # docs/accuracy.md). Likely cause, not yet shown: the dashpots and the friction history use
    # the half-step velocity, first order in dt. The mu = 0 stretch is a FIRE minimisation and
    # keeps 0.7: a stretch at another step ends in another relaxed state of nearly the same
    # f_x^ini, whose ladder differs by the knit's run-to-run scatter (v_lad 0.27 against 0.49 at 3.9).
    dt_safety: float = 0.5 * DEFAULT_SAFETY
    # a global viscous drag on every node during the laddering dynamics [1/s]; 0 (no drag) is the
    # physics: air drag on this yarn is ~1e2 /s at 10 m/s. For comparison with engines that damp globally (the
    # authors' public engine does): on 16 x 16, 3e3 /s slows the ladder and 3e4 /s stops it.
    drag_per_s: float = 0.0
    # the yarns carry twist during the laddering, so friction, acting on their surfaces, also
    # turns them about their axes (the friction couple; knitlad.state.with_twist). The stretch
    # at mu = 0 stays twist-free: there twist decouples from the centreline.
    twist: bool = False
    material: Material = NYLON

    def __post_init__(self) -> None:
        if (self.lx_over_l0 is None) == (self.fx_target is None):
            raise ValueError("give exactly one of lx_over_l0 (position control) and fx_target (force control)")
        for name in ("contact_damping_ratio", "stretch_damping_ratio", "drag_per_s"):
            value = getattr(self, name)
            if not (value >= 0 and math.isfinite(value)):  # checked here, not after a long stretch
                raise ValueError(f"{name} must be >= 0, got {value!r}")
        if self.edge not in EDGES:
            raise ValueError(f"edge must be one of {', '.join(EDGES)}, got {self.edge!r}")
        if self.contact_counting not in COUNTING:
            raise ValueError(f"contact_counting must be one of {', '.join(COUNTING)}, got {self.contact_counting!r}")


@dataclass
class LadderResult:
    settings: LadderSettings
    fx_ini: float = float("nan")
    fx_fin: float = float("nan")
    lx_over_l0: float = float("nan")
    ly_over_l0: float = float("nan")
    n_lad: int = 0
    n_lad_over_ny: float = float("nan")
    v_lad_over_cb: float = float("nan")
    laddering_column: int = -1  # the column beside the cut whose front is followed (measure.laddering_column)
    reached_edge: bool = False
    stop_reason: str = ""
    v_fit_stitches: tuple = (2, 10)
    wall_s: dict = field(default_factory=dict)
    times_s: list = field(default_factory=list)
    front_up: list = field(default_factory=list)
    front_down: list = field(default_factory=list)
    fx_series: list = field(default_factory=list)
    column_history: list = field(default_factory=list)  # laddered flags of the laddering column over time
    frames: list = field(default_factory=list)
    frame_times_s: list = field(default_factory=list)
    final_laddered: np.ndarray | None = None
    baseline_laddered: np.ndarray | None = None
    nodes: int = 0
    steps: int = 0
    relax_steps: int = 0  # FIRE steps of the stretch and relaxation
    fx_within_tolerance: bool = True  # force control: f_x^ini within fx_tolerance of the target
    box_lx_over_l0: float = float("nan")  # the affine stretch of the held ends and edge courses
    peak_overlap_over_d: float = 0.0  # deepest yarn-yarn overlap at any step (stretch, relaxation, laddering), in d

    def summary(self) -> dict:
        return {
            "fx_ini": self.fx_ini,
            "fx_fin": self.fx_fin,
            "n_lad": self.n_lad,
            "n_lad_over_ny": self.n_lad_over_ny,
            "v_lad_over_cb": self.v_lad_over_cb,
            "lx_over_l0": self.lx_over_l0,
            "ly_over_l0": self.ly_over_l0,
            "laddering_column": self.laddering_column,
            "v_fit_stitches": list(self.v_fit_stitches),
            "reached_edge": self.reached_edge,
            "stop_reason": self.stop_reason,
            "nodes": self.nodes,
            "steps": self.steps,
            "relax_steps": self.relax_steps,
            "fx_within_tolerance": self.fx_within_tolerance,
            "box_lx_over_l0": self.box_lx_over_l0,
            "peak_overlap_over_d": self.peak_overlap_over_d,
            "wall_s": float(sum(self.wall_s.values())),
            **{f"wall_{k}_s": v for k, v in self.wall_s.items()},
        }


Progress = Callable[[str, float], None]  # (stage, fraction done)


class Interpenetration(RuntimeError):
    """Two yarns overlap by more than MAX_OVERLAP_OVER_D: the contact is too soft for the forces it carries."""


# settings read only from the cut on: one stretched knit can be laddered under each of them
AFTER_CUT = ("mu", "contact_damping_ratio", "stretch_damping_ratio", "contact_counting", "drag_per_s", "twist",
             "dt_safety", "observe_every_s", "arrest_s", "max_time_s", "frame_every_s")


class LadderRun:
    """Drives one laddering experiment; see the module docstring for the stages."""

    def __init__(self, settings: LadderSettings, progress: Progress | None = None) -> None:
        self.s = settings
        self.progress = progress or (lambda stage, frac: None)
        m = settings.material
        self.build_lx = build_width(settings.ly_over_l0, m, settings.nodes_per_stitch)
        self.lx = min(settings.lx_over_l0, self.build_lx) if settings.lx_over_l0 is not None else self.build_lx
        self.ly = settings.ly_over_l0  # current box stretch, l/l0
        self.knit: KnitScene = self._build_knit()
        self.contact = ContactModel.for_force(
            settings.contact_force_f0 * m.f0, m.diameter, overlap_fraction=settings.overlap_fraction, friction=0.0,
            damping_ratio=STRETCH_CONTACT_DAMPING, tangential_damping_ratio=STRETCH_CONTACT_DAMPING,
        )
        self.sim = Simulation(self.knit.state, contact=self.contact)
        self.result = LadderResult(settings, nodes=self.knit.state.x.shape[0])

    def _build_knit(self) -> KnitScene:
        """The jersey at (self.lx, self.ly); thick yarns (d/l0 = 1/20) only fit narrower."""
        s, m = self.s, self.s.material
        lx = widest_fitting_width(self.lx, self.ly, m, s.nodes_per_stitch, lx_min=MIN_BUILD_LX)
        if lx < self.lx:
            self.lx = self.build_lx = lx
        return build_jersey(Jersey(
            n_x=s.n_x, n_y=s.n_y, l_x=self.lx * m.stitch_length, l_y=self.ly * m.stitch_length,
            nodes_per_stitch=s.nodes_per_stitch, material=m, edge=s.edge,
        ), stretch_damping_ratio=STRETCH_AXIAL_DAMPING)

    # ------------------------------------------------------------ measurements
    def tension(self) -> float:
        k = self.knit
        return tension_per_thread(self.sim.reaction_forces_N(), k.left_end, k.right_end, self.s.material.f0)

    def rows(self) -> list[np.ndarray]:
        k = self.knit
        return course_rows(self.sim.state.x, self.sim.state.yarn_start, k.courses + [k.bars[1]])

    def column_centres(self) -> np.ndarray:
        """Head x of each column [internal]: the built columns, carried by the affine stretch."""
        g = self.knit.geometry
        scale = self.lx * self.s.material.stitch_length / g.l_x
        return g.column_x(np.arange(g.n_x)) * scale / units.LENGTH

    def laddered(self) -> np.ndarray:
        l0 = self.s.material.stitch_length / units.LENGTH
        overlap = cell_overlap(self.rows(), self.column_centres(), self.lx * l0)
        return laddered_cells(overlap, self.ly * l0)

    # ------------------------------------------------------------ stage 1-2
    def _affine(self, lx_new: float, ly_new: float) -> None:
        x = self.sim.state.x
        x[:, 0] *= lx_new / self.lx
        x[:, 1] *= ly_new / self.ly
        self.lx, self.ly = lx_new, ly_new

    def _relax(self, steps: int) -> dict:
        """One FIRE round of at most ``steps`` to the protocol's tolerance (1e-3 f0); its report."""
        info = self.sim.relax(force_tol_N=1e-3 * self.s.material.f0, max_steps=steps)
        self.result.relax_steps += info["steps"]
        return info

    def _relax_to_steady_tension(self, rtol: float = 0.005, max_rounds: int = 60) -> float:
        """Relax in rounds until f_x is within ``rtol`` of its extrapolated asymptote.

        After a stretch f_x creeps toward equilibrium with a time constant of a few
        rounds (42 x 42 with tail ends: from 2.1 to 5.0 over 14 rounds at l_x = 0.38 l0;
        clamped ends: 2.36 to 2.28 over 30 rounds at 0.355), so a small change between
        two rounds does not mean convergence. The asymptote is
        estimated by Aitken's delta-squared extrapolation of the last three readings.
        """
        readings = [self.tension()]
        for _ in range(max_rounds):
            self._relax(self.s.steps_per_increment)
            readings.append(self.tension())
            if len(readings) >= 3:
                older, old, new = readings[-3:]
                curvature = new - 2 * old + older
                limit = new - (new - old) ** 2 / curvature if abs(curvature) > 1e-12 else new
                if abs(new - limit) <= rtol * max(abs(limit), 0.1) and abs(new - old) <= 4 * rtol * max(abs(new), 0.1):
                    return new
        return readings[-1]

    def stretch_to(self, lx: float, ly: float, report: bool = False) -> None:
        """Affine increments to (lx, ly) [l/l0], relaxing after each; ``report``: drive the progress bar."""
        span = max(abs(lx - self.lx), abs(ly - self.ly))
        n = max(1, int(math.ceil(span / self.s.stretch_increment - 1e-9)))  # 1e-9: no extra step from round-off
        lx0, ly0 = self.lx, self.ly
        for k in range(1, n + 1):
            self._affine(lx0 + (lx - lx0) * k / n, ly0 + (ly - ly0) * k / n)
            self._relax(self.s.steps_per_increment)
            if report:
                self.progress("stretch", k / n)

    def _force_control(self) -> float:
        """Stretch until the relaxed f_x matches the target within ``fx_tolerance``; returns f_x.

        A reading taken right after an increment lags the relaxed tension (42 x 42 with
        tail ends at l_x = 0.38 l0: 1.9 read, 5.0 relaxed), so only steady (extrapolated) readings
        decide near the target: cheap increments while the reading is below a quarter
        of the target, then a steady reading after every increment until the target is
        bracketed, then bisection on steady readings.
        """
        s = self.s
        target, tol = s.fx_target, s.fx_tolerance
        self._relax(s.steps_per_increment)
        fx = self.tension()
        while fx < 0.25 * target:
            self._step_out()
            fx = self.tension()
            self.progress("stretch", 0.5 * max(fx, 0.0) / target)
        a, fa = self.lx, self._relax_to_steady_tension()
        if fa > (1 + tol) * target:
            # the cheap phase overshot: bracket from below by stepping back (not below the build width)
            b, fb = a, fa
            a = max(self.build_lx, self.lx - 4 * s.stretch_increment)
            if a < self.lx - 1e-9:
                self.stretch_to(a, s.ly_over_l0)
                fa = self._relax_to_steady_tension()
            if fa > (1 + tol) * target:
                raise RuntimeError(
                    f"at l_x/l0 = {a:.3f} the relaxed knit already carries f_x = {fa:.2f} > {target}: "
                    "use position control (--lx) for this tension"
                )
        else:
            b, fb = a, fa
            while fb < (1 - tol) * target:
                a, fa = b, fb
                self._step_out()
                b, fb = self.lx, self._relax_to_steady_tension()
                self.progress("stretch", 0.5 + 0.5 * min(max(fb, 0.0) / target, 1.0))
        fx, lx = (fb, b) if abs(fb - target) <= abs(fa - target) else (fa, a)
        for _ in range(10):
            if abs(fx - target) <= tol * target:
                break
            # interpolate in the bracket (the curve is steep and smooth), bisect if it leaves it
            guess = a + (target - fa) * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
            if not min(a, b) < guess < max(a, b):
                guess = 0.5 * (a + b)
            self.stretch_to(guess, s.ly_over_l0)
            fx, lx = self._relax_to_steady_tension(), guess
            if fx < target:
                a, fa = guess, fx
            else:
                b, fb = guess, fx
        if abs(self.lx - lx) > 1e-12:
            self.stretch_to(lx, s.ly_over_l0)
            fx = self._relax_to_steady_tension()
        self.result.fx_within_tolerance = bool(abs(fx - target) <= tol * target)
        self.progress("stretch", 1.0)
        return fx

    def _step_out(self) -> None:
        if self.lx + self.s.stretch_increment >= 0.95:
            raise RuntimeError(f"l_x/l0 reached {self.lx:.3f}: the target f_x = {self.s.fx_target} is out of reach")
        self.stretch_to(self.lx + self.s.stretch_increment, self.s.ly_over_l0)

    def stretch(self) -> None:
        s = self.s
        t0 = time.perf_counter()
        if s.lx_over_l0 is not None:
            self.stretch_to(s.lx_over_l0, s.ly_over_l0, report=True)
            fx = self._relax_to_steady_tension()
        else:
            fx = self._force_control()
        self.record_stretched(fx)
        self.result.wall_s["stretch"] = time.perf_counter() - t0

    def record_stretched(self, fx: float) -> None:
        """The stretched knit's f_x^ini, box and measured periodicities; stops on a deep overlap."""
        self._check_overlap("while stretching")
        self.result.fx_ini = fx
        self.result.box_lx_over_l0 = self.lx
        l0 = self.s.material.stitch_length / units.LENGTH
        lx_m, ly_m = periodicities(self.rows()[:-1], self.column_centres(), self.lx * l0)
        self.result.lx_over_l0 = lx_m / l0
        self.result.ly_over_l0 = ly_m / l0

    def branch(self, **after_cut) -> "LadderRun":
        """An independent copy of this stretched run that will ladder with other ``AFTER_CUT`` settings.

        Studies of the laddering dynamics (dashpots, drag, mu, time step) compare runs from
        one relaxed knit: re-stretching gives the same knit at several times the cost.
        """
        if self.result.times_s:
            raise RuntimeError("this run is already cut: branch it after the stretch, before propagate()")
        unknown = sorted(set(after_cut) - set(AFTER_CUT))
        if unknown:
            raise ValueError(f"{', '.join(unknown)}: not a setting of the laddering dynamics ({', '.join(AFTER_CUT)})")
        settings = replace(self.s, **after_cut)  # validated before the copy is made
        new = copy.deepcopy(self)
        new.s = settings
        new.result.settings = settings
        return new

    # ------------------------------------------------------------ stage 3-4
    def cut_row(self) -> int:
        return self.s.n_y // 2

    def cut_column(self) -> int:
        return self.s.n_x // 2

    def cut(self) -> int:
        """Cut the sinker loop of the central course on the -x side of the central column; returns the edge."""
        k = self.knit
        r, i = self.cut_row(), self.cut_column()
        nodes = k.course_nodes(r)
        x = self.sim.state.x[nodes]
        l_x = self.lx * self.s.material.stitch_length / units.LENGTH
        target = self.column_centres()[i] - 0.5 * l_x
        near = np.flatnonzero(np.abs(x[:, 0] - target) < 0.25 * l_x)
        apex = nodes.start + near[np.argmin(x[near, 1])]
        edge = int(np.flatnonzero(self.sim.state.edge_a == apex)[0])
        state = cut_edge(self.sim.state, edge)
        # from here on, the dashpots of the dynamics
        state.stretch_damping[:] *= self.s.stretch_damping_ratio / STRETCH_AXIAL_DAMPING
        if self.s.twist:
            m = self.s.material
            state = with_twist(state, m.twisting_stiffness / m.bending_stiffness)
        self.contact = replace(self.contact, damping_ratio=self.s.contact_damping_ratio,
                               tangential_damping_ratio=self.s.contact_damping_ratio, counting=self.s.contact_counting)
        # the cut frees two end nodes: keep the smaller of the old and the new stable step
        limit = critical_time_steps(state, self.s.twist, contact_time_step(state, self.contact, spin=self.s.twist))
        limit = limit.combined * units.TIME
        sim = Simulation(state, contact=self.contact, dt_s=min(self.sim.dt_s, self.s.dt_safety * limit),
                         drag_per_s=self.s.drag_per_s)
        sim.set_friction(self.s.mu)
        self.sim = sim
        return edge

    def propagate(self) -> None:
        s = self.s
        t0 = time.perf_counter()
        self.sim.set_friction(s.mu)
        baseline = self.laddered()  # cells already flagged before the cut are not damage
        self.cut()
        res = self.result
        res.baseline_laddered = baseline
        undone = np.zeros_like(baseline)
        r0, i0 = self.cut_row(), self.cut_column()
        columns = [i0 - 1, i0]  # the two columns beside the cut sinker loop
        fronts: list[list[tuple[int, int]]] = [[] for _ in columns]  # (up, down) extents over time
        cells: list[list[np.ndarray]] = [[] for _ in columns]
        last_change = 0.0
        n_last = -1
        next_frame = 0.0
        t_start = self.sim.time_s
        while True:
            self.sim.run(s.observe_every_s)
            t = self.sim.time_s - t_start
            self._check_overlap(f"at t = {t * 1e3:.3f} ms after the cut")
            # an undone cell does not knit itself again: keep every cell ever undone
            undone |= self.laddered() & ~baseline
            lad = undone
            for c, col in enumerate(columns):
                fronts[c].append(ladder_front(lad, col, r0))
                cells[c].append(lad[:, col].copy())
            res.times_s.append(t)
            res.fx_series.append(self.tension())
            n = int(lad.sum())
            if n != n_last:
                n_last, last_change = n, t
            if t >= next_frame:
                res.frames.append(self.sim.positions_m().astype(np.float32))
                res.frame_times_s.append(t)
                next_frame += s.frame_every_s
            top = lad[-1].any()
            bottom = lad[0].any()
            self.progress("propagate", min(t / s.max_time_s, 1.0))
            if top or bottom:
                res.reached_edge = True
                res.stop_reason = "ladder reached an edge course"
                break
            if t - last_change >= s.arrest_s:
                res.stop_reason = f"no cell changed for {s.arrest_s * 1e3:.1f} ms"
                break
            if t >= s.max_time_s:
                res.stop_reason = "max_time_s reached"
                break
        res.final_laddered = lad
        # one column for the whole run, as the paper follows one; chosen at each observation
        # instead, the front jumped between the two columns
        best = laddering_column([f[-1] for f in fronts])
        res.front_up = [up for up, _ in fronts[best]]
        res.front_down = [down for _, down in fronts[best]]
        res.column_history = cells[best]
        res.n_lad = int(lad.sum())
        res.n_lad_over_ny = res.n_lad / s.n_y
        res.laddering_column = columns[best]
        # f_x after arrest: mean over the last arrest window (the force rings after the cut)
        times = np.array(res.times_s)
        window = times >= times[-1] - 0.5 * s.arrest_s
        res.fx_fin = float(np.mean(np.array(res.fx_series)[window]))
        l_y = self.ly * s.material.stitch_length
        # the paper fits stitches 2 to 10; a small knit offers fewer rows above the cut
        last = min(10, s.n_y - 1 - r0)
        first = min(2, max(last - 2, 1))
        res.v_fit_stitches = (first, last)
        res.v_lad_over_cb = laddering_velocity(times, np.array(res.front_up), l_y, first, last) / s.material.c_b
        res.steps = self.sim.steps
        res.wall_s["propagate"] = time.perf_counter() - t0

    def _check_overlap(self, when: str) -> None:
        """Stop with :class:`Interpenetration` if two yarns overlapped deeper than MAX_OVERLAP_OVER_D since the last check."""
        d = self.s.material.diameter
        peak = self.sim.peak_overlap_m(reset=True) / d
        self.result.peak_overlap_over_d = max(self.result.peak_overlap_over_d, peak)
        if peak > MAX_OVERLAP_OVER_D:
            raise Interpenetration(
                f"yarns overlap by {peak:.2f} d {when} (limit {MAX_OVERLAP_OVER_D} d): "
                f"the contact is too soft for this tension; raise contact_force_f0 (now {self.s.contact_force_f0:g})"
            )

    def run(self) -> LadderResult:
        self.stretch()
        self.propagate()
        return self.result


def run_ladder(settings: LadderSettings, progress: Progress | None = None) -> LadderResult:
    return LadderRun(settings, progress).run()
