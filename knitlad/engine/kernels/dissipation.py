"""Dissipation as physics, and the energy ledger's accumulators.

Three ways a yarn loses energy besides friction, each a kernel that *adds* into the force array and
returns the energy it took out over the step [uJ]:

* **Material damping** (:func:`viscoelastic_forces`): the Nylon is a standard linear solid (Zener), a
  spring in parallel with a Maxwell branch, in the rod's own strains: the extension g = |e| - |e_bar| of
  each edge and the curvature binormal kb of each hinge, taken along its own line (the strains the elastic
  energy depends on, so a rigid motion is not damped). The branch has stiffness ``ratio`` x the elastic one
  (EA, B) and relaxes towards the strain with the time tau: q' = (strain - q)/tau, its energy
  ratio k |strain - q|^2 / 2.
  Its loss factor at angular frequency omega is

      eta(omega) = ratio omega tau / (1 + (1 + ratio) (omega tau)^2),

  which peaks at omega tau = 1/sqrt(1 + ratio) with eta_max = ratio / (2 sqrt(1 + ratio))
  (:func:`knitlad.engine.dissipation.MaterialDamping`). Far above the peak the branch is an extra stiffness
  (which the step limit counts), far below it a weak dashpot; a constant loss factor over all frequencies
  (hysteretic damping) has no causal form with a finite number of branches. The branch's internal
  variable is advanced exactly over each step at the strain of the step's start,
  q <- strain + (q - strain) exp(-dt/tau), so the energy it dissipates is the branch energy it releases,
  exactly, and the update is stable at any dt/tau.
* **Air drag** (:func:`air_drag_forces`): each edge is a cylinder of its yarn's diameter in still air; the
  normal component of its velocity feels the drag of a cylinder in cross flow at its Reynolds number,
  f_n = (1/2) rho_air C_N(Re) d |v_n| v_n per length with C_N = 1 + 10 Re^(-2/3) (White, *Fluid Mechanics*,
  the fit to a circular cylinder's drag, 1 <= Re <= 2e5), the tangential component a skin friction
  f_t = (1/2) rho_air pi d C_T |v_t| v_t per length (C_T: :data:`knitlad.engine.dissipation.SKIN_FRICTION`).
* **A global drag** -drag m v on every free node (:func:`drag_dissipation` counts it; the force is in
  :func:`knitlad.engine.kernels.integrate.external_forces`): the authors' engine damps this way. Not physics.

The ledger (``Workspace.ledger``, rows x :data:`N_LEDGER` channels) accumulates, per yarn (kernels run yarn
by yarn) or per block of contact pairs, the energy each mechanism took out since it was zeroed, and the
work done on the rods by the held nodes (supports that move) and by the obstacles, and the energy the union
contact counting creates or destroys when a contact changes owner
(:func:`knitlad.engine.kernels.contact.pair_contact_forces`).
"""

import math
from typing import NamedTuple

from numba import njit, prange

from knitlad.engine.kernels.elastic import add_hinge_forces, isotropic_bending_gradient
from knitlad.engine.kernels.options import NUMBA_OPTS, PARALLEL_OPTS
from knitlad.engine.kernels.vec import cross, dot

# channels of the ledger: energy dissipated [uJ] (or, for the last three, energy put into the rods)
AXIAL_DASHPOT, CONTACT_DASHPOT, FRICTION, GLOBAL_DRAG, MATERIAL, AIR, SUPPORT_WORK, OBSTACLE_WORK, OWNER_CHANGES = (
    range(9))
N_LEDGER = 9
LEDGER_NAMES = ("axial_dashpot", "contact_dashpot", "friction", "global_drag", "material", "air", "support_work",
                "obstacle_work", "owner_changes")

# below this |kb|, a hinge is straight: its bending branch has no direction to act along
STRAIGHT_KB = 1e-12
# an edge slower than this [m/s] feels no air: its drag, under 1e-6 N/m (Re < 0.1), is a millionth of the
# yarn's tension gradients, and the drag law's power costs as much as the rest of a step would on all edges
AIR_STILL = 0.01


class DampingParams(NamedTuple):
    """The dissipation of a dynamic run, in internal units (:class:`knitlad.engine.dissipation.Dissipation` in SI)."""

    drag: float  # global drag rate [1/ms]: -drag m v on every free node
    branch_ratio: float  # stiffness of the viscoelastic branch over the elastic one [-] (0: no material damping)
    relaxation_time: float  # the branch's tau [ms]
    air_density: float  # [mg/mm^3] (0: no air)
    air_viscosity: float  # kinematic [mm^2/ms]
    skin_friction: float  # tangential drag coefficient C_T [-]
    supports_moving: bool  # some held node has a prescribed velocity: count the work the supports do
    spin_drag: float  # [1/ms]: -spin_drag I omega on every free edge's spin about its axis (twist only)


@njit(**NUMBA_OPTS)
def no_damping():
    """Statics: no drag, no branch, no air (what a relaxation's force evaluations use)."""
    return DampingParams(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, False, 0.0)


@njit(**NUMBA_OPTS)
def viscoelastic_forces(e, elen, v, edge_a, edge_b, rest_length, EA, hinge_e0, hinge_e1, B_over_l, ratio, decay,
                        lead, branch_ext, branch_kb, F, e0, e1, h0, h1, loss):
    """The viscoelastic branches' forces on edges [e0, e1) and hinges [h0, h1) (module docstring), added to F;
    then each branch relaxed over the step, exactly for a strain that changes at its rate now (velocities
    ``v``) across the step: q <- strain + (q - strain) decay + rate lead, with ``decay`` = exp(-dt/tau) and
    ``lead`` = dt - tau (1 - decay) (relaxing towards the strain of the step's start instead lags the branch
    by dt/2, which overdamps a mode by ratio omega dt / 2 / eta: 3 % for the Nylon's axial waves at the
    stability limit). Adds to ``loss[0]`` the energy released [uJ]: the branch energy its relaxation gave up at
    the current shape (a step may give back O(dt^2), the price of the lead).

    Stretching: E_1 = ratio EA (g - q_e)^2 / (2 |e_bar|), tension ratio EA (g - q_e)/|e_bar| along the edge.
    Bending: E_1 = ratio B |kb - q_h|^2 / (2 l_h), q_h a vector kept along the line of kb: each step it is first
    projected on that line (p = q_h . kb/|kb|, signed, so a hinge bending through straight, where kb turns
    over, sees its strain change sign as in plane bending), the part across it released (the direction kb
    turns to about the yarn is no strain of an isotropic rod without twist, nor is a rigid rotation). The
    force is then the gradient of ratio B (|kb| - p)^2/2l, that of B |kb|^2/2l
    (:func:`knitlad.engine.kernels.elastic.bending_forces`) with kb replaced by (|kb| - p) kb/|kb|, and p
    relaxes towards |kb|. Across a step a rigid rotation turns kb by O(dt): the projection releases O(dt^2)
    of the branch's energy, so rigid motion is undamped as dt -> 0.
    """
    released = 0.0
    for k in range(e0, e1):
        a = edge_a[k]
        b = edge_b[k]
        stiffness = ratio * EA[k] / rest_length[k]
        g = elen[k] - rest_length[k]
        lag = g - branch_ext[k]
        inv = 1.0 / elen[k]
        scale = stiffness * lag * inv
        F[a, 0] += scale * e[k, 0]
        F[a, 1] += scale * e[k, 1]
        F[a, 2] += scale * e[k, 2]
        F[b, 0] -= scale * e[k, 0]
        F[b, 1] -= scale * e[k, 1]
        F[b, 2] -= scale * e[k, 2]
        rate = ((v[b, 0] - v[a, 0]) * e[k, 0] + (v[b, 1] - v[a, 1]) * e[k, 1] + (v[b, 2] - v[a, 2]) * e[k, 2]) * inv
        after = lag * decay - rate * lead
        branch_ext[k] = g - after
        released += 0.5 * stiffness * (lag * lag - after * after)
    for h in range(h0, h1):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        ax, ay, az = e[k0, 0], e[k0, 1], e[k0, 2]
        bx, by, bz = e[k1, 0], e[k1, 1], e[k1, 2]
        cx, cy, cz = cross(ax, ay, az, bx, by, bz)
        inv_D = 2.0 / (elen[k0] * elen[k1] + dot(ax, ay, az, bx, by, bz))
        kbx, kby, kbz = cx * inv_D, cy * inv_D, cz * inv_D
        bend = math.sqrt(kbx * kbx + kby * kby + kbz * kbz)
        stiffness = ratio * B_over_l[h]
        qx, qy, qz = branch_kb[h, 0], branch_kb[h, 1], branch_kb[h, 2]
        q2 = qx * qx + qy * qy + qz * qz
        # a straight hinge has no line for its branch: u = 0 lets the branch go (released below), with no branch
        inv_bend = 1.0 / max(bend, STRAIGHT_KB)
        ux, uy, uz = kbx * inv_bend, kby * inv_bend, kbz * inv_bend
        p = qx * ux + qy * uy + qz * uz
        lag = bend - p
        _, _, _, gax, gay, gaz, gbx, gby, gbz = isotropic_bending_gradient(
            ax, ay, az, bx, by, bz, elen[k0], elen[k1], stiffness * lag * inv_bend)
        add_hinge_forces(F, edge_a[k0], edge_b[k0], edge_b[k1], gax, gay, gaz, gbx, gby, gbz)
        p0, c0, n0 = edge_a[k0], edge_b[k0], edge_b[k1]
        rate = bend_rate(ax, ay, az, bx, by, bz, elen[k0], elen[k1], inv_D, ux, uy, uz, bend,
                         v[c0, 0] - v[p0, 0], v[c0, 1] - v[p0, 1], v[c0, 2] - v[p0, 2],
                         v[n0, 0] - v[c0, 0], v[n0, 1] - v[c0, 1], v[n0, 2] - v[c0, 2])
        after = lag * decay - rate * lead
        p = bend - after
        branch_kb[h, 0] = p * ux
        branch_kb[h, 1] = p * uy
        branch_kb[h, 2] = p * uz
        # the part of q across the line of kb, then the relaxation along it
        released += 0.5 * stiffness * (max(q2 - (bend - lag) * (bend - lag), 0.0) + lag * lag - after * after)
    loss[0] += released


@njit(inline="always", **NUMBA_OPTS)
def bend_rate(ax, ay, az, bx, by, bz, la, lb, two_over_D, ux, uy, uz, bend, dax, day, daz, dbx, dby, dbz):
    """d|kb|/dt = u . d(kb)/dt at the hinge of edges a = x_c - x_p, b = x_n - x_c (u = kb/|kb|), whose rates
    are a' = v_c - v_p, b' = v_n - v_c, with kb = 2 a x b / D, D = |a||b| + a.b:
    d(kb)/dt = (2 (a' x b + a x b') - kb D')/D, D' = (a.a') |b|/|a| + (b.b') |a|/|b| + a'.b + a.b'.
    Scalars only: an inlined helper that takes an array puts reference counting into its caller's loop."""
    c1x, c1y, c1z = cross(dax, day, daz, bx, by, bz)
    c2x, c2y, c2z = cross(ax, ay, az, dbx, dby, dbz)
    d_dot = (dot(ax, ay, az, dax, day, daz) * lb / la + dot(bx, by, bz, dbx, dby, dbz) * la / lb
             + dot(dax, day, daz, bx, by, bz) + dot(ax, ay, az, dbx, dby, dbz))
    return 0.5 * two_over_D * (2.0 * dot(ux, uy, uz, c1x + c2x, c1y + c2y, c1z + c2z) - bend * d_dot)


@njit(**NUMBA_OPTS)
def branch_energy(elen, rest_length, EA, hinge_e0, hinge_e1, e, B_over_l, ratio, branch_ext, branch_kb):
    """Energy stored in the viscoelastic branches [uJ]: sum ratio k |strain - q|^2 / 2."""
    total = 0.0
    if ratio == 0.0:
        return total
    for k in range(elen.shape[0]):
        lag = elen[k] - rest_length[k] - branch_ext[k]
        total += 0.5 * ratio * EA[k] / rest_length[k] * lag * lag
    for h in range(hinge_e0.shape[0]):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        cx, cy, cz = cross(e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2])
        inv_D = 2.0 / (elen[k0] * elen[k1] + dot(e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2]))
        lx, ly, lz = cx * inv_D - branch_kb[h, 0], cy * inv_D - branch_kb[h, 1], cz * inv_D - branch_kb[h, 2]
        total += 0.5 * ratio * B_over_l[h] * (lx * lx + ly * ly + lz * lz)
    return total


@njit(**NUMBA_OPTS)
def relaxed_branches(e, elen, rest_length, hinge_e0, hinge_e1, branch_ext, branch_kb):
    """Every branch at rest at the current shape (q = strain): how a simulation starts, from a state at rest."""
    for k in range(elen.shape[0]):
        branch_ext[k] = elen[k] - rest_length[k]
    for h in range(hinge_e0.shape[0]):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        cx, cy, cz = cross(e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2])
        inv_D = 2.0 / (elen[k0] * elen[k1] + dot(e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2]))
        branch_kb[h, 0] = cx * inv_D
        branch_kb[h, 1] = cy * inv_D
        branch_kb[h, 2] = cz * inv_D


@njit(inline="always", **NUMBA_OPTS)
def cross_flow_drag_coefficient(reynolds):
    """C_N of a circular cylinder in cross flow at Reynolds number ``reynolds`` = |v_n| d / nu:
    1 + 10 Re^(-2/3) (White's fit, 1 <= Re <= 2e5; below, it underestimates the Stokes-Oseen rise)."""
    return 1.0 + 10.0 * reynolds ** (-2.0 / 3.0)


@njit(**NUMBA_OPTS)
def air_drag_forces(e, elen, v, edge_a, edge_b, radius, density, viscosity, skin_friction, F, e0, e1, dt, loss):
    """Air drag on edges [e0, e1) (module docstring), half of each edge's on each of its nodes, added to F.
    The edge moves at the mean of its nodes' velocities; one slower than :data:`AIR_STILL` is skipped. Adds to
    ``loss[0]`` what it takes out over dt [uJ]."""
    power = 0.0
    for k in range(e0, e1):
        a = edge_a[k]
        b = edge_b[k]
        vx = 0.5 * (v[a, 0] + v[b, 0])
        vy = 0.5 * (v[a, 1] + v[b, 1])
        vz = 0.5 * (v[a, 2] + v[b, 2])
        if vx * vx + vy * vy + vz * vz < AIR_STILL * AIR_STILL:  # most of a stretched knit: skip its drag law
            continue
        inv = 1.0 / elen[k]
        tx, ty, tz = e[k, 0] * inv, e[k, 1] * inv, e[k, 2] * inv
        vt = dot(vx, vy, vz, tx, ty, tz)
        nx, ny, nz = vx - vt * tx, vy - vt * ty, vz - vt * tz
        speed_n = math.sqrt(nx * nx + ny * ny + nz * nz)
        d = radius[a] + radius[b]  # the diameter
        cn = 0.0
        if speed_n > 0.0:
            reynolds = speed_n * d / viscosity
            cn = cross_flow_drag_coefficient(reynolds)
        # force per length / velocity component, times the edge's length, shared by its two nodes
        normal = -0.25 * density * cn * d * speed_n * elen[k]
        tangential = -0.25 * density * math.pi * d * skin_friction * abs(vt) * elen[k]
        fx = normal * nx + tangential * vt * tx
        fy = normal * ny + tangential * vt * ty
        fz = normal * nz + tangential * vt * tz
        F[a, 0] += fx
        F[a, 1] += fy
        F[a, 2] += fz
        F[b, 0] += fx
        F[b, 1] += fy
        F[b, 2] += fz
        power -= 2.0 * (fx * vx + fy * vy + fz * vz)
    loss[0] += dt * power


@njit(**PARALLEL_OPTS)
def drag_dissipation(held, mass, v, drag):
    """The power the global drag -drag m v takes out of the free nodes [uJ/ms]."""
    total = 0.0
    for i in prange(v.shape[0]):
        if not held[i]:
            total += drag * mass[i] * (v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] + v[i, 2] * v[i, 2])
    return total


@njit(**NUMBA_OPTS)
def spin_drag_torques(theta_held, twist_inertia, omega, spin_drag, torque):
    """torque -= spin_drag I omega on every free edge; returns the power it takes out [uJ/ms].

    The global drag on the spin, as the authors' engine applies it (its ``kernel_Calculate_le``: a moment
    -lambda (theta_t - theta_t-1)/dt with the lambda of the nodes' drag, so at the same rate)."""
    total = 0.0
    for j in range(omega.shape[0]):
        if not theta_held[j]:
            c = spin_drag * twist_inertia[j]
            torque[j] -= c * omega[j]
            total += c * omega[j] * omega[j]
    return total


@njit(**PARALLEL_OPTS)
def support_power(held, v_prescribed, force):
    """The power the supports put into the rods [uJ/ms]: at a held node the support's force is -force
    (``force``: the sum of every other force on it), and the node moves at its prescribed velocity."""
    total = 0.0
    for i in prange(force.shape[0]):
        if held[i]:
            total -= (force[i, 0] * v_prescribed[i, 0] + force[i, 1] * v_prescribed[i, 1]
                      + force[i, 2] * v_prescribed[i, 2])
    return total


@njit(**NUMBA_OPTS)
def rail_power(rail_node, rail_axis, v, taken):
    """The power the rails put into the rods by moving across themselves (a clip carried with its bar) [uJ/ms]:
    the rail's reaction across it, -(taken less its part along the rail), times the node's velocity (the part
    along, the clip's friction, is counted as friction)."""
    total = 0.0
    for r in range(rail_node.shape[0]):
        i = rail_node[r]
        along = taken[r, 0] * rail_axis[r, 0] + taken[r, 1] * rail_axis[r, 1] + taken[r, 2] * rail_axis[r, 2]
        for k in range(3):
            total -= (taken[r, k] - along * rail_axis[r, k]) * v[i, k]
    return total
