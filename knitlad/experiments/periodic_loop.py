"""The single loop in rows periodic along the course (paper, Fig. 5b,c; Crassous 2024's periodised stitch).

The loop's row and its neighbours are endless courses (:mod:`knitlad.fabric.scenes.rows`),
copies of the relaxed periodised stitch at the tension f_x, so that nothing recoils
but the stitch itself (the model of :mod:`knitlad.experiments.loop_model` ends its rows in tails,
whose recoil adds a v_0 to v_lad). Rows, bottom to top: the *lower* row 0, the *loop*
row 1, the *upper* row 2, more free rows, and a top row held in y and z (railed along x).
Two geometries:

* ``columns = 1`` (one stitch per period): the period L is a degree of freedom under
  the imposed tension (:class:`TensionBox`), set by force control before t_0 (every row
  carries f_x f0) and followed in time after it (the rows present carry f_x f0 each).
  The lower row, railed along x, is removed at t_0 (held far below, out of the energy).
* ``columns > 1`` (a strip of that many columns): the period is held (the fabric's
  far field; ``force_controlled`` makes it follow the tension instead) and the lower
  row, held whole, loses only its loop in the middle column at t_0, which becomes a
  straight bar between its sinkers (the laddered state); the loop row's other stitches
  are the reservoir its loop draws yarn from.

``sinkers_held``: the loop row's sinker nodes slide along x only (the fabric's
neighbouring columns keep a course's height). tau = t_cl - t_0, t_cl the last contact
between the loop (its middle column) and the upper row before they stay apart for
``confirm_s``; v_lad = l_y / tau (the paper's definition).

What each geometry did: docs/single_loop.md ("Periodic geometries").
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import KNIT_CONTACT_FORCE_F0, KNIT_OVERLAP, ContactModel
from knitlad.experiments.loop_model import LoopReading, LoopResult, check_tension_and_friction
from knitlad.fabric.observers import LetGo, TimeLimit
from knitlad.engine.deprecation import renamed_fields
from knitlad.engine.runloop import Observer, run_until
from knitlad.fabric.scenes.rows import PeriodicRows, build_periodic_rows
from knitlad.engine.simulation import Simulation, small_scene_threads
from knitlad.fabric.stitch_model import StitchRun, StitchSettings, cell_energy
from knitlad.fabric.stretching import force_control
from knitlad.engine.timestep import DEFAULT_SAFETY
from knitlad.engine.units import NYLON, Material

LOWER, LOOP, UPPER = 0, 1, 2
MIN_LX = 0.15  # narrowest l_x/l0 force control steps back to


@renamed_fields({"ly_over_l0": "ly", "nodes_per_stitch": "resolution"}, since="0.14.0")
@dataclass
class PeriodicLoopSettings:
    """Inputs of one run of the periodised single loop; tension as f_x, lengths as l/l0, SI otherwise. Built by
    :meth:`knitlad.experiments.config.LoopConfig.settings`, where the first five have their defaults and units;
    the rest are the model's own choices."""

    fx: float
    mu: float
    ly: float  # l_y/l0
    resolution: int
    max_time_s: float
    columns: int = 1  # stitches per period: 1, one stitch; more, a strip with one loop removed
    force_controlled: bool | None = None  # the period follows the tension (default: with one column only)
    rows: int = 5  # lower, loop, upper, free rows, railed top row
    sinkers_held: bool = False
    confirm_s: float = 20e-6  # apart this long: released
    observe_every_s: float = 0.5e-6
    box_response_s: float = 0.3e-6  # the box's relaxation time under its stiffest (affine) response
    contact_force_f0: float = KNIT_CONTACT_FORCE_F0
    overlap_fraction: float = KNIT_OVERLAP
    dt_safety: float = DEFAULT_SAFETY
    material: Material = NYLON

    def __post_init__(self) -> None:
        check_tension_and_friction(self.fx, self.mu)
        if self.rows < 4:
            raise ValueError(f"rows must be >= 4 (lower, loop, upper, top), got {self.rows}")
        if self.columns < 1:
            raise ValueError(f"columns must be >= 1, got {self.columns}")
        if self.force_controlled is None:
            self.force_controlled = self.columns == 1


@dataclass
class PeriodicLoopResult(LoopResult):
    lx_over_l0: float = math.nan  # column width at t_0
    lx_end_over_l0: float = math.nan  # at the end of the run
    fx_measured: float = math.nan  # tension per row at t_0 (the period's energy derivative)
    climb_over_ly: float = math.nan  # rise of the loop's centroid by the end, in l_y
    peak_overlap_over_d: float = math.nan  # deepest overlap of two yarns after t_0 (a yarn through another: ~1)
    geometry: dict = field(default_factory=dict)

    def summary(self) -> dict:
        return {**super().summary(), "lx_over_l0": self.lx_over_l0, "lx_end_over_l0": self.lx_end_over_l0,
                "fx_measured": self.fx_measured, "climb_over_ly": self.climb_over_ly,
                "peak_overlap_over_d": self.peak_overlap_over_d, **self.geometry}


class TensionBox:
    """The period L as an overdamped degree of freedom under an imposed force F:
    gamma dL/dt = F - dE/dL, with dE/dL the energy derivative of the rows present under an
    affine stretch along x (the virial tension, :func:`knitlad.fabric.stitch_model.cell_energy`).

    gamma = k_aff * response, k_aff the affine stiffness dF/dL measured at the start: the
    stiffest response of the stack (the relaxed one is an order of magnitude softer), so
    that the explicit update is stable for steps below 2 * response. Also a
    :class:`knitlad.fabric.stretching.Box` (deform, relax, tension) for force control at rest.
    """

    def __init__(self, rows: PeriodicRows, sim: Simulation, material: Material, rows_carrying: int) -> None:
        self.rows, self.sim, self.m = rows, sim, material
        self.l0 = material.stitch_length / units.LENGTH
        self.f0 = material.f0 / units.FORCE
        self.rows_carrying = rows_carrying
        self.ly = rows.ly / self.l0
        self.gamma = math.nan

    @property
    def lx(self) -> float:
        return self.rows.lx / self.l0

    def _derivative(self, read, rel_step: float) -> float:
        """d(read)/dL by central differences under an affine stretch of the period, the state restored."""
        rows, sim = self.rows, self.sim
        lx, x_saved, model = rows.lx, sim.state.x.copy(), sim.model
        values = []
        for sign in (1, -1):
            rows.set_period(sim, lx * (1 + sign * rel_step))
            values.append(read())
            sim.state.x[:] = x_saved
            sim.replace_model(edge_shift=model.edge_shift, image_shift=model.image_shift)
            rows.lx = lx
        return (values[0] - values[1]) / (2 * rel_step * rows.period)

    def energy_derivative(self, rel_step: float = 1e-5) -> float:
        """dE/dL [internal force] under an affine stretch of the period, nodes otherwise fixed."""
        f = self._derivative(lambda: cell_energy(self.sim, self.rows), rel_step)
        self.sim.fresh_contacts()
        return f

    def tension(self) -> float:
        """Tension per row f_x = (dE/dL) / (rows carrying * f0)."""
        return self.energy_derivative() / (self.rows_carrying * self.f0)

    def deform(self, lx: float, ly: float) -> None:
        self.rows.set_period(self.sim, lx * self.l0)

    def relax(self) -> dict:
        return self.sim.relax(force_tol_N=1e-2 * self.m.f0, max_steps=20_000)

    def set_response(self, response_s: float, rel_step: float = 1e-3) -> None:
        """gamma from the affine stiffness at the current state."""
        stiffness = self._derivative(self.energy_derivative, rel_step)
        self.gamma = max(stiffness, 1e-12) * response_s / units.TIME

    def follow(self, fx: float, elapsed: float) -> float:
        """One overdamped update over ``elapsed`` [internal time] toward f_x per row; returns the f_x read."""
        f = self.energy_derivative()
        force = self.rows_carrying * fx * self.f0
        dL = (force - f) / self.gamma * elapsed
        self.rows.set_period(self.sim, self.rows.lx + dL / self.rows.columns)
        return f / (self.rows_carrying * self.f0)


class PeriodicLoopRun:
    """Drives one run; see the module docstring."""

    def __init__(self, settings: PeriodicLoopSettings) -> None:
        self.s = s = settings
        m = s.material
        self.l0 = m.stitch_length / units.LENGTH
        self.cell = StitchRun(StitchSettings(0.30, s.ly, s.resolution, m,
                                             contact_force_f0=s.contact_force_f0, overlap_fraction=s.overlap_fraction))
        self.result = PeriodicLoopResult(settings, geometry={"columns": s.columns, "rows": s.rows,
                                                             "sinkers_held": s.sinkers_held,
                                                             "force_controlled": s.force_controlled})
        self.sim: Simulation | None = None
        self.rows: PeriodicRows | None = None
        self.box: TensionBox | None = None

    @property
    def middle(self) -> int:
        return self.s.columns // 2

    def build(self) -> None:
        """The stitch by force control at f_x, copied into the rows."""
        t0 = time.perf_counter()
        s, n = self.s, self.s.resolution
        self.cell.relax()
        force_control(self.cell, s.fx, 0.005, self.cell.s.stretch_increment, MIN_LX)
        self.cell.settle()
        rails = {s.rows - 1: None}
        if s.columns == 1:
            rails[LOWER] = None
        if s.sinkers_held:
            rails[LOOP] = (-1, 0, 1)
        self.rows = build_periodic_rows(self.cell.sim.state.x[:n].copy(), self.cell.lx * self.l0,
                                        self.cell.ly * self.l0, s.rows, s.columns, s.material, rails=rails,
                                        held=(LOWER,) if s.columns > 1 else (),
                                        rest_length=self.cell.sim.model.rest_length[self.cell.cell.real_edges])
        if s.columns > 1:
            self.rows.absent.add(LOWER)  # a support: out of the energy
        contact = ContactModel.of_settings(s, mu=0.0)
        self.sim = Simulation(self.rows.rods, contact=contact, safety=s.dt_safety)
        self.box = TensionBox(self.rows, self.sim, s.material, s.rows if s.columns == 1 else s.rows - 1)
        self.result.nodes = int(self.sim.model.yarn_start[s.rows])
        self.result.wall_s["build"] = time.perf_counter() - t0

    def relax(self) -> None:
        """FIRE at mu = 0; force-controlled, the period brought to f_x per row."""
        t0 = time.perf_counter()
        tol = 1e-4 * self.s.material.f0
        info = self.sim.relax(force_tol_N=tol, max_steps=200_000)
        if self.s.force_controlled:
            force_control(self.box, self.s.fx, 0.01, self.cell.s.stretch_increment, MIN_LX)
            info = self.sim.relax(force_tol_N=tol, max_steps=200_000)
        self.result.relax_converged = info["converged"]
        self.sim.state.v[:] = 0.0
        self.result.fx_measured = self.box.tension()
        self.result.lx_over_l0 = self.box.lx
        self.result.wall_s["relax"] = time.perf_counter() - t0

    def remove_lower_loop(self) -> None:
        """One stitch per period: the lower row held far below and out of the energy. A strip: the lower
        row's loop in the middle column becomes a straight bar between its sinkers."""
        s, sim, rows = self.s, self.sim, self.rows
        nodes = rows.row_nodes(sim, LOWER)
        x = sim.state.x
        if s.columns == 1:
            x[nodes, 1] -= 10.0 * (x[:, 1].max() - x[:, 1].min())
            held = sim.model.held.copy()
            held[nodes] = True
            sim.replace_model(held=held)
            rows.absent.add(LOWER)
            self.box.rows_carrying = s.rows - 1
        else:
            n = s.resolution
            a = nodes.start + self.middle * n
            start, end = x[a].copy(), x[a + n].copy()
            along = np.arange(1, n)[:, None] / n
            x[a + 1:a + n] = start + along * (end - start)
        sim.state.v[nodes] = 0.0

    def _loop_edges(self) -> tuple[np.ndarray, np.ndarray, slice]:
        """Edge masks of the loop (its middle column, with its images) and of the upper row; the loop's nodes."""
        m, rows, n = self.sim.model, self.rows, self.s.resolution
        edge_yarn = m.edge_yarn
        first = m.yarn_start[edge_yarn]
        column = (m.edge_a - first) // n
        in_loop = np.isin(edge_yarn, rows.family(LOOP)) & (column == self.middle)
        in_upper = np.isin(edge_yarn, rows.family(UPPER))
        start = rows.row_nodes(self.sim, LOOP).start + self.middle * n
        return in_loop, in_upper, slice(start, start + n)

    def release(self, observers: Sequence[Observer] = ()) -> None:
        """Remove the loop below and follow the loop until it lets go; ``observers`` see (t, this run, a
        :class:`LoopReading`) at every reading."""
        t0 = time.perf_counter()
        s, sim, res = self.s, self.sim, self.result
        sim.set_friction(s.mu)
        in_loop, in_upper, loop_nodes = self._loop_edges()
        res.contacts_before = sim.touching_pairs_of_edges(in_loop, in_upper)
        if res.contacts_before == 0:
            raise RuntimeError("the loop does not touch the upper row after relaxation: nothing to release")
        centroid = float(sim.state.x[loop_nodes, 1].mean())
        self.remove_lower_loop()
        sim.peak_overlap_m(reset=True)
        followed = s.force_controlled
        if followed:
            self.box.set_response(s.box_response_s)
        n_obs = 1 if followed else max(1, int(round(s.observe_every_s / sim.dt_s)))
        seen = {"last_touch": 0.0}

        def observe(t: float) -> LoopReading:
            if followed:  # force control: the box follows the imposed tension at every step
                self.box.follow(s.fx, n_obs * sim.dt)
            touching = sim.touching_pairs_of_edges(in_loop, in_upper) > 0
            if touching:
                seen["last_touch"] = t
            return LoopReading(touching)

        let_go = LetGo(s.confirm_s, "apart from the upper row")
        _, rule, _ = run_until(sim, n_obs, observe, [let_go, TimeLimit(s.max_time_s)], observers, self)
        if rule is let_go:
            res.released = True
            res.tau_s = res.tau_contact_s = seen["last_touch"] + 0.5 * n_obs * sim.dt_s
            res.v_lad_over_cb = s.ly * s.material.stitch_length / res.tau_s / s.material.c_b
        res.climb_over_ly = (float(sim.state.x[loop_nodes, 1].mean()) - centroid) / self.rows.ly
        res.lx_end_over_l0 = self.rows.lx / self.l0
        res.peak_overlap_over_d = sim.peak_overlap_m() / s.material.diameter
        res.steps = sim.steps
        res.wall_s["release"] = time.perf_counter() - t0

    def run(self, observers: Sequence[Observer] = ()) -> PeriodicLoopResult:
        with small_scene_threads():
            self.build()
            self.relax()
            self.release(observers)
        return self.result


def run_single_loop(settings, observers: Sequence[Observer] = ()):
    """One single-loop run of either model: :class:`knitlad.experiments.loop_model.LoopSettings` (rows ending in tails)
    or :class:`PeriodicLoopSettings`; ``observers`` see (t, the run, a :class:`LoopReading`) at every reading."""
    from knitlad.experiments.loop_model import LoopRun

    return (PeriodicLoopRun if isinstance(settings, PeriodicLoopSettings) else LoopRun)(settings).run(observers)
