"""Yarn-obstacle contact: rigid planes and cylinders, fixed or moving, with the yarn-yarn contact law.

Each node is a sphere of its yarn's radius r (a chain of them stands for the yarn: the obstacle's
radius of curvature must exceed the edge length for the chain to feel it smoothly).

* Plane (point p, unit normal n): the yarn lies on the side n points to; overlap
  delta = r - (x - p).n, normal n.
* Cylinder (point p on its axis, unit axis a, radius R, half-length h): the yarn lies outside; with
  s = (x - p).a clamped to [-h, h] and rho = |(x - p) - s a|, overlap delta = R + r - rho, normal
  along (x - p) - s a. An endless cylinder has h = inf; a finite one has hemispherical caps (a pin).
* The force, as :func:`knitlad.engine.kernels.contact.pair_contact_forces` gives a pair of yarns (Cundall
  & Strack 1979): f_n = f(delta) - 2 zeta_n sqrt(k_n m) v_n, never pulling, f the obstacle's law
  (:mod:`knitlad.engine.kernels.contact_law`); a tangential spring
  stretched by the slip u_t accumulated while the node touches, plus a dashpot, capped by Coulomb
  |f_t| <= mu f_n (then u_t is set to the slipping value), reset when the node leaves. m is the
  node's mass (the obstacle is rigid), v the node's velocity less the obstacle's.
* An obstacle moves by translation at its velocity (:func:`advance_obstacles`, once per step).
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from knitlad.engine.kernels.contact import coulomb_spring
from knitlad.engine.kernels.contact_law import normal_spring
from knitlad.engine.kernels.options import NUMBA_OPTS
from knitlad.engine.kernels.vec import dot

PLANE, CYLINDER = 0, 1


class ObstacleState(NamedTuple):
    """Rigid obstacles and their contact history (internal units; :mod:`knitlad.engine.obstacles` in SI)."""

    kind: np.ndarray  # (k,) PLANE or CYLINDER
    point: np.ndarray  # (k, 3) a point of the plane, or of the cylinder's axis, now
    axis: np.ndarray  # (k, 3) unit normal of the plane (towards the yarn), or the cylinder's axis
    radius: np.ndarray  # (k,) the cylinder's radius (0 for a plane)
    half_length: np.ndarray  # (k,) half the cylinder's length along its axis (inf: endless; unused for a plane)
    velocity: np.ndarray  # (k, 3) translation velocity
    k_n: np.ndarray  # (k,) normal stiffness
    damping_n: np.ndarray  # (k,) normal dashpot, fraction of critical
    k_t: np.ndarray  # (k,) tangential stiffness
    damping_t: np.ndarray  # (k,) tangential dashpot, fraction of critical
    mu: np.ndarray  # (k,) Coulomb coefficient
    slip: np.ndarray  # (n, k, 3) tangential spring elongation of each node on each obstacle
    state: np.ndarray  # (n, k) uint8: 0 apart, 1 touching, 2 sliding (last evaluation)
    reaction: np.ndarray  # (k, 3) force the yarns exert on each obstacle (last evaluation)
    law: np.ndarray  # (k,) int64 the normal law's mode (knitlad.engine.kernels.contact_law)
    reference_overlap: np.ndarray  # (k,) the law's delta_ref


@njit(**NUMBA_OPTS)
def obstacle_gap(kind, point, axis, radius, half_length, x, i, o):
    """(signed distance from the obstacle's surface to node i's axis point, unit normal towards the node)."""
    rx = x[i, 0] - point[o, 0]
    ry = x[i, 1] - point[o, 1]
    rz = x[i, 2] - point[o, 2]
    along = dot(rx, ry, rz, axis[o, 0], axis[o, 1], axis[o, 2])
    if kind[o] == PLANE:
        return along, axis[o, 0], axis[o, 1], axis[o, 2]
    along = min(max(along, -half_length[o]), half_length[o])  # a finite cylinder's caps
    rx -= along * axis[o, 0]
    ry -= along * axis[o, 1]
    rz -= along * axis[o, 2]
    rho = math.sqrt(rx * rx + ry * ry + rz * rz)
    if rho < 1e-300:  # on the axis: any radial direction
        return -radius[o], 1.0, 0.0, 0.0
    return rho - radius[o], rx / rho, ry / rho, rz / rho


@njit(**NUMBA_OPTS)
def obstacle_forces(x, v, mass, node_radius, held, o, dt, force):
    """Add each obstacle's contact force on every free node to ``force``; the opposite sum to ``o.reaction``.
    Advances the slip history (module docstring). Returns the power the obstacles put into the nodes,
    sum f.v [uJ/ms] (negative while they take energy out: their dashpots and friction)."""
    o.reaction[:] = 0.0
    power = 0.0
    for i in range(x.shape[0]):
        for b in range(o.kind.shape[0]):
            gap, nx, ny, nz = obstacle_gap(o.kind, o.point, o.axis, o.radius, o.half_length, x, i, b)
            overlap = node_radius[i] - gap
            if overlap <= 0.0 or held[i]:
                o.slip[i, b, 0] = 0.0
                o.slip[i, b, 1] = 0.0
                o.slip[i, b, 2] = 0.0
                o.state[i, b] = 0
                continue
            vx = v[i, 0] - o.velocity[b, 0]
            vy = v[i, 1] - o.velocity[b, 1]
            vz = v[i, 2] - o.velocity[b, 2]
            vn = dot(vx, vy, vz, nx, ny, nz)  # > 0: separating
            fn = (normal_spring(o.law[b], o.k_n[b], o.reference_overlap[b], overlap)
                  - 2.0 * o.damping_n[b] * math.sqrt(o.k_n[b] * mass[i]) * vn)
            if fn < 0.0:
                fn = 0.0
            vtx = vx - vn * nx
            vty = vy - vn * ny
            vtz = vz - vn * nz
            gamma_t = 2.0 * o.damping_t[b] * math.sqrt(o.k_t[b] * mass[i])
            ftx, fty, ftz, ux, uy, uz, slides = coulomb_spring(o.slip[i, b, 0], o.slip[i, b, 1], o.slip[i, b, 2], nx,
                                                               ny, nz, vtx, vty, vtz, vtx, vty, vtz, dt, o.k_t[b],
                                                               gamma_t, o.mu[b] * fn)
            o.state[i, b] = 2 if slides else 1
            o.slip[i, b, 0] = ux
            o.slip[i, b, 1] = uy
            o.slip[i, b, 2] = uz
            fx = fn * nx + ftx
            fy = fn * ny + fty
            fz = fn * nz + ftz
            force[i, 0] += fx
            force[i, 1] += fy
            force[i, 2] += fz
            o.reaction[b, 0] -= fx
            o.reaction[b, 1] -= fy
            o.reaction[b, 2] -= fz
            power += fx * v[i, 0] + fy * v[i, 1] + fz * v[i, 2]
    return power


@njit(**NUMBA_OPTS)
def advance_obstacles(o, dt):
    """Translate every obstacle by its velocity over ``dt``."""
    for b in range(o.kind.shape[0]):
        for k in range(3):
            o.point[b, k] += o.velocity[b, k] * dt
