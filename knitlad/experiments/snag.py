"""A snag: a pin hooks one loop of the stretched knit and pulls it out until the yarn breaks; the ladder follows.

How runs start in worn fabric, where the paper's experiment cuts a loop with scissors:

1. **hook** (:func:`pin_behind_head`): a pin, a rigid cylinder of finite length along the courses
   (:class:`knitlad.engine.obstacles.Cylinder` with ``length_m``), sits just behind the head of the loop
   of course ``row``, column ``column``, between the legs of the course above that pass behind it; as
   long as fits there.
2. **pull** (:func:`snag`): with friction on (the dynamics' mu, also between pin and yarn), the pin moves
   out of the fabric's plane (+z, the side the heads face) at ``snag_speed``. Each yarn segment breaks
   when its tension exceeds its breaking force (:mod:`knitlad.engine.fracture`: the material's, and a
   weaker ``weak_point_force`` on the hooked head's segments if given: a worn spot). Recorded every
   ``record_every_s``: the pin's travel and the force the yarn holds it back with (the pull-out curve).
   The pull ends at the first break, or without one at ``max_pull_m``.
3. **ladder**: at a break the pin lets go (:meth:`~knitlad.engine.simulation.Simulation.release_obstacle`)
   and the knit runs on as after the paper's cut (:func:`knitlad.experiments.laddering.propagate`,
   :func:`~knitlad.experiments.laddering.analyse`): the fronts are followed in the broken loop's column
   and the one beside it, cells counted from the state at the break (what the snag distorted before it
   is not the ladder's damage).

The energy ledger starts when the pull does: the work the pin put in up to the break is
``pin_work_J``; at the break the ledger starts again, so the ladder's record is what the break released.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from knitlad.engine import units
from knitlad.engine.deprecation import renamed_fields
from knitlad.engine.fracture import Break
from knitlad.engine.obstacles import Cylinder
from knitlad.experiments.laddering import (
    DynamicsSettings,
    LadderResult,
    Laddering,
    analyse,
    dynamics_rods,
    dynamics_simulation,
    propagate,
)
from knitlad.fabric.preparation import InfeasibleRun, StretchedKnit, stretch_contact

PIN_GAP_D = 0.15  # the pin starts this many yarn diameters behind the head
PIN_SIDE_MARGIN_D = 0.5  # ... and its caps this far from the legs beside it


@renamed_fields({"speed_m_s": "snag_speed", "breaking_force_N": "breaking_force",
                 "weak_point_N": "weak_point_force", "row": "snag_row", "column": "snag_column"}, since="0.14.0")
@dataclass(frozen=True)
class SnagSettings:
    """The snag's pin and pull (SI; from :meth:`knitlad.experiments.config.SnagConfig.snag_settings`, where each
    field has its default and unit). ``snag_row``/``snag_column``: the hooked loop (None: the knit's centre, where
    the paper cuts); ``breaking_force`` [N]: every segment's (None: the material's); ``weak_point_force`` [N]: the
    hooked head's segments' (None: as the rest)."""

    snag_speed: float  # m/s
    pin_radius_m: float
    max_pull_m: float
    breaking_force: float | None
    weak_point_force: float | None
    snag_row: int | None
    snag_column: int | None
    record_every_s: float = 20e-6  # the pull's readings (the model's choice, not a setting)

    def __post_init__(self) -> None:
        for name in ("snag_speed", "pin_radius_m", "max_pull_m", "record_every_s"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        for name in ("breaking_force", "weak_point_force"):
            value = getattr(self, name)
            if value is not None and not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{name} must be a positive number of N or None, got {value!r}")


@dataclass
class SnagResult:
    """The pull-out curve, the break and the ladder that followed it (None without a break)."""

    settings: SnagSettings
    row: int
    column: int
    pull_m: np.ndarray  # (k,) the pin's travel at each record
    force_N: np.ndarray  # (k,) the force the yarn holds the pin back with, along the pull
    breaks: tuple[Break, ...]  # what broke, in the order it did
    break_row: int = -1  # the course and column of the first break (-1: none)
    break_column: int = -1
    pin_work_J: float = 0.0  # the work the pin did on the knit up to the break (or the end of the pull)
    friction_before_break_J: float = 0.0  # what friction took during the pull
    stored_at_break_J: float = math.nan  # the knit's stored energy when it broke
    ladder: LadderResult | None = None
    fx_ini: float = math.nan  # the stretched knit's f_x before the snag
    wall_s: float = 0.0
    energy_pull: dict = field(default_factory=dict)  # the ledger at the break (EnergyLedger.as_dict) [J]

    @property
    def broke(self) -> bool:
        return bool(self.breaks)

    def summary(self) -> dict:
        """One row: the peak pull-out force, the break (when, where, its tension), the pin's work, and the
        ladder's observables (NaN without a break)."""
        first = self.breaks[0] if self.breaks else None
        out = {
            "snag_row": self.row, "snag_column": self.column, "broke": self.broke,
            "peak_force_N": float(self.force_N.max()) if self.force_N.size else math.nan,
            "pull_at_break_mm": float(self.pull_m[-1] * 1e3) if first and self.pull_m.size else math.nan,
            "break_tension_N": first.tension_N if first else math.nan,
            "break_row": self.break_row, "break_column": self.break_column,
            "pin_work_J": self.pin_work_J, "friction_before_break_J": self.friction_before_break_J,
        }
        ladder = self.ladder
        out["fx_ini"] = self.fx_ini
        for key in ("n_lad_over_ny", "v_lad_over_cb", "fx_fin", "reached_edge"):
            out[key] = getattr(ladder, key) if ladder is not None else (math.nan if key != "reached_edge" else False)
        out["v_down_over_cb"] = downward_velocity(ladder) if ladder is not None else math.nan
        if ladder is not None:
            record = ladder.energy_record()
            out["ladder_released_J"] = record.get("energy_start_J", math.nan) - record.get("energy_end_J", math.nan)
        else:
            out["ladder_released_J"] = math.nan
        out["wall_s"] = self.wall_s
        return out


def downward_velocity(ladder: LadderResult) -> float:
    """v/c_b of the downward front of the followed column, fitted from stitch 2 to 10 below the break (fewer
    where the knit has fewer courses below it): a broken head frees the course below it first, so the ladder
    from a snag may run down more than up, where the paper's v_lad is the upward front's. NaN if the front
    does not cover the fit's range."""
    from knitlad.fabric.measure import laddering_velocity

    s = ladder.settings.stretch
    last = min(10, ladder.cut_row - 1)
    first = min(2, max(last - 2, 1))
    l_y = ladder.ly_over_l0 * s.material.stitch_length
    return laddering_velocity(np.asarray(ladder.times_s), np.asarray(ladder.front_down), l_y, first,
                              last) / s.material.c_b


def loop_head_node(knit: StretchedKnit, row: int, column: int) -> int:
    """The node at the apex of the head of the loop of course ``row`` in ``column`` (the highest node of the
    course within a quarter stitch of the column's centre)."""
    k = knit.knit
    nodes = k.course_nodes(row)
    x = k.rods.state.x[nodes]
    l_x = knit.box_lx * knit.settings.material.stitch_length / units.LENGTH
    centre = knit.gauge.column_centres(knit.box_lx)[column]
    near = np.flatnonzero(np.abs(x[:, 0] - centre) < 0.25 * l_x)
    return int(nodes.start + near[np.argmax(x[near, 1])])


def pin_behind_head(knit: StretchedKnit, row: int, column: int, radius_m: float, speed_m_s: float,
                    mu: float) -> Cylinder:
    """The snag's pin: along x, just behind the head's apex (PIN_GAP_D diameters from the yarn), inside the
    head's arc, as long as fits between the nodes beside it (PIN_SIDE_MARGIN_D diameters clear of them),
    moving +z at ``speed_m_s``, at most half a stitch long; contact stiffness that of the yarns', friction
    ``mu``. InfeasibleRun if no pin of that radius fits there without touching the knit."""
    m = knit.settings.material
    x = knit.knit.rods.state.x * units.LENGTH  # m
    apex = loop_head_node(knit, row, column)
    r = 0.5 * m.diameter
    centre = x[apex] - np.array([0.0, 0.5 * radius_m, r + radius_m + PIN_GAP_D * m.diameter])
    reach = radius_m + r + PIN_SIDE_MARGIN_D * m.diameter
    # the nodes a pin along x would meet: within reach of its axis line, apart from the head's own arc (a
    # quarter stitch either side of the apex: what the pin is there to hook)
    course = knit.knit.node_course()
    l_x = knit.box_lx * m.stitch_length
    near_axis = np.hypot(x[:, 1] - centre[1], x[:, 2] - centre[2]) < reach
    head_arc = (course == row) & (np.abs(x[:, 0] - x[apex, 0]) < 0.25 * l_x)
    blocking = near_axis & ~head_arc
    half = (np.min(np.abs(x[blocking, 0] - centre[0])) if blocking.any() else math.inf) - reach
    half = min(half, 0.25 * l_x)
    along = np.clip(x[:, 0] - centre[0], -half, half)
    clearance = np.linalg.norm(x - centre - along[:, None] * np.array([1.0, 0.0, 0.0]), axis=1) - radius_m - r
    if not (half > 0.0 and clearance.min() > 0.0):
        raise InfeasibleRun(f"a pin of radius {radius_m * 1e3:g} mm does not fit behind the head of the loop at "
                            f"course {row}, column {column}: choose a thinner pin (pin_radius_mm)")
    contact = stretch_contact(knit.settings)
    return Cylinder(stiffness=contact.stiffness, mu=mu, point_m=tuple(centre), axis=(1.0, 0.0, 0.0),
                    radius_m=radius_m, length_m=2.0 * half, velocity_m_s=(0.0, 0.0, speed_m_s))


def cell_of_node(knit: StretchedKnit, node: int) -> tuple[int, int]:
    """(course, column) of a node of the stretched knit: its yarn's course, the nearest column centre."""
    x = knit.knit.rods.state.x[node]
    columns = knit.gauge.column_centres(knit.box_lx)
    return int(knit.knit.node_course()[node]), int(np.argmin(np.abs(columns - x[0])))


def snag(knit: StretchedKnit, dynamics: DynamicsSettings, settings: SnagSettings, progress=None) -> SnagResult:
    """Hook, pull until a break (or ``max_pull_m``), then let the ladder run (module docstring)."""
    t0 = time.perf_counter()
    s, m = knit.settings, knit.settings.material
    row = s.n_y // 2 if settings.snag_row is None else settings.snag_row
    column = s.n_x // 2 if settings.snag_column is None else settings.snag_column
    if not (0 <= row < s.n_y and 0 <= column < s.n_x):
        raise ValueError(f"row, column: ({row}, {column}) is outside the {s.n_x} x {s.n_y} knit")
    pin = pin_behind_head(knit, row, column, settings.pin_radius_m, settings.snag_speed, dynamics.mu)
    rods = dynamics_rods(knit.knit.rods.copy(), dynamics, m)  # the stretched knit stays as it was, for reuse
    sim = dynamics_simulation(rods, knit, dynamics, obstacles=[pin])
    strength = np.full(sim.model.edge_a.shape[0], settings.breaking_force or m.breaking_force)
    if settings.weak_point_force is not None:
        x = sim.positions_m()
        a, b = sim.model.edge_a, sim.model.edge_b
        middle = 0.5 * (x[a] + x[b])
        on_pin = (np.abs(middle[:, 0] - pin.point_m[0]) < 0.5 * pin.length_m + pin.radius_m) & (
            knit.knit.node_course()[a] == row) & (np.abs(middle[:, 1] - pin.point_m[1]) < 4 * pin.radius_m)
        strength[on_pin] = settings.weak_point_force
    sim.set_breaking_force(strength)
    sim.reset_ledger()
    every = max(1, int(round(settings.record_every_s / sim.dt_s)))
    pull, force = [0.0], [0.0]
    start_z = sim.obstacle_positions_m()[0, 2]
    while not sim.breaks and pull[-1] < settings.max_pull_m:
        sim.step(every)
        pull.append(float(sim.obstacle_positions_m()[0, 2] - start_z))
        force.append(float(-sim.obstacle_reactions_N()[0, 2]))
        if progress:
            progress("pull", min(pull[-1] / settings.max_pull_m, 1.0))
    ledger = sim.ledger()
    result = SnagResult(settings, row, column, np.array(pull), np.array(force), sim.breaks,
                        pin_work_J=ledger.obstacle_work, friction_before_break_J=ledger.friction,
                        energy_pull=ledger.as_dict(), fx_ini=knit.fx_ini)
    sim.release_obstacle(0)
    if sim.breaks:
        first = sim.breaks[0]
        result.break_row, result.break_column = cell_of_node(knit, first.node)
        result.stored_at_break_J = ledger.stored
        sim.reset_ledger()  # the ladder's ledger: what the break released
        # the laddered cells at the break are the baseline: what the snag distorted is not the ladder's damage
        baseline = knit.gauge.laddered(sim.state.x, knit.box_lx, knit.box_ly)
        run = Laddering(knit, dynamics, sim, first.edge, result.break_row, result.break_column, baseline,
                        time.perf_counter() - t0)
        result.ladder = analyse(propagate(run, progress=progress))
    result.wall_s = time.perf_counter() - t0
    return result
