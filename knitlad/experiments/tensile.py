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
LEG_NAMES = {LOADING: "loading", HOLD: "hold", UNLOADING: "unloading"}
COLUMNS = ("leg", "t_s", "box_lx_over_l0", "box_ly_over_l0", "lx_over_l0", "ly_over_l0", "fx", "fy")
# a tester's strip: force per 5 cm of width (EN ISO 13934-1 cuts 50 mm wide strips of woven fabric; knitted
# fabrics are quoted the same way)
STRIP_CM = 5.0
TESTER_COLUMNS = ("cycle", "leg", "t_s", "extension_mm", "extension_pct", "force_N", "force_N_per_5cm",
                  "transverse_force_N")
RESULTS_COLUMNS = ("cycle", "gauge_length_mm", "width_mm", "peak_force_N", "peak_force_N_per_5cm",
                   "extension_at_peak_mm", "extension_at_peak_pct", "initial_modulus_N_per_5cm",
                   "hysteresis_energy_mJ")


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
    cycles: int = 1  # loadings, each held and (but for a last without unload) brought back

    def __post_init__(self) -> None:
        if self.lx_max is None and self.ly_max is None:
            raise ValueError("give lx_max, ly_max or both: the box must move")
        if self.cycles > 1 and not self.unload:
            raise ValueError("cycles: a second cycle starts from the unloaded knit; give unload")


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

    @property
    def along_x(self) -> bool:
        """The test pulls along x (also when biaxial); else along y."""
        return self.settings.lx_max is not None

    def cycle_of_readings(self) -> np.ndarray:
        """The cycle (1, 2, ...) of each reading: a new one begins at each loading after an unloading."""
        leg = self.readings[:, 0]
        starts = np.r_[False, (leg[1:] == LOADING) & (leg[:-1] == UNLOADING)]
        return 1 + np.cumsum(starts)

    def _gauge(self) -> tuple[int, int, float, float]:
        """(the readings' column of the box along the pull, the stitch spacings over the gauge, the gauge length and
        the strip's width at the start [mm]): n_x stitches between the held ends along x, n_y + 1 course spacings
        between the bars along y; the width across, n_y l_y (n_x l_x)."""
        r, l0_mm = self.readings, self.material.stitch_length * 1e3
        box, count, across, across_count = (2, self.n_x, 3, self.n_y) if self.along_x else (3, self.n_y + 1, 2, self.n_x)
        return box, count, r[0, box] * count * l0_mm, r[0, across] * across_count * l0_mm

    def tester_readings(self) -> np.ndarray:
        """The readings in a tester's terms, (k, len(TESTER_COLUMNS)) but the leg's name: the extension of the
        gauge length (the held ends' distance at the start) [mm, %] and the pull F [N, N per 5 cm of the strip's
        width], F_x = f_x n_y f0 pulling along x (F_y = f_y n_x f0 along y), the transverse force beside it."""
        m, r = self.material, self.readings
        box, count, gauge_mm, width_mm = self._gauge()
        width_cm = width_mm / 10.0
        extension = (r[:, box] - r[0, box]) * count * m.stitch_length * 1e3
        f, f_across = (r[:, 6] * self.n_y, r[:, 7] * self.n_x) if self.along_x else (r[:, 7] * self.n_x, r[:, 6] * self.n_y)
        force = f * m.f0
        return np.column_stack([self.cycle_of_readings(), r[:, 0], r[:, 1], extension, 100 * extension / gauge_mm,
                                force, force * STRIP_CM / width_cm, f_across * m.f0])

    def tester_results(self) -> list[dict]:
        """One row per cycle of :data:`RESULTS_COLUMNS`: the peak force and its extension, the initial modulus (the
        secant d(F per 5 cm)/d(strain) over the loading's first ramp), and the hysteresis energy, the work the bars
        did over the cycle's closed path (what friction took), integral of F_x dx + F_y dy [mJ]."""
        t = self.tester_readings()
        r, m = self.readings, self.material
        _, _, gauge_mm, width_mm = self._gauge()
        # the bars' work: F_x = f_x n_y f0 over dx = dl_x n_x l0, F_y = f_y n_x f0 over dy = dl_y (n_y + 1) l0
        fx_N, fy_N = r[:, 6] * self.n_y * m.f0, r[:, 7] * self.n_x * m.f0
        dx_m, dy_m = np.diff(r[:, 2]) * self.n_x * m.stitch_length, np.diff(r[:, 3]) * (self.n_y + 1) * m.stitch_length
        work = 0.5 * (fx_N[1:] + fx_N[:-1]) * dx_m + 0.5 * (fy_N[1:] + fy_N[:-1]) * dy_m
        rows = []
        for c in np.unique(t[:, 0]).astype(int):
            mine = np.flatnonzero(t[:, 0] == c)
            peak = mine[np.argmax(t[mine, 5])]
            first = mine[:2]
            strain = (t[first[1], 4] - t[first[0], 4]) / 100 if len(first) == 2 else math.nan
            modulus = (t[first[1], 6] - t[first[0], 6]) / strain if strain else math.nan
            closed = t[mine[-1], 1] == UNLOADING
            rows.append({"cycle": int(c), "gauge_length_mm": gauge_mm, "width_mm": width_mm,
                         "peak_force_N": float(t[peak, 5]), "peak_force_N_per_5cm": float(t[peak, 6]),
                         "extension_at_peak_mm": float(t[peak, 3]), "extension_at_peak_pct": float(t[peak, 4]),
                         "initial_modulus_N_per_5cm": float(modulus),
                         "hysteresis_energy_mJ": float(work[mine[:-1]].sum() * 1e3) if closed else math.nan})
        return rows

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
                **{k: v for k, v in self.tester_results()[0].items() if k != "cycle"},
                "cycles": int(self.cycle_of_readings()[-1]), "wall_s": self.wall_s}


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
    legs = s.cycles * (2 if s.unload else 1)

    def report(done: int) -> Callable[[float], None]:
        return lambda f: progress("tensile", (done + f) / legs) if progress else None

    converged = True
    for cycle in range(s.cycles):
        if cycle:  # the next loading starts where the last unloading ended: its reading opens the cycle
            rows.append(read(loaded, LOADING))
        loaded.move_box(*top, report(2 * cycle if s.unload else cycle), lambda: rows.append(read(loaded, LOADING)))
        held = loaded.sim.settle(force_tol_N=s.hold_tol_f0 * knit.settings.material.f0, max_time_s=s.hold_s,
                                 damping_per_s=s.cycle_damping_per_s)
        converged = converged and bool(held["converged"])
        rows.append(read(loaded, HOLD))
        if s.unload:
            loaded.move_box(*start, report(2 * cycle + 1), lambda: rows.append(read(loaded, UNLOADING)))
    return TensileResult(s, knit.settings.material, knit.settings.n_x, knit.settings.n_y, np.array(rows, dtype=float),
                         converged, time.perf_counter() - t0)
