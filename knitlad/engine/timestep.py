"""Stable explicit time step from the stretching, bending and twisting limits.

Velocity Verlet is stable for dt < 2/omega_max. We bound omega_max^2 per node by
Gershgorin's theorem on the lumped-mass stiffness matrix (row sum / mass), a
safe upper bound that for a uniform rod gives back the textbook limits of
``shared/notes``: stretching dt < l/c_E, bending dt < (l^2/2) sqrt(rho_L/B).
An axial dashpot of damping ratio zeta lowers the limit by sqrt(1+zeta^2) - zeta.
Contact adds its own limit (:mod:`knitlad.engine.kernels.contact`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from knitlad.engine import units
from knitlad.engine.state import RodModel

DEFAULT_SAFETY = 0.7


def damped_limit_factor(zeta: float, predicted: bool = False) -> float:
    """omega dt_crit / 2 of an oscillator with a dashpot of damping ratio ``zeta`` under this code's Verlet.

    On the half-step velocity (DASHPOTS_HALF_STEP) it is sqrt(1 + zeta^2) - zeta. On the velocity
    predicted from the last acceleration (DASHPOTS_PREDICTED) the step map acts on (x, v, a_last)
    and has no simple closed form: the limit is found by bisection on its spectral radius
    (0.68 at zeta 0.2, 0.57 at 0.3, against 0.82 and 0.74).
    """
    if not predicted or zeta <= 0.0:
        return math.sqrt(1.0 + zeta * zeta) - zeta

    def radius(h: float) -> float:
        # (x, v_half, a_last) -> next, unit mass and frequency: drift, predict, force, kick
        step = np.array([[1.0, h, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        accel = np.array([-1.0, -2.0 * zeta, -zeta * h]) @ step  # a = -x_new - 2 zeta (v + h a_last / 2)
        m = np.vstack([step[0], step[1] + h * accel, accel])
        return float(np.max(np.abs(np.linalg.eigvals(m))))

    lo, hi = 0.0, 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if radius(mid) <= 1.0 + 1e-12 else (lo, mid)
    return lo / 2.0


MAX_STEPS = 100_000_000  # the most steps one call runs (the command line's cap on a ladder)


def step_count(name: str, value) -> int:
    """``value`` steps as an int; a ValueError naming ``name`` if it is not a finite number >= 0 or is over
    :data:`MAX_STEPS` (a call that would not end)."""
    try:
        steps = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: a number is needed, got {value!r}") from None
    if not (steps >= 0 and math.isfinite(steps)):
        raise ValueError(f"{name}: must be a finite number >= 0, got {value!r}")
    if round(steps) > MAX_STEPS:
        raise ValueError(f"{name}: {steps:.3g} steps, over the {MAX_STEPS:.0e} one call runs; nothing was run")
    return int(round(steps))


class UnstableTimeStep(ValueError):
    """A requested time step exceeds the explicit stability limit."""


@dataclass(frozen=True)
class TimeStepLimits:
    """Critical time steps [internal ms] of each mechanism and of all together."""

    stretching: float
    bending: float
    twisting: float
    contact: float
    combined: float

    def limiting(self) -> str:
        parts = {"stretching": self.stretching, "bending": self.bending, "twisting": self.twisting, "contact": self.contact}
        return min(parts, key=parts.get)

    def time_step(self, dt_s: float | None, safety: float) -> float:
        """The step [internal ms]: ``dt_s`` [s] if given (refused above the limit), else ``safety`` x the limit."""
        if dt_s is None:
            dt = safety * self.combined
        else:
            dt = dt_s / units.TIME
            if not (dt > 0 and math.isfinite(dt)):
                raise ValueError(f"dt must be a positive number of seconds, got {dt_s!r}")
            if dt > self.combined:
                limit = self.combined * units.TIME
                raise UnstableTimeStep(f"dt = {dt_s:.3e} s exceeds the stability limit {limit:.3e} s (set by "
                                       f"{self.limiting()}); use dt <= {limit:.3e} s or leave dt unset")
        return dt if math.isfinite(dt) else 1.0  # infinite limit: nothing moves, any step is stable


def stiffness_row_sums(model: RodModel, twist: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gershgorin row sums of the stretching and bending stiffness per node, and of twist per edge."""
    n = model.n_nodes
    k = model.EA / model.rest_length
    stretch = np.zeros(n)
    np.add.at(stretch, model.edge_a, 2.0 * k)
    np.add.at(stretch, model.edge_b, 2.0 * k)
    # bending: E ~ (B/2l_h) |x_p - 2 x_c + x_n|^2 / (l0 l1); row sums of the (1,-2,1) outer product
    l0 = model.rest_length[model.hinge_e0]
    l1 = model.rest_length[model.hinge_e1]
    kb = 4.0 * model.B_over_l / (l0 * l1)
    bend = np.zeros(n)
    np.add.at(bend, model.edge_a[model.hinge_e0], kb * 1.0)
    np.add.at(bend, model.edge_b[model.hinge_e0], kb * 2.0)
    np.add.at(bend, model.edge_b[model.hinge_e1], kb * 1.0)
    twist_rows = np.zeros(model.edge_a.shape[0])
    if twist:
        np.add.at(twist_rows, model.hinge_e0, 2.0 * model.GJ_over_l)
        np.add.at(twist_rows, model.hinge_e1, 2.0 * model.GJ_over_l)
    return stretch, bend, twist_rows


def critical_time_steps(model: RodModel, twist: bool, contact: float = math.inf,
                        implicit_axial: bool = False, predicted_dashpots: bool = False,
                        branch_ratio: float = 0.0) -> TimeStepLimits:
    """Stability limits dt_crit = 2 / omega_max; ``contact`` is the contact springs' own limit.

    ``implicit_axial``: the axial springs are implicit (AXIAL_IMPLICIT of :mod:`knitlad.engine.kernels.integrate`),
    so they set no limit (``stretching`` is inf) and the rest is bending, twist and contact.
    ``predicted_dashpots``: the axial dashpot acts on predicted velocities (:func:`damped_limit_factor`).
    ``branch_ratio``: the material damping's viscoelastic branch (:mod:`knitlad.engine.dissipation`), explicit
    stiffness of that many times the elastic one in stretching and bending (with implicit axial springs the
    branch's axial part is still explicit and limits the step)."""
    stretch, bend, twist_rows = stiffness_row_sums(model, twist)
    branch_stretch = branch_ratio * stretch
    stretch, bend = stretch + branch_stretch, bend * (1.0 + branch_ratio)
    free = ~model.held  # none free: the twist (and contact) limits may still apply
    mass = model.mass[free]

    def limit(rows: np.ndarray, mass: np.ndarray) -> float:
        w2 = np.max(rows / mass) if rows.size else 0.0
        return 2.0 / math.sqrt(w2) if w2 > 0 else math.inf

    zeta = 0.0
    if model.stretch_damping.size:
        crit = 2.0 * np.sqrt(model.EA / model.rest_length * 0.5 * model.mass[model.edge_a])
        zeta = float(np.max(model.stretch_damping / crit))
    damping_factor = damped_limit_factor(zeta, predicted_dashpots)
    dt_s = limit(stretch[free], mass) * damping_factor
    dt_b = limit(bend[free], mass)
    dt_all = limit(stretch[free] + bend[free], mass) * damping_factor
    if implicit_axial:
        dt_s = limit(branch_stretch[free], mass)
        dt_all = limit(branch_stretch[free] + bend[free], mass)
    free_edges = ~model.theta_held
    dt_t = limit(twist_rows[free_edges], model.twist_inertia[free_edges]) if twist else math.inf
    # contact and rod stiffness add: 1/dt^2 add in quadrature (omega^2 adds)
    dt_combined = 1.0 / math.sqrt(1.0 / dt_all**2 + 1.0 / contact**2) if math.isfinite(contact) else dt_all
    return TimeStepLimits(dt_s, dt_b, dt_t, contact, min(dt_combined, dt_t))
