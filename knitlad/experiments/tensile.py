"""The fabric's tensile test: a stretched knit pulled and let back along x, y or both, with friction.

    stretch(StretchSettings) -> StretchedKnit          at mu = 0 (knitlad.fabric.preparation)
    run_tensile(knit, TensileSettings, Dynamics) -> TensileResult

From the stretched knit, with the laddering's dynamics (friction mu, dashpots, step), the held course ends
and the held courses below and above (the bars) are moved affinely about the box's centre at a steady
speed (:class:`knitlad.experiments.cycling.LoadedKnit`, as protocol B moves them) to the box (l_x, l_y)_max,
held until static, and brought back to where they started. After each ramp the test reads the box, the
knit's own periodicities l_x, l_y (measured on its free courses), f_x = F_x/(n_y f0) per course and
f_y = F_y/(n_x f0) per column (:func:`knitlad.fabric.measure.transverse_tension`).

What it measures, beside the force-displacement curves: the loop's area, the work friction took per stitch
(the integral of f_x dl_x + f_y dl_y, in f0 l0), and the coupling of the two directions: along one
direction the other bar spacing stays fixed (the bars are held, not free to come together), so the
Poisson effect shows as the change of the transverse tension, d f_y / d f_x, and as the knit's own
l_y moving inside its fixed box.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from knitlad.engine.deprecation import renamed_fields
from knitlad.engine.units import Material
from knitlad.experiments.cycling import LoadedKnit
from knitlad.experiments.laddering import DynamicsSettings
from knitlad.fabric.preparation import InfeasibleRun, StretchedKnit

LOADING, HOLD, UNLOADING = 1, 0, -1  # the leg column of the readings
COLUMNS = ("leg", "t_s", "box_lx_over_l0", "box_ly_over_l0", "lx_over_l0", "ly_over_l0", "fx", "fy")


@renamed_fields({"bar_speed_m_s": "bar_speed", "damping_per_s": "cycle_damping_per_s"}, since="0.14.0")
@dataclass(frozen=True)
class TensileSettings:
    """The tensile test's path and pace (from :meth:`knitlad.experiments.config.TensileConfig.tensile_settings`)."""

    lx_max: float | None  # the box's l_x/l0 at the top (None: l_x stays)
    ly_max: float | None  # the box's l_y/l0 at the top (None: l_y stays)
    unload: bool  # come back to the start after the hold
    bar_speed: float  # m/s
    cycle_damping_per_s: float  # 1/s
    readings_per_leg: int
    hold_s: float
    hold_tol_f0: float

    def __post_init__(self) -> None:
        if self.lx_max is None and self.ly_max is None:
            raise ValueError("give lx_max, ly_max or both: the box must move")


@dataclass
class TensileResult:
    """The readings (k, 8) of :data:`COLUMNS`, and what they give."""

    settings: TensileSettings
    material: Material
    n_x: int
    n_y: int
    readings: np.ndarray
    hold_converged: bool = False
    wall_s: float = 0.0

    def column(self, name: str) -> np.ndarray:
        return self.readings[:, COLUMNS.index(name)]

    @property
    def dissipated_per_stitch(self) -> float:
        """The work friction took per stitch over the closed path, the integral of f_x dl_x + f_y dl_y [f0 l0]
        (trapezoids over the readings; NaN if the path is not closed)."""
        if not self.settings.unload:
            return math.nan
        lx, ly = self.column("box_lx_over_l0"), self.column("box_ly_over_l0")
        fx, fy = self.column("fx"), self.column("fy")
        return float(np.sum(0.5 * (fx[1:] + fx[:-1]) * np.diff(lx) + 0.5 * (fy[1:] + fy[:-1]) * np.diff(ly)))

    def summary(self) -> dict:
        r = self.readings
        top = np.flatnonzero(r[:, 0] == HOLD)[0]
        first = r[: top + 1]
        dfx, dfy = first[-1, 6] - first[0, 6], first[-1, 7] - first[0, 7]
        return {"fx_start": float(r[0, 6]), "fy_start": float(r[0, 7]), "fx_top": float(r[top, 6]),
                "fy_top": float(r[top, 7]), "lx_top_over_l0": float(r[top, 4]), "ly_top_over_l0": float(r[top, 5]),
                "fx_end": float(r[-1, 6]), "fy_end": float(r[-1, 7]),
                "coupling": float(dfy / dfx) if self.settings.ly_max is None and dfx else
                float(dfx / dfy) if self.settings.lx_max is None and dfy else math.nan,
                "dissipated_per_stitch": self.dissipated_per_stitch, "hold_converged": self.hold_converged,
                "wall_s": self.wall_s}


def read(loaded: LoadedKnit, leg: int) -> tuple:
    """One row of :data:`COLUMNS` from the knit as it is now."""
    lx, ly = loaded.knit.gauge.periodicities(loaded.sim.state.x, loaded.lx)
    return (leg, loaded.sim.time_s, loaded.lx, loaded.ly, lx, ly, loaded.tension(),
            loaded.knit.gauge.tension_y(loaded.sim))


def run_tensile(knit: StretchedKnit, s: TensileSettings, dynamics: DynamicsSettings,
                progress: Callable[[str, float], None] | None = None) -> TensileResult:
    """Pull the stretched ``knit`` to the top of ``s``'s path under ``dynamics``, hold it until static (or
    ``hold_s``), and bring it back if ``s.unload``; read after every ramp."""
    t0 = time.perf_counter()
    if s.lx_max is not None and s.lx_max <= knit.box_lx:  # force control put the start beyond the top
        raise InfeasibleRun(f"lx_max: {s.lx_max:g} is not above the box's l_x/l0 at the start, {knit.box_lx:.4f} "
                            f"(where f_x = {knit.fx_ini:.3f}): the bars would move inwards; a larger lx_max or a "
                            "lower fx")
    loaded = LoadedKnit(knit, s, dynamics)
    rows = [read(loaded, LOADING)]
    start = (loaded.lx, loaded.ly)
    top = (s.lx_max if s.lx_max is not None else loaded.lx, s.ly_max if s.ly_max is not None else loaded.ly)
    legs = 2 if s.unload else 1

    def report(done: int) -> Callable[[float], None]:
        return lambda f: progress("tensile", (done + f) / legs) if progress else None

    loaded.move_box(*top, report(0), lambda: rows.append(read(loaded, LOADING)))
    held = loaded.sim.settle(force_tol_N=s.hold_tol_f0 * knit.settings.material.f0, max_time_s=s.hold_s,
                             damping_per_s=s.cycle_damping_per_s)
    rows.append(read(loaded, HOLD))
    if s.unload:
        loaded.move_box(*start, report(1), lambda: rows.append(read(loaded, UNLOADING)))
    return TensileResult(s, knit.settings.material, knit.settings.n_x, knit.settings.n_y, np.array(rows, dtype=float),
                         bool(held["converged"]), time.perf_counter() - t0)
