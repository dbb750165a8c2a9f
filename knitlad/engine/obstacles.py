"""Rigid obstacles in SI: planes and cylinders a yarn rests on, is pressed by or slides over.

``Simulation(rods, obstacles=[Plane(...), Cylinder(...)])``. Each has its own contact stiffness,
dashpots, friction coefficient and normal law, in the yarn-yarn contact's forms
(:mod:`knitlad.engine.kernels.obstacles`, :mod:`knitlad.engine.kernels.contact_law`), and may translate at a
constant velocity (a plate pressing, a bar pulled). The time step accounts for their stiffness. The force the
yarns exert on each: ``Simulation.obstacle_reactions_N()``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import check_contact_law, check_friction_coefficient
from knitlad.engine.deprecation import renamed_field
from knitlad.engine.kernels.contact_law import largest_slope_factor, law_mode
from knitlad.engine.kernels.obstacles import CYLINDER, PLANE, ObstacleState
from knitlad.engine.state import RodModel
from knitlad.engine.timestep import damped_limit_factor


STIFFNESS_INTERNAL = units.LENGTH / units.FORCE  # N/m -> mN/mm


def _unit(vector, name: str) -> np.ndarray:
    a = np.asarray(vector, dtype=float)
    norm = float(np.linalg.norm(a)) if a.shape == (3,) else 0.0
    if not (norm > 0 and math.isfinite(norm)):
        raise ValueError(f"{name} must be a non-zero, finite 3-vector, got {vector!r}")
    return a / norm


@dataclass(frozen=True, kw_only=True)
class _Contact:
    stiffness: float  # k_n [N/m]
    mu: float = 0.0  # Coulomb coefficient [-] (``friction`` before 0.5.0)
    damping_ratio: float = 0.3  # normal dashpot, fraction of critical [-]
    tangential_stiffness_ratio: float = 0.5  # k_t / k_n [-]
    tangential_damping_ratio: float = 0.3  # [-]
    velocity_m_s: tuple = (0.0, 0.0, 0.0)  # translation [m/s]
    law: str = "linear"  # the normal spring: "linear" or "hertz" (knitlad.engine.kernels.contact_law)
    reference_overlap: float | None = None  # delta_ref [m], where every law gives stiffness x delta_ref

    def _check(self) -> None:
        if not (self.stiffness > 0 and math.isfinite(self.stiffness)):
            raise ValueError(f"stiffness must be a positive number of N/m, got {self.stiffness!r}")
        check_friction_coefficient(self.mu)
        check_contact_law(self.law, self.reference_overlap)
        for name in ("damping_ratio", "tangential_stiffness_ratio", "tangential_damping_ratio"):
            value = getattr(self, name)
            if not (value >= 0 and math.isfinite(value)):
                raise ValueError(f"{name} must be >= 0, got {value!r}")
        for name in ("velocity_m_s", "point_m"):
            value = getattr(self, name)
            if np.shape(value) != (3,) or not np.all(np.isfinite(np.asarray(value, dtype=float))):
                raise ValueError(f"{name} must be a finite 3-vector, got {value!r}")


@renamed_field("friction", "mu", since="0.5.0")
@dataclass(frozen=True, kw_only=True)
class Plane(_Contact):
    """A rigid plane through ``point_m`` [m]; the yarn stays on the side ``normal`` points to."""

    point_m: tuple = (0.0, 0.0, 0.0)
    normal: tuple = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        self._check()
        _unit(self.normal, "normal")


@renamed_field("friction", "mu", since="0.5.0")
@dataclass(frozen=True, kw_only=True)
class Cylinder(_Contact):
    """A rigid cylinder of radius ``radius_m`` [m] about the line through ``point_m`` along ``axis``;
    the yarn stays outside. Its radius should exceed the yarn's edge length (module docstring of
    :mod:`knitlad.engine.kernels.obstacles`). ``length_m`` [m]: endless (inf, the default), or a pin of
    that length centred on ``point_m``, with hemispherical caps (a snag's needle)."""

    point_m: tuple = (0.0, 0.0, 0.0)
    axis: tuple = (0.0, 0.0, 1.0)
    radius_m: float = 1e-3
    length_m: float = math.inf

    def __post_init__(self) -> None:
        self._check()
        _unit(self.axis, "axis")
        if not (self.radius_m > 0 and math.isfinite(self.radius_m)):
            raise ValueError(f"radius_m must be positive, got {self.radius_m!r}")
        if not self.length_m >= 0:
            raise ValueError(f"length_m must be >= 0 m (inf: endless), got {self.length_m!r}")


Obstacle = Plane | Cylinder


def obstacle_state(obstacles: Sequence[Obstacle], n_nodes: int) -> ObstacleState:
    """The kernels' arrays of ``obstacles`` (internal units), with an empty contact history."""
    k = len(obstacles)
    kind = np.array([PLANE if isinstance(o, Plane) else CYLINDER for o in obstacles], dtype=np.int64)
    point = np.array([o.point_m for o in obstacles], dtype=float).reshape(k, 3) / units.LENGTH
    axis = np.array([_unit(o.normal if isinstance(o, Plane) else o.axis, "axis") for o in obstacles]).reshape(k, 3)
    radius = np.array([0.0 if isinstance(o, Plane) else o.radius_m / units.LENGTH for o in obstacles])
    half_length = np.array([math.inf if isinstance(o, Plane) else 0.5 * o.length_m / units.LENGTH for o in obstacles])
    velocity = np.array([o.velocity_m_s for o in obstacles], dtype=float).reshape(k, 3) / units.VELOCITY
    k_n = np.array([o.stiffness * STIFFNESS_INTERNAL for o in obstacles])
    return ObstacleState(
        kind, point, axis, radius, half_length, velocity, k_n, np.array([o.damping_ratio for o in obstacles], dtype=float),
        k_n * np.array([o.tangential_stiffness_ratio for o in obstacles], dtype=float),
        np.array([o.tangential_damping_ratio for o in obstacles], dtype=float),
        np.array([o.mu for o in obstacles], dtype=float), np.zeros((n_nodes, k, 3)),
        np.zeros((n_nodes, k), dtype=np.uint8), np.zeros((k, 3)),
        np.array([law_mode(o.law) for o in obstacles], dtype=np.int64),
        np.array([0.0 if o.reference_overlap is None else o.reference_overlap / units.LENGTH for o in obstacles]),
    )


def obstacle_time_step(model: RodModel, obstacles: Sequence[Obstacle], predicted: bool = False) -> float:
    """Critical time step [internal ms] of the obstacles' contact springs on the lightest free node,
    2/omega with omega^2 = (k_n' + k_t)/m summed over the obstacles (a node may touch all of them), k_n' the
    law's largest slope up to the overlaps it allows (:data:`knitlad.engine.kernels.contact_law.LAWS`)."""
    free = ~model.held
    if not obstacles or not np.any(free):
        return math.inf
    stiffness = sum(o.stiffness * (largest_slope_factor(o.law) + o.tangential_stiffness_ratio)
                    for o in obstacles) * STIFFNESS_INTERNAL
    zeta = max(max(o.damping_ratio, o.tangential_damping_ratio) for o in obstacles)
    return 2.0 / math.sqrt(stiffness / float(model.mass[free].min())) * damped_limit_factor(zeta, predicted)


class ObstacleReadout:
    """What a :class:`~knitlad.engine.simulation.Simulation` does with its obstacles (a mixin): read the forces
    on them and where they touch, and move them between relaxations (displacement-controlled statics)."""

    def move_obstacle(self, index: int, by_m) -> None:
        """Translate obstacle ``index`` by ``by_m`` [m] now (then ``relax`` or ``settle``): a plate pressed
        step by step. As with ``move_held``, the forces of the old position stay until the next evaluation;
        its contact history stays (a node that no longer touches forgets it at that evaluation)."""
        if self.obstacles is None or not 0 <= index < self.obstacles.kind.shape[0]:
            raise IndexError(f"no obstacle {index}")
        shift = np.asarray(by_m, dtype=float)
        if shift.shape != (3,) or not np.all(np.isfinite(shift)):
            raise ValueError(f"by_m must be a finite 3-vector [m], got {by_m!r}")
        self.obstacles.point[index] += shift / units.LENGTH

    def set_obstacle_velocity(self, index: int, velocity_m_s) -> None:
        """Translate obstacle ``index`` at ``velocity_m_s`` [m/s] from the next step on (zeros: it stops)."""
        self._obstacle(index)
        v = np.asarray(velocity_m_s, dtype=float)
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise ValueError(f"velocity_m_s must be a finite 3-vector [m/s], got {velocity_m_s!r}")
        self.obstacles.velocity[index] = v / units.VELOCITY

    def release_obstacle(self, index: int) -> None:
        """Let go: obstacle ``index`` exerts no force from the next step on (its springs, dashpots and friction
        zeroed, its contact history forgotten) and stops; it stays in the record where it was."""
        self._obstacle(index)
        o = self.obstacles
        o.k_n[index] = o.k_t[index] = o.damping_n[index] = o.damping_t[index] = o.mu[index] = 0.0
        o.slip[:, index] = 0.0
        o.velocity[index] = 0.0

    def _obstacle(self, index: int) -> None:
        if self.obstacles is None or not 0 <= index < self.obstacles.kind.shape[0]:
            raise IndexError(f"no obstacle {index}")

    def obstacle_reactions_N(self) -> np.ndarray:
        """(k, 3) the force the yarns exert on each obstacle at the last force evaluation [N]."""
        if self.obstacles is None:
            return np.zeros((0, 3))
        return self.obstacles.reaction * units.FORCE

    def obstacle_contacts(self) -> np.ndarray:
        """(n, k) each node's contact with each obstacle: 0 apart, 1 touching, 2 sliding."""
        if self.obstacles is None:
            return np.zeros((self.model.n_nodes, 0), dtype=np.uint8)
        return self.obstacles.state.copy()

    def obstacle_positions_m(self) -> np.ndarray:
        """(k, 3) each obstacle's reference point now (it moves with its velocity) [m]."""
        if self.obstacles is None:
            return np.zeros((0, 3))
        return self.obstacles.point * units.LENGTH
