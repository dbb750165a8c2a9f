"""Protocol B (paper, Fig. 4a and the appendix "Stretching protocols"): the damage prediction's loading.

The knit, stretched at mu = 0 to a small holding tension (Delta x_min, f_x about 0.68), is loaded with
friction on: its held ends (the bars) move apart at a steady speed to Delta x_max, are held there until the
knit is static, and come back, ``cycles`` times. At Delta x_max of the last cycle a copy of the knit is cut
(friction history and all, :func:`cut_cycled`), while the uncut twin goes on unloading: where its tension
crosses the threshold f_x^thr lies the shortening delta l of Eq. 1,

    n_lad / n_y = delta l / (l0 - l_x),

each laddered column freeing l0 - l_x of yarn. Delta x is the distance between the knit's two held ends,
n_x l_x in a uniform knit, so a change of the box's l_x/l0 by dl is a Delta x change of n_x dl l0.

Quasi-static with friction. The bars move at ``bar_speed`` under a mass-proportional damping
(:meth:`knitlad.engine.simulation.Simulation.ramp_held`, ``knitlad/engine/quasistatic.py``); a hold settles to a stated
force residual. Readings while moving carry the damping's bias alpha M V and the knit's inertia; the
answer is rate-independent when halving the speed changes it less than its own error
(``tests/experiments/test_cycling.py``, docs/quasistatic.md). The experiments' "gentle stroking" at each hold has no
counterpart here: a hold is a settle with the friction history as the loading left it.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from knitlad.engine import units
from knitlad.experiments.laddering import (
    DynamicsSettings,
    LadderResult,
    Laddering,
    LadderSettings,
    analyse,
    cut,
    dynamics_rods,
    dynamics_simulation,
    propagate,
)
from knitlad.fabric.preparation import InfeasibleRun, StretchedKnit, stretch
from knitlad.engine.deprecation import renamed_fields
from knitlad.engine.simulation import Simulation

LOADING, HOLD, UNLOADING = 1, 0, -1  # the leg column of the readings


@renamed_fields({"bar_speed_m_s": "bar_speed", "damping_per_s": "cycle_damping_per_s"}, since="0.14.0")
@dataclass(frozen=True)
class CycleSettings:
    """Protocol B's loading (from :meth:`knitlad.experiments.config.CycleConfig.cycle_settings`). l/l0, f_x, SI."""

    lx_max: float  # the box's l_x/l0 at Delta x_max
    cycles: int  # loading cycles; the cut comes at Delta x_max of the last
    bar_speed: float  # m/s: each held end's speed away from (or towards) the knit's centre line
    cycle_damping_per_s: float  # alpha of the mass-proportional damping while the bars move and hold
    readings_per_leg: int
    hold_s: float  # the longest hold at Delta x_max (a settle)
    hold_tol_f0: float  # a hold has settled when no free node carries more than this (f0)
    fx_thr: float | None  # delta l is read where the uncut twin's unloading crosses this f_x
    cut: bool  # cut a copy at Delta x_max of the last cycle and follow its ladder

    def __post_init__(self) -> None:
        if self.cycles < 1 or self.readings_per_leg < 1:
            raise ValueError("cycles and readings_per_leg must be at least 1")
        if not (self.bar_speed > 0 and self.cycle_damping_per_s > 0 and self.hold_s > 0 and self.hold_tol_f0 > 0):
            raise ValueError("bar_speed, cycle_damping_per_s, hold_s and hold_tol_f0 must be positive")


class LoadedKnit:
    """A stretched knit under the laddering's dynamics (friction, dashpots, twist, step), its held ends and
    bars moved affinely (as the stretch moved them): along x for protocol B, along x and y for the tensile test."""

    def __init__(self, knit: StretchedKnit, s: CycleSettings, dynamics: DynamicsSettings) -> None:
        self.knit, self.s = knit, s
        rods = dynamics_rods(knit.knit.rods.copy(), dynamics, knit.settings.material)
        self.sim = dynamics_simulation(rods, knit, dynamics)
        self.held = np.flatnonzero(self.sim.model.held)
        self.clips = self.sim.model.rail_node  # carried with the box across their rails (sliding bars, clips)
        self.lx, self.ly = knit.box_lx, knit.box_ly
        held_y = self.sim.state.x[self.held, 1]
        self.y_centre = 0.5 * (held_y.min() + held_y.max())  # the box's centre line (x's is x = 0)
        self.readings: list[tuple[int, int, float, float, float]] = []  # cycle, leg, t [s], box l_x/l0, f_x

    def tension(self) -> float:
        return self.knit.gauge.tension(self.sim)

    def move_box(self, lx: float, ly: float, report: Callable[[float], None] | None = None,
                 read: Callable[[], None] | None = None) -> None:
        """Bring the box to (``lx``, ``ly``) (l/l0) in ``readings_per_leg`` ramps of the held nodes, affine about
        the box's centre, the clips carried with them across their rails (along them they slide), calling
        ``read`` after each."""
        s = self.s
        lx0, ly0 = self.lx, self.ly
        for k, f in enumerate(np.linspace(0.0, 1.0, s.readings_per_leg + 1)[1:], start=1):
            tx, ty = lx0 + (lx - lx0) * f, ly0 + (ly - ly0) * f
            by, clips_by = (self.affine_move(nodes, tx, ty) for nodes in (self.held, self.clips))
            self.sim.ramp_held(self.held, by_m=by, speed_m_s=s.bar_speed, damping_per_s=s.cycle_damping_per_s,
                               rails=self.clips, rails_by_m=clips_by)
            self.lx, self.ly = tx, ty
            if read:
                read()
            if report:
                report(k / s.readings_per_leg)

    def affine_move(self, nodes: np.ndarray, tx: float, ty: float) -> np.ndarray:
        """(len(nodes), 3) the move [m] of ``nodes`` from the box now to (``tx``, ``ty``) (l/l0), affine about
        its centre; a node outside the held ones in x (a turning loop's clip) moves as the box's side does."""
        x = self.sim.state.x
        side = np.abs(x[self.held, 0]).max()
        by = np.zeros((nodes.size, 3))
        by[:, 0] = np.clip(x[nodes, 0], -side, side) * (tx / self.lx - 1.0) * units.LENGTH
        by[:, 1] = (x[nodes, 1] - self.y_centre) * (ty / self.ly - 1.0) * units.LENGTH
        return by

    def move_bars(self, lx: float, cycle: int, report: Callable[[float], None] | None = None) -> None:
        """Bring the box to ``lx`` (l_x/l0) in ``readings_per_leg`` ramps, reading f_x after each."""
        leg = LOADING if lx > self.lx else UNLOADING
        self.move_box(lx, self.ly, report,
                      lambda: self.readings.append((cycle, leg, self.sim.time_s, self.lx, self.tension())))

    def hold(self, cycle: int) -> dict:
        """Keep the bars still until the knit is static (or ``hold_s`` has passed); read f_x."""
        s = self.s
        out = self.sim.settle(force_tol_N=s.hold_tol_f0 * self.knit.settings.material.f0, max_time_s=s.hold_s,
                              damping_per_s=s.cycle_damping_per_s)
        self.readings.append((cycle, HOLD, self.sim.time_s, self.lx, self.tension()))
        return out

    def snapshot(self) -> StretchedKnit:
        """The knit as it is now, as the value the laddering starts from (its friction history stays in
        :attr:`sim`: :func:`cut_cycled` carries it over)."""
        rods = self.sim.rods.copy()
        lx, ly = self.knit.gauge.periodicities(rods.state.x, self.lx)  # node indices are those of the knit
        return dataclasses.replace(self.knit, knit=dataclasses.replace(self.knit.knit, rods=rods), box_lx=self.lx,
                                   fx_ini=self.tension(), lx_over_l0=lx, ly_over_l0=ly, dt_s=self.sim.dt_s)


def cut_cycled(knit: StretchedKnit, loaded: Simulation, dynamics: DynamicsSettings) -> Laddering:
    """:func:`knitlad.experiments.laddering.cut` of a cycled knit, the contacts' friction history carried over from the
    simulation that loaded it (``loaded``): the cut edge's pairs go, every other pair keeps its slip."""
    run = cut(knit, dynamics, rods_ready=True)
    ne = loaded.model.edge_a.shape[0]
    edge_map = np.arange(ne) - (np.arange(ne) > run.cut_edge)
    edge_map[run.cut_edge] = -1
    run.sim.adopt_friction_history(loaded.contacts, edge_map)
    return run


@dataclass
class CycleResult:
    """Protocol B's curve and the damage it predicts (paper, Fig. 4a and Eq. 1)."""

    settings: CycleSettings
    n_x: int
    lx_min: float  # box l_x/l0 at Delta x_min
    readings: np.ndarray  # (k, 5): cycle, leg (1 loading, 0 hold, -1 unloading), t [s], box l_x/l0, f_x
    fx_ini: float = math.nan  # settled f_x at Delta x_max of the last cycle
    lx_over_l0: float = math.nan  # measured l_x/l0 there (before the cut)
    ly_over_l0: float = math.nan
    delta_l_over_l0: float = math.nan  # the shortening from Delta x_max to f_x^thr on the uncut twin's unloading
    # the paper's reading of Eq. 1: f_thr is the tension at the bars once the cut copy's ladder stopped (its f_x^fin)
    fx_thr_own: float = math.nan
    delta_l_own_over_l0: float = math.nan  # the same shortening, to fx_thr_own
    hold_converged: bool = False
    wall_s: float = 0.0

    @property
    def predicted_damage(self) -> float:
        """delta l / (l0 - l_x) (Eq. 1), l_x measured at Delta x_max."""
        return self.delta_l_over_l0 / (1.0 - self.lx_over_l0)

    @property
    def predicted_damage_own(self) -> float:
        """Eq. 1 as the paper reads it: delta l to the run's own post-arrest tension at the bars, over (l0 - l_x)."""
        return self.delta_l_own_over_l0 / (1.0 - self.lx_over_l0)

    def shortening_at(self, fx_thr: float) -> float:
        """delta l/l0 on the last unloading, from the hold at Delta x_max down to ``fx_thr`` (:func:`shortening_to`)."""
        r, last = self.readings, self.settings.cycles
        start = np.flatnonzero((r[:, 0] == last) & (r[:, 1] == HOLD))[0]
        return shortening_to(np.vstack([r[start, 3:5], self.leg(last, UNLOADING)]), fx_thr, self.n_x)

    def leg(self, cycle: int, leg: int) -> np.ndarray:
        """(k, 2) box l_x/l0 and f_x of one leg, in order."""
        r = self.readings
        return r[(r[:, 0] == cycle) & (r[:, 1] == leg)][:, 3:5]

    def nan_reasons(self) -> dict[str, str]:
        """Why delta l (and the damage Eq. 1 predicts from it) is NaN, when it is; the same for the reading at
        the run's own f_x^fin."""
        reasons = {}
        if math.isnan(self.delta_l_over_l0):
            why = "no f_x^thr was given (fx_thr)" if self.settings.fx_thr is None else self._unreached(self.settings.fx_thr)
            reasons.update({"delta_l_over_l0": why, "predicted_damage": why})
        if math.isnan(self.delta_l_own_over_l0):
            why = ("no cut copy stopped with a finite f_x^fin" if math.isnan(self.fx_thr_own)
                   else self._unreached(self.fx_thr_own))
            reasons.update({"delta_l_own_over_l0": why, "predicted_damage_own": why})
        return reasons

    def _unreached(self, thr: float) -> str:
        unloading = self.leg(self.settings.cycles, -1)
        if unloading.size and unloading[0, 1] <= thr:
            return f"f_x at Delta x_max, {unloading[0, 1]:.3f}, is already at or below f_x^thr = {thr:g}"
        low = f"{unloading[:, 1].min():.3f}" if unloading.size else "nothing (no unloading was read)"
        return f"the unloading never fell to f_x^thr = {thr:g} (its lowest f_x: {low})"

    def summary(self) -> dict:
        return {"fx_ini": self.fx_ini, "lx_over_l0": self.lx_over_l0, "ly_over_l0": self.ly_over_l0,
                "lx_max": self.settings.lx_max, "lx_min": self.lx_min, "fx_thr": self.settings.fx_thr,
                "delta_l_over_l0": self.delta_l_over_l0, "predicted_damage": self.predicted_damage,
                "fx_thr_own": self.fx_thr_own, "delta_l_own_over_l0": self.delta_l_own_over_l0,
                "predicted_damage_own": self.predicted_damage_own,
                "cycles": self.settings.cycles, "bar_speed_m_s": self.settings.bar_speed,
                "hold_converged": self.hold_converged, "wall_s": self.wall_s,
                "nan_reasons": "; ".join(f"{k}: {why}" for k, why in self.nan_reasons().items())}


def shortening_to(unloading: np.ndarray, fx_thr: float, n_x: int) -> float:
    """delta l / l0: the Delta x shortening from the first reading of ``unloading`` ((k, 2) box l_x/l0, f_x,
    from Delta x_max down) to where f_x first falls to ``fx_thr`` (linear between readings); NaN if never."""
    lx, fx = unloading[:, 0], unloading[:, 1]
    below = np.flatnonzero(fx <= fx_thr)
    if below.size == 0 or below[0] == 0:
        return math.nan
    k = below[0]
    at = lx[k - 1] + (fx_thr - fx[k - 1]) * (lx[k] - lx[k - 1]) / (fx[k] - fx[k - 1])
    return n_x * (lx[0] - at)


LOADED, UNLOADED = 1, 2  # a checkpoint's phase: after the hold at Delta x_max, after the return to Delta x_min


def check_cycle_checkpoint(arrays: dict[str, np.ndarray], cycles: int) -> None:
    """Refuse (ValueError, naming the array) a checkpoint of protocol B that a resume could not trust whole: the
    cycle's own arrays (the leg done, within the run's cycles; the readings, (k, 5) and finite; the box), the
    simulation's clock (finite, not negative) and its state (finite). Shapes against the simulation are checked
    by :meth:`~knitlad.engine.simulation.Simulation.restore`."""
    for name in ("cycle/done", "cycle/readings", "cycle/box_lx", "clock", "state/x", "state/v"):
        if name not in arrays:
            raise ValueError(f"it has no {name}")
    done = np.asarray(arrays["cycle/done"])
    if done.shape != (2,) or not (1 <= int(done[0]) <= cycles and int(done[1]) in (LOADED, UNLOADED)):
        raise ValueError(f"cycle/done is {done.tolist()}, not a leg of a run of {cycles} cycles")
    readings = np.asarray(arrays["cycle/readings"], dtype=float)
    if readings.ndim != 2 or readings.shape[1] != 5:
        raise ValueError(f"cycle/readings has shape {readings.shape}, not (k, 5)")
    for name in ("cycle/readings", "cycle/box_lx", "clock") + tuple(k for k in arrays if k.startswith("state/")):
        if not np.all(np.isfinite(np.asarray(arrays[name], dtype=float))):
            raise ValueError(f"{name} holds NaN or infinity")
    if np.any(np.asarray(arrays["clock"], dtype=float)[:3] < 0):
        raise ValueError("clock holds a negative time, step count or drag")


def cycle_checkpoint(loaded: LoadedKnit, cycle: int, phase: int, hold_converged: bool) -> dict[str, np.ndarray]:
    """Where protocol B stands after a leg: the simulation's :meth:`~knitlad.engine.simulation.Simulation.checkpoint`
    and the cycle's own ("cycle/*": the cycle and phase done, the readings, the box, whether the hold settled)."""
    return {**loaded.sim.checkpoint(), "cycle/done": np.array([cycle, phase]),
            "cycle/readings": np.array(loaded.readings, dtype=float).reshape(-1, 5),
            "cycle/box_lx": np.array([loaded.lx, float(hold_converged)])}


def run_cycles(knit: StretchedKnit, s: CycleSettings, dynamics: DynamicsSettings,
               progress: Callable[[str, float], None] | None = None,
               at_the_cut: Callable[[StretchedKnit, Simulation], None] | None = None,
               after_leg: Callable[[np.ndarray], None] | None = None,
               keep: Callable[[dict], None] | None = None, resume: dict | None = None) -> CycleResult:
    """Protocol B on ``knit`` (stretched at mu = 0 to Delta x_min) under ``dynamics`` (its friction on):
    ``cycles`` loadings to ``lx_max`` with a hold, back to the start; ``at_the_cut(snapshot, sim)`` is
    called at Delta x_max of the last cycle (to cut a copy: :func:`cut_cycled`); the last unloading is the
    uncut twin's, read for delta l. ``after_leg(readings)``: the readings so far after each leg and hold
    (to keep them as they come: a run of an hour stopped early keeps its curve). ``keep(checkpoint)``: a
    :func:`cycle_checkpoint` after each leg up to the last cut; ``resume``: one of them, to continue from
    (the same knit and settings; the run then goes on to the bit as it would have)."""
    if s.lx_max <= knit.box_lx:  # force control put Delta x_min beyond the asked Delta x_max: a negative stroke
        raise InfeasibleRun(f"lx_max: {s.lx_max:g} is not above the box's l_x/l0 at Delta x_min, {knit.box_lx:.4f} "
                            f"(where f_x = {knit.fx_ini:.3f}): the bars would move inwards; a larger lx_max or a "
                            "smaller fx")
    t0 = time.perf_counter()
    loaded, lx_min = LoadedKnit(knit, s, dynamics), knit.box_lx
    loaded.readings.append((0, HOLD, 0.0, lx_min, loaded.tension()))
    result = CycleResult(settings=s, n_x=knit.settings.n_x, lx_min=lx_min, readings=np.zeros((0, 5)))
    first, skip_loading = 1, False
    if resume is not None:
        loaded.sim.restore(resume)
        done_cycle, done_phase = (int(v) for v in resume["cycle/done"])
        loaded.readings = [tuple(r) for r in np.asarray(resume["cycle/readings"], dtype=float)]
        loaded.lx, result.hold_converged = float(resume["cycle/box_lx"][0]), bool(resume["cycle/box_lx"][1])
        first, skip_loading = (done_cycle, True) if done_phase == LOADED else (done_cycle + 1, False)
    legs = 2 * s.cycles
    for cycle in range(first, s.cycles + 1):
        def report(f, done=2 * (cycle - 1)):
            if progress:
                progress("cycle", (done + f) / legs)
        if not (skip_loading and cycle == first):
            loaded.move_bars(s.lx_max, cycle, report)
            result.hold_converged = bool(loaded.hold(cycle)["converged"])
            if after_leg:
                after_leg(np.array(loaded.readings, dtype=float))
            if keep:
                keep(cycle_checkpoint(loaded, cycle, LOADED, result.hold_converged))
        if cycle == s.cycles:
            snap = loaded.snapshot()
            result.fx_ini, result.lx_over_l0, result.ly_over_l0 = snap.fx_ini, snap.lx_over_l0, snap.ly_over_l0
            if at_the_cut:
                at_the_cut(snap, loaded.sim)
        loaded.move_bars(lx_min, cycle, lambda f, done=2 * cycle - 1: report(f, done))
        if after_leg:
            after_leg(np.array(loaded.readings, dtype=float))
        if keep and cycle < s.cycles:  # after the last cut, a resume starts from before it: the ladder is redone
            keep(cycle_checkpoint(loaded, cycle, UNLOADED, result.hold_converged))
    result.readings = np.array(loaded.readings, dtype=float)
    if s.fx_thr is not None:
        result.delta_l_over_l0 = result.shortening_at(s.fx_thr)
    result.wall_s = time.perf_counter() - t0
    return result


def run_protocol_b(ladder: LadderSettings, s: CycleSettings,
                   progress: Callable[[str, float], None] | None = None, knit: StretchedKnit | None = None,
                   after_leg: Callable[[np.ndarray], None] | None = None, keep: Callable[[dict], None] | None = None,
                   resume: dict | None = None) -> tuple[CycleResult, LadderResult | None]:
    """Stretch at mu = 0 to Delta x_min (``ladder.stretch``; or start from ``knit``, stretched so), cycle
    (:func:`run_cycles`, with its checkpoints ``keep`` and ``resume``), and at Delta x_max of the last cycle cut
    a copy and follow its ladder under ``ladder.dynamics`` (if ``s.cut``)."""
    if knit is None:
        knit = stretch(ladder.stretch, progress)
    laddered: list[LadderResult] = []

    def at_the_cut(snapshot: StretchedKnit, sim: Simulation) -> None:
        if s.cut:
            laddered.append(analyse(propagate(cut_cycled(snapshot, sim, ladder.dynamics), progress=progress)))

    result = run_cycles(knit, s, ladder.dynamics, progress, at_the_cut, after_leg, keep, resume)
    if laddered and math.isfinite(laddered[0].fx_fin):
        result.fx_thr_own = laddered[0].fx_fin
        result.delta_l_own_over_l0 = result.shortening_at(result.fx_thr_own)
    return result, (laddered[0] if laddered else None)
