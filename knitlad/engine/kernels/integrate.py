"""Time stepping: force assembly, velocity Verlet, FIRE relaxation, blow-up guard.

All loops over steps run inside Numba so a small scene pays no Python cost per
step. ``m`` is a :class:`knitlad.engine.state.RodModel` (read only), ``s`` a
:class:`knitlad.engine.state.RodState` (advanced in place), ``w`` a
:class:`knitlad.engine.state.Workspace`, ``c`` the contact buffers
(:class:`knitlad.engine.contact.Contacts`). The modes are arguments, never read off the
arrays: ``twist``, ``contact`` (yarn-yarn contact on), ``axial`` and ``dashpots`` (below). ``twist`` is one of
TWIST_OFF (0: isotropic bending of rods straight at rest, no twist), TWIST_FRAMED
(1, or True: framed DER, material frames, natural curvature) and TWIST_STRAIGHT (2:
rods straight at rest that twist: isotropic bending and the twist energy, the
reference twist by the holonomy of the tangents, no material frame: DER08 sec. 4.2; at
zero natural curvature TWIST_FRAMED's bending energy is B |kb|^2 cos^2(m/2) / 2l, a
coupling of bending and twist that this one, as the continuum, has not: docs/accuracy.md).
``if twist:`` reads "the yarns carry twist". TWIST_STRAIGHT's force evaluation time-transports
only the anchors' reference frames (``Workspace.frame_anchor``); the kernels that advance or read
the state (:func:`verlet_steps`, :func:`fire_relax`, :func:`potential_energy`) rebuild the others
before they return (:func:`complete_frames`), so the state they hand back is complete.
"""

import math

import numpy as np
from numba import njit, prange

from knitlad.engine.kernels.options import NUMBA_OPTS, PARALLEL_OPTS
from knitlad.engine.kernels.contact import contact_energy, contact_forces, refresh_contacts
from knitlad.engine.kernels.dissipation import (
    AIR,
    AXIAL_DASHPOT,
    FRICTION,
    GLOBAL_DRAG,
    MATERIAL,
    OBSTACLE_WORK,
    SUPPORT_WORK,
    air_drag_forces,
    drag_dissipation,
    no_damping,
    rail_power,
    spin_drag_torques,
    support_power,
    viscoelastic_forces,
)
from knitlad.engine.kernels.obstacles import advance_obstacles, obstacle_forces
from knitlad.engine.kernels.elastic import (
    bending_energy,
    bending_forces,
    edge_vectors,
    framed_bending_twisting_energy,
    framed_bending_twisting_forces,
    implicit_stretching_forces,
    straight_bending_twisting_forces,
    stretching_energy,
    stretching_forces,
    twisting_energy,
)
from knitlad.engine.kernels.frames import (
    material_frames,
    rebuild_reference_frames,
    reference_twist_by_holonomy,
    store_tangents,
    transport_reference_frames,
    update_reference_twist,
)

TWIST_OFF = 0
TWIST_FRAMED = 1
TWIST_STRAIGHT = 2
# the axial springs: AXIAL_EXPLICIT, forces of the current state (velocity Verlet, the step bound by
# the axial waves), or AXIAL_IMPLICIT, tensions at the end of the kick (elastic.implicit_stretching_forces,
# open yarns only, no rail or image): the step is then set by the contact springs and bending
AXIAL_EXPLICIT = 0
AXIAL_IMPLICIT = 1
# the dashpots (axial, contact, drag): DASHPOTS_HALF_STEP, on the half-step velocity that the force
# evaluation sees (first order in dt), or DASHPOTS_PREDICTED, on the velocity at the end of the step
# predicted from the last forces (predict_velocities, second order; the slip keeps the half-step one)
DASHPOTS_HALF_STEP = 0
DASHPOTS_PREDICTED = 1



@njit(**PARALLEL_OPTS)
def elastic_forces_by_yarn(m, s, w, explicit_stretch, v_damp, dt):
    """Stretching and isotropic bending, yarn by yarn in parallel (the axial dashpots' loss over ``dt`` to the
    ledger: each kernel adds into its yarn's slice, as a value returned into the loop's array costs a fifth).

    A yarn's edges and hinges only touch its own nodes, so threads never write
    the same node (edges and hinges are stored yarn by yarn: see Workspace).
    """
    for y in prange(w.yarn_edges.shape[0] - 1):
        e0, e1 = w.yarn_edges[y], w.yarn_edges[y + 1]
        edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen, e0, e1)
        if explicit_stretch:
            stretching_forces(w.e, w.elen, v_damp, m.edge_a, m.edge_b, m.rest_length, m.EA, m.stretch_damping, w.force,
                              e0, e1, w.ledger[y, AXIAL_DASHPOT:AXIAL_DASHPOT + 1], dt)
        bending_forces(w.e, w.elen, m.edge_a, m.edge_b, m.hinge_e0, m.hinge_e1, m.B_over_l, w.force,
                       w.yarn_hinges[y], w.yarn_hinges[y + 1])


@njit(**PARALLEL_OPTS)
def framed_forces_by_yarn(m, s, w, explicit_stretch, v_damp, dt):
    """Stretching, and bending and twisting with material frames (framed DER), yarn by yarn in
    parallel: the frames of a yarn's edges and its hinges' forces and torques touch only its own
    nodes and edges (as :func:`elastic_forces_by_yarn`)."""
    for y in prange(w.yarn_edges.shape[0] - 1):
        e0, e1 = w.yarn_edges[y], w.yarn_edges[y + 1]
        h0, h1 = w.yarn_hinges[y], w.yarn_hinges[y + 1]
        edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen, e0, e1)
        if explicit_stretch:
            stretching_forces(w.e, w.elen, v_damp, m.edge_a, m.edge_b, m.rest_length, m.EA, m.stretch_damping, w.force,
                              e0, e1, w.ledger[y, AXIAL_DASHPOT:AXIAL_DASHPOT + 1], dt)
        transport_reference_frames(w.e, w.elen, s.tangent, s.ref_u, e0, e1)
        update_reference_twist(s.tangent, s.ref_u, m.hinge_e0, m.hinge_e1, s.ref_twist, h0, h1)
        material_frames(s.tangent, s.ref_u, s.theta, w.d1, w.d2, e0, e1)
        framed_bending_twisting_forces(
            w.e, w.elen, w.d1, w.d2, m.edge_a, m.edge_b, m.hinge_e0, m.hinge_e1,
            m.B_over_l, m.GJ_over_l, m.kappa_bar, s.ref_twist, m.twist_bar, s.theta, w.force, w.torque, h0, h1,
        )


@njit(**PARALLEL_OPTS)
def straight_twisting_forces_by_yarn(m, s, w, explicit_stretch, v_damp, dt):
    """Stretching, and isotropic bending and twisting of yarns straight at rest (TWIST_STRAIGHT), yarn by
    yarn in parallel: the reference twist by holonomy from the stored tangents with the forces and
    torques, then the new tangents stored (and the frames of the anchor edges carried:
    :func:`reference_frames_by_yarn` rebuilds the others when the state is read)."""
    for y in prange(w.yarn_edges.shape[0] - 1):
        e0, e1 = w.yarn_edges[y], w.yarn_edges[y + 1]
        h0, h1 = w.yarn_hinges[y], w.yarn_hinges[y + 1]
        edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen, e0, e1)
        if explicit_stretch:
            stretching_forces(w.e, w.elen, v_damp, m.edge_a, m.edge_b, m.rest_length, m.EA, m.stretch_damping, w.force,
                              e0, e1, w.ledger[y, AXIAL_DASHPOT:AXIAL_DASHPOT + 1], dt)
        straight_bending_twisting_forces(
            w.e, w.elen, s.tangent, m.edge_a, m.edge_b, m.hinge_e0, m.hinge_e1,
            m.B_over_l, m.GJ_over_l, s.ref_twist, m.twist_bar, s.theta, w.force, w.torque, h0, h1,
        )
        store_tangents(w.e, w.elen, s.tangent, s.ref_u, w.frame_anchor, e0, e1)


@njit(**PARALLEL_OPTS)
def reference_frames_by_yarn(m, s, w):
    """The reference frames of every edge from the anchors' and the reference twist (TWIST_STRAIGHT
    carries only the anchors' each step), yarn by yarn in parallel."""
    for y in prange(w.yarn_edges.shape[0] - 1):
        rebuild_reference_frames(s.tangent, s.ref_u, s.ref_twist, m.hinge_e0, m.hinge_e1, w.frame_anchor,
                                 w.yarn_hinges[y], w.yarn_hinges[y + 1])


@njit(**NUMBA_OPTS)
def complete_frames(m, s, w, twist):
    """Every edge's reference frame up to date: TWIST_STRAIGHT's steps carry only the anchors'
    (:func:`knitlad.engine.kernels.frames.store_tangents`), so :func:`verlet_steps`, :func:`fire_relax` and
    :func:`potential_energy` call this before they return; the other modes keep every frame."""
    if twist == TWIST_STRAIGHT:
        reference_frames_by_yarn(m, s, w)


@njit(**PARALLEL_OPTS)
def dissipative_forces_by_yarn(m, w, v_damp, ratio, decay, lead, air_density, air_viscosity, skin_friction, dt):
    """The viscoelastic branches (``ratio`` > 0, relaxing by ``decay`` = exp(-dt/tau) and ``lead`` a step) and the air
    drag (``air_density`` > 0), yarn by yarn in parallel, each one's loss over the step to the ledger
    (:mod:`knitlad.engine.kernels.dissipation`). Reads the edge vectors of the elastic pass."""
    for y in prange(w.yarn_edges.shape[0] - 1):
        e0, e1 = w.yarn_edges[y], w.yarn_edges[y + 1]
        h0, h1 = w.yarn_hinges[y], w.yarn_hinges[y + 1]
        if ratio > 0.0:
            viscoelastic_forces(w.e, w.elen, v_damp, m.edge_a, m.edge_b, m.rest_length, m.EA, m.hinge_e0, m.hinge_e1,
                                m.B_over_l, ratio, decay, lead, w.branch_ext, w.branch_kb, w.force, e0, e1, h0, h1,
                                w.ledger[y, MATERIAL:MATERIAL + 1])
        if air_density > 0.0:
            air_drag_forces(w.e, w.elen, v_damp, m.edge_a, m.edge_b, m.radius, air_density, air_viscosity,
                            skin_friction, w.force, e0, e1, dt, w.ledger[y, AIR:AIR + 1])


@njit(**NUMBA_OPTS)
def compute_forces(m, s, w, c, twist, contact, damping, dt, axial, dashpots, obstacles):
    """Total force on every node (``w.force``) and torque on every edge (``w.torque``).

    ``twist``, ``contact``, ``axial``, ``dashpots``: the modes (module docstring; with DASHPOTS_PREDICTED the
    dashpots act on ``w.v_damp``, ``w.omega_damp``, which the caller fills). ``damping``: a
    :class:`~knitlad.engine.kernels.dissipation.DampingParams` (the global drag, the material's viscoelastic
    branches, the air; ``no_damping()`` for statics). ``dt``: the step over which contact slip accumulates, the
    branches relax and the ledger counts, and with AXIAL_IMPLICIT the kick that follows (a full step:
    :func:`verlet_steps` fuses the half-kicks).
    ``obstacles``: an :class:`~knitlad.engine.kernels.obstacles.ObstacleState` (the simulation passes an empty one
    when there are none: one compiled step for both), or None.
    Every mechanism adds what it took out over ``dt`` (and the supports and obstacles the work they did) to
    ``w.ledger``. Returns False if the contact buffer overflowed (forces incomplete).
    """
    follow_images(s.x, s.v, m.image_node, m.image_master, m.image_shift)
    predicted = dashpots == DASHPOTS_PREDICTED
    v_damp = w.v_damp if predicted else s.v
    external_forces(m.f_ext, m.held, m.mass, v_damp, damping.drag, w.force)
    if damping.drag > 0.0:
        w.ledger[0, GLOBAL_DRAG] += dt * drag_dissipation(m.held, m.mass, v_damp, damping.drag)
    w.torque[:] = 0.0
    if twist and damping.spin_drag > 0.0:
        w.ledger[0, GLOBAL_DRAG] += dt * spin_drag_torques(m.theta_held, m.twist_inertia,
                                                           w.omega_damp if predicted else s.omega,
                                                           damping.spin_drag, w.torque)
    explicit = axial == AXIAL_EXPLICIT
    if twist == TWIST_FRAMED:
        framed_forces_by_yarn(m, s, w, explicit, v_damp, dt)
    elif twist:
        straight_twisting_forces_by_yarn(m, s, w, explicit, v_damp, dt)
    else:
        elastic_forces_by_yarn(m, s, w, explicit, v_damp, dt)
    if damping.branch_ratio > 0.0 or damping.air_density > 0.0:
        decay = math.exp(-dt / damping.relaxation_time)
        dissipative_forces_by_yarn(m, w, v_damp, damping.branch_ratio, decay,
                                   dt - damping.relaxation_time * (1.0 - decay), damping.air_density,
                                   damping.air_viscosity, damping.skin_friction, dt)
    if contact:
        if not refresh_contacts(s.x, m.edge_a, m.edge_b, m.edge_shift, c, s.v, c.params.lookahead_steps * dt):
            return False
        contact_forces(s.x, s.v, s.omega, twist, m.mass, m.edge_a, m.edge_b, m.edge_shift, c, dt, w.force, w.torque,
                       v_damp, w.omega_damp if predicted else s.omega, predicted, w.ledger)
    if obstacles is not None and obstacles.kind.shape[0] > 0:
        w.ledger[0, OBSTACLE_WORK] += dt * obstacle_forces(s.x, v_damp, m.mass, m.radius, m.held, obstacles, dt,
                                                           w.force)
    w.rail_reaction[:] = 0.0
    rail_forces(m.rail_node, m.rail_axis, w.force, w.rail_reaction)
    if not explicit:
        implicit_stretching_by_yarn(m, s, w, dt)  # its tensions balance every other force ...
    if m.rail_friction.shape[0] > 0:  # ... but the clips': they need the rail's whole normal reaction
        w.ledger[0, FRICTION] += rail_friction_forces(m.rail_node, m.rail_axis, m.rail_friction, m.mass, s.v, dt,
                                                      w.force, w.rail_reaction)
    if damping.supports_moving:  # every force on the held nodes is known: the supports' work
        w.ledger[0, SUPPORT_WORK] += dt * (support_power(m.held, m.v_prescribed, w.force)
                                           + rail_power(m.rail_node, m.rail_axis, s.v, w.rail_reaction))
    return True


@njit(**PARALLEL_OPTS)
def implicit_stretching_by_yarn(m, s, w, dt):
    """The axial forces at the end of the coming kick (AXIAL_IMPLICIT), yarn by yarn in parallel:
    a yarn's tridiagonal system couples only its own edges and nodes."""
    if m.rail_node.shape[0] == 0:
        for y in prange(w.yarn_edges.shape[0] - 1):
            implicit_stretching_forces(
                w.e, w.elen, s.v, m.held, m.mass, m.edge_a, m.edge_b, m.rest_length, m.EA, m.stretch_damping, dt,
                w.force, w.axial_sweep, w.yarn_edges[y], w.yarn_edges[y + 1],
                w.ledger[y, AXIAL_DASHPOT:AXIAL_DASHPOT + 1])
        return
    # nodes on rails move along them only: the solve sees their projected inverse mass, then their forces are
    # projected (what the rail takes is added to its reaction)
    rail_of_node = np.full(m.mass.shape[0], -1, dtype=np.int64)
    for r in range(m.rail_node.shape[0]):
        rail_of_node[m.rail_node[r]] = r
    for y in prange(w.yarn_edges.shape[0] - 1):
        implicit_stretching_forces(
            w.e, w.elen, s.v, m.held, m.mass, m.edge_a, m.edge_b, m.rest_length, m.EA, m.stretch_damping, dt, w.force,
            w.axial_sweep, w.yarn_edges[y], w.yarn_edges[y + 1], w.ledger[y, AXIAL_DASHPOT:AXIAL_DASHPOT + 1],
            rail_of_node, m.rail_axis)
    rail_forces(m.rail_node, m.rail_axis, w.force, w.rail_reaction)


@njit(**PARALLEL_OPTS)
def external_forces(f_ext, held, mass, v, drag, force):
    """force = f_ext - drag m v (the drag on free nodes only: on a held node it would leak into its reaction)."""
    for i in prange(force.shape[0]):
        damp = 0.0 if held[i] else drag * mass[i]
        for k in range(3):
            force[i, k] = f_ext[i, k] - damp * v[i, k]


@njit(**NUMBA_OPTS)
def follow_images(x, v, image_node, image_master, image_shift):
    """Put every periodic-image node at its master's position plus its lattice shift, with its velocity."""
    for g in range(image_node.shape[0]):
        i = image_node[g]
        m = image_master[g]
        for k in range(3):
            x[i, k] = x[m, k] + image_shift[g, k]
            v[i, k] = v[m, k]


@njit(**NUMBA_OPTS)
def rail_forces(rail_node, rail_axis, force, taken):
    """Keep only the component along its rail of the force on each rail node (the rail
    takes the rest, added to ``taken[r]``: the rail's reaction is -taken), so a node starting at rest on its
    rail moves along it."""
    for r in range(rail_node.shape[0]):
        i = rail_node[r]
        f = force[i, 0] * rail_axis[r, 0] + force[i, 1] * rail_axis[r, 1] + force[i, 2] * rail_axis[r, 2]
        for k in range(3):
            taken[r, k] += force[i, k] - f * rail_axis[r, k]
            force[i, k] = f * rail_axis[r, k]


@njit(**NUMBA_OPTS)
def rail_friction_forces(rail_node, rail_axis, rail_friction, mass, v, dt, force, taken):
    """Coulomb friction of each rail on its node (a clip on a bar), after :func:`rail_forces`; returns the energy
    it takes out over the coming kick.

    The rail presses on its node with N = |taken| (what it took of the force), so its friction F_f along the
    axis is at most mu N. The kick of ``dt`` that follows takes the half-step velocity u to
    u + dt (F_a + F_f) / m: F_f is the force that stops the node there (sticking, u' = 0) if it is within
    mu N, else mu N against that (sliding). Discrete Coulomb friction: no regularising velocity, and a
    node at rest under a pull below mu N stays at rest to round-off. The energy taken out is
    -F_f (u + u')/2 dt, what the kick takes from the kinetic energy. The rail's reaction gains -F_f.
    """
    lost = 0.0
    for r in range(rail_node.shape[0]):
        mu = rail_friction[r]
        if mu == 0.0:
            continue
        i = rail_node[r]
        ax, ay, az = rail_axis[r, 0], rail_axis[r, 1], rail_axis[r, 2]
        normal = math.sqrt(taken[r, 0] ** 2 + taken[r, 1] ** 2 + taken[r, 2] ** 2)
        along = force[i, 0] * ax + force[i, 1] * ay + force[i, 2] * az
        u = v[i, 0] * ax + v[i, 1] * ay + v[i, 2] * az
        cap = mu * normal
        f = min(max(-(mass[i] * u / dt + along), -cap), cap)
        u_next = u + dt * (along + f) / mass[i]
        lost -= f * 0.5 * (u + u_next) * dt
        force[i, 0] += f * ax
        force[i, 1] += f * ay
        force[i, 2] += f * az
        taken[r, 0] -= f * ax
        taken[r, 1] -= f * ay
        taken[r, 2] -= f * az
    return lost


@njit(**NUMBA_OPTS)
def potential_energy(m, s, w, c, twist, contact):
    """(stretching, bending, twisting, contact, external) energies [uJ] at the current state."""
    follow_images(s.x, s.v, m.image_node, m.image_master, m.image_shift)
    edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen)
    es = stretching_energy(w.elen, m.rest_length, m.EA)
    if twist == TWIST_STRAIGHT:
        reference_twist_by_holonomy(s.tangent, w.e, w.elen, m.hinge_e0, m.hinge_e1, s.ref_twist)
        store_tangents(w.e, w.elen, s.tangent, s.ref_u, w.frame_anchor)
        complete_frames(m, s, w, twist)
        eb = bending_energy(w.e, w.elen, m.hinge_e0, m.hinge_e1, m.B_over_l)
        et = twisting_energy(m.hinge_e0, m.hinge_e1, m.GJ_over_l, s.ref_twist, m.twist_bar, s.theta)
    elif twist:
        transport_reference_frames(w.e, w.elen, s.tangent, s.ref_u)
        update_reference_twist(s.tangent, s.ref_u, m.hinge_e0, m.hinge_e1, s.ref_twist)
        material_frames(s.tangent, s.ref_u, s.theta, w.d1, w.d2)
        eb, et = framed_bending_twisting_energy(
            w.e, w.elen, w.d1, w.d2, m.hinge_e0, m.hinge_e1,
            m.B_over_l, m.GJ_over_l, m.kappa_bar, s.ref_twist, m.twist_bar, s.theta,
        )
    else:
        eb = bending_energy(w.e, w.elen, m.hinge_e0, m.hinge_e1, m.B_over_l)
        et = 0.0
    ec = 0.0
    if contact:
        n = c.n_pairs[0]
        ec = contact_energy(s.x, m.edge_a, m.edge_b, m.edge_shift, c, c.pairs[:n], c.slip[:n])
    ext = 0.0
    for i in range(s.x.shape[0]):
        ext -= m.f_ext[i, 0] * s.x[i, 0] + m.f_ext[i, 1] * s.x[i, 1] + m.f_ext[i, 2] * s.x[i, 2]
    return es, eb, et, ec, ext


@njit(**NUMBA_OPTS)
def kinetic_energy(m, s):
    """(1/2) sum m v^2 + (1/2) sum I omega^2 [uJ]."""
    k = 0.0
    for i in range(s.x.shape[0]):
        k += 0.5 * m.mass[i] * (s.v[i, 0] ** 2 + s.v[i, 1] ** 2 + s.v[i, 2] ** 2)
    for j in range(s.theta.shape[0]):
        k += 0.5 * m.twist_inertia[j] * s.omega[j] ** 2
    return k


# The per-node kernels take arrays, not the model and state tuples: with parallel=True, Numba
# (0.68 here) drops writes to a named tuple's array under a branch in a prange loop, silently
# (numba/numba#5872; seen here as a wrong drift of the held nodes).
@njit(**PARALLEL_OPTS)
def kick_nodes(held, mass, force, v, half_dt):
    """v += half_dt F / m on every free node."""
    for i in prange(v.shape[0]):
        if not held[i]:
            step = half_dt / mass[i]
            v[i, 0] += force[i, 0] * step
            v[i, 1] += force[i, 1] * step
            v[i, 2] += force[i, 2] * step


@njit(**PARALLEL_OPTS)
def drift_nodes(held, v_prescribed, v, x, dt):
    """x += dt v, a held node moving at its prescribed velocity."""
    for i in prange(v.shape[0]):
        if held[i]:
            v[i, 0] = v_prescribed[i, 0]
            v[i, 1] = v_prescribed[i, 1]
            v[i, 2] = v_prescribed[i, 2]
        x[i, 0] += dt * v[i, 0]
        x[i, 1] += dt * v[i, 1]
        x[i, 2] += dt * v[i, 2]


@njit(**PARALLEL_OPTS)
def kick_drift_nodes(held, mass, force, v_prescribed, v, x, dt):
    """One step's closing kick and the next one's drift in one pass (:func:`kick_nodes` with half_dt = dt, then
    :func:`drift_nodes`): the same operations on each node in the same order, so the same bits, with one
    parallel region and one sweep of the node arrays fewer per step."""
    for i in prange(v.shape[0]):
        if held[i]:
            v[i, 0] = v_prescribed[i, 0]
            v[i, 1] = v_prescribed[i, 1]
            v[i, 2] = v_prescribed[i, 2]
        else:
            step = dt / mass[i]
            v[i, 0] += force[i, 0] * step
            v[i, 1] += force[i, 1] * step
            v[i, 2] += force[i, 2] * step
        x[i, 0] += dt * v[i, 0]
        x[i, 1] += dt * v[i, 1]
        x[i, 2] += dt * v[i, 2]


@njit(**PARALLEL_OPTS)
def kick_drift_edges(theta_held, twist_inertia, torque, omega, theta, dt):
    """:func:`kick_edges` with half_dt = dt, then :func:`drift_edges`, in one pass (as :func:`kick_drift_nodes`)."""
    for j in prange(omega.shape[0]):
        if theta_held[j]:
            omega[j] = 0.0
        else:
            omega[j] += dt * torque[j] / twist_inertia[j]
        theta[j] += dt * omega[j]


@njit(**PARALLEL_OPTS)
def kick_edges(theta_held, twist_inertia, torque, omega, half_dt):
    """omega += half_dt torque / I on every edge free to twist."""
    for j in prange(omega.shape[0]):
        if not theta_held[j]:
            omega[j] += half_dt * torque[j] / twist_inertia[j]


@njit(**PARALLEL_OPTS)
def drift_edges(theta_held, omega, theta, dt):
    """theta += dt omega, a clamped edge held at zero spin."""
    for j in prange(omega.shape[0]):
        if theta_held[j]:
            omega[j] = 0.0
        theta[j] += dt * omega[j]


@njit(**PARALLEL_OPTS)
def predict_velocities(held, mass, force, v, half_dt, v_damp):
    """v_damp = v + (dt/2) F / m: the velocity at the end of a step from the half-step one and the
    last forces, O(dt^2) (their own change over the step is the error); a held node keeps its own."""
    for i in prange(v.shape[0]):
        rate = 0.0 if held[i] else half_dt / mass[i]
        for k in range(3):
            v_damp[i, k] = v[i, k] + rate * force[i, k]


@njit(**PARALLEL_OPTS)
def predict_spins(theta_held, twist_inertia, torque, omega, half_dt, omega_damp):
    """omega_damp = omega + (dt/2) torque / I, as :func:`predict_velocities`."""
    for j in prange(omega.shape[0]):
        omega_damp[j] = 0.0 if theta_held[j] else omega[j] + half_dt * torque[j] / twist_inertia[j]


@njit(**NUMBA_OPTS)
def half_kick(m, s, w, half_dt, twist):
    kick_nodes(m.held, m.mass, w.force, s.v, half_dt)
    if twist:
        kick_edges(m.theta_held, m.twist_inertia, w.torque, s.omega, half_dt)


@njit(**NUMBA_OPTS)
def _drift(m, s, dt, twist):
    drift_nodes(m.held, m.v_prescribed, s.v, s.x, dt)
    if twist:
        drift_edges(m.theta_held, s.omega, s.theta, dt)


@njit(**NUMBA_OPTS)
def verlet_steps(m, s, w, c, dt, n_steps, twist, contact, damping, axial, dashpots, obstacles):
    """Advance ``n_steps`` of velocity Verlet (kick-drift-kick); return the steps completed.

    Expects ``w.force``/``w.torque`` to hold the forces of the current state
    (call :func:`compute_forces` once before the first call). Held nodes move
    with their prescribed velocity; the force left on them in ``w.force`` is
    minus the reaction of the support. If the contact buffer overflows in step
    k, returns k with that step drifted but not closed: grow the buffer, call
    :func:`compute_forces` and ``half_kick(dt/2)`` to finish it. With ``axial`` AXIAL_IMPLICIT the
    forces of each evaluation hold the tensions for a kick of dt from the half-step velocity it saw,
    which the fused half-kicks give (two halves of dt around a call boundary add up to it). With
    ``dashpots`` DASHPOTS_PREDICTED each step predicts ``w.v_damp``, ``w.omega_damp`` before its forces.
    """
    # the closing half-kick of one step and the opening one of the next are fused, and with the next drift
    half_kick(m, s, w, 0.5 * dt, twist)
    _drift(m, s, dt, twist)
    for step in range(n_steps):
        if obstacles is not None:
            advance_obstacles(obstacles, dt)
        if dashpots == DASHPOTS_PREDICTED:  # w.force still holds the last step's forces
            predict_velocities(m.held, m.mass, w.force, s.v, 0.5 * dt, w.v_damp)
            if twist:
                predict_spins(m.theta_held, m.twist_inertia, w.torque, s.omega, 0.5 * dt, w.omega_damp)
        if not compute_forces(m, s, w, c, twist, contact, damping, dt, axial, dashpots, obstacles):
            complete_frames(m, s, w, twist)
            return step
        if step < n_steps - 1:
            kick_drift_nodes(m.held, m.mass, w.force, m.v_prescribed, s.v, s.x, dt)
            if twist:
                kick_drift_edges(m.theta_held, m.twist_inertia, w.torque, s.omega, s.theta, dt)
        else:
            half_kick(m, s, w, 0.5 * dt, twist)
    complete_frames(m, s, w, twist)
    return n_steps


@njit(**NUMBA_OPTS)
def max_free_force(m, w, twist):
    """(max |F| over free nodes [mN], max |torque| over free edges [mN mm])."""
    fmax = 0.0
    for i in range(w.force.shape[0]):
        if not m.held[i]:
            f = math.sqrt(w.force[i, 0] ** 2 + w.force[i, 1] ** 2 + w.force[i, 2] ** 2)
            if f > fmax:
                fmax = f
    tmax = 0.0
    if twist:
        for j in range(w.torque.shape[0]):
            if not m.theta_held[j] and abs(w.torque[j]) > tmax:
                tmax = abs(w.torque[j])
    return fmax, tmax


@njit(**NUMBA_OPTS)
def fire_relax(m, s, w, c, dt_start, dt_max, max_steps, force_tol, torque_tol, twist, contact, obstacles):
    """FIRE energy minimisation (Bitzek et al. 2006, with the FIRE 2.0 back-step of
    Guenole et al. 2020) over free node positions and free twist angles.

    Held nodes stay where they are. Stops when max |F| <= force_tol and
    max |torque| <= torque_tol. Returns (steps taken, max |F|, max |torque|);
    steps = -1 if the contact buffer overflowed (grow it and call again).
    """
    # the modes as int64, not literals, so that the dynamics' specialisation of compute_forces serves (kernels/options.py)
    statics_axial, statics_dashpots = np.int64(AXIAL_EXPLICIT), np.int64(DASHPOTS_HALF_STEP)
    alpha0 = 0.1
    alpha = alpha0
    n_delay = 5
    f_inc = 1.1
    f_dec = 0.5
    f_alpha = 0.99
    dt = dt_start
    dt_min = 0.02 * dt_start
    n_pos = 0
    for i in range(s.x.shape[0]):
        for k in range(3):
            s.v[i, k] = 0.0
    s.omega[:] = 0.0
    if not compute_forces(m, s, w, c, twist, contact, no_damping(), dt, statics_axial, statics_dashpots, obstacles):
        return -1, 0.0, 0.0
    fmax, tmax = max_free_force(m, w, twist)
    step = 0
    while step < max_steps and (fmax > force_tol or tmax > torque_tol):
        step += 1
        power = 0.0
        for i in range(s.x.shape[0]):
            if not m.held[i]:
                power += w.force[i, 0] * s.v[i, 0] + w.force[i, 1] * s.v[i, 1] + w.force[i, 2] * s.v[i, 2]
        if twist:
            for j in range(s.theta.shape[0]):
                if not m.theta_held[j]:
                    power += w.torque[j] * s.omega[j]
        if power > 0.0:
            n_pos += 1
            if n_pos > n_delay:
                dt = min(dt * f_inc, dt_max)
                alpha *= f_alpha
        else:
            n_pos = 0
            dt = max(dt * f_dec, dt_min)
            alpha = alpha0
            for i in range(s.x.shape[0]):
                if not m.held[i]:
                    for k in range(3):
                        s.x[i, k] -= 0.5 * dt * s.v[i, k]
                        s.v[i, k] = 0.0
            if twist:
                for j in range(s.theta.shape[0]):
                    s.theta[j] -= 0.5 * dt * s.omega[j]
                    s.omega[j] = 0.0
        # semi-implicit Euler with FIRE mixing, positions and twist mixed separately
        vv = 0.0
        ff = 0.0
        for i in range(s.x.shape[0]):
            if not m.held[i]:
                for k in range(3):
                    s.v[i, k] += dt * w.force[i, k] / m.mass[i]
                    vv += s.v[i, k] ** 2
                    ff += w.force[i, k] ** 2
        scale = alpha * math.sqrt(vv / ff) if ff > 0.0 else 0.0
        for i in range(s.x.shape[0]):
            if not m.held[i]:
                for k in range(3):
                    s.v[i, k] = (1.0 - alpha) * s.v[i, k] + scale * w.force[i, k]
                    s.x[i, k] += dt * s.v[i, k]
        if twist:
            oo = 0.0
            tt = 0.0
            for j in range(s.theta.shape[0]):
                if not m.theta_held[j]:
                    s.omega[j] += dt * w.torque[j] / m.twist_inertia[j]
                    oo += s.omega[j] ** 2
                    tt += w.torque[j] ** 2
            tscale = alpha * math.sqrt(oo / tt) if tt > 0.0 else 0.0
            for j in range(s.theta.shape[0]):
                if not m.theta_held[j]:
                    s.omega[j] = (1.0 - alpha) * s.omega[j] + tscale * w.torque[j]
                    s.theta[j] += dt * s.omega[j]
        if not compute_forces(m, s, w, c, twist, contact, no_damping(), dt, statics_axial, statics_dashpots,
                              obstacles):
            return -1, 0.0, 0.0
        fmax, tmax = max_free_force(m, w, twist)
    for i in range(s.x.shape[0]):
        for k in range(3):
            s.v[i, k] = 0.0
    s.omega[:] = 0.0
    complete_frames(m, s, w, twist)
    return step, fmax, tmax


@njit(**NUMBA_OPTS)
def first_bad_node(x, v, max_speed):
    """Index of the first node with a non-finite position/velocity or a speed
    above ``max_speed``; -1 if all are sane. (Kinds: 1 non-finite, 2 too fast.)"""
    vmax2 = max_speed * max_speed
    for i in range(x.shape[0]):
        for c in range(3):
            if not (math.isfinite(x[i, c]) and math.isfinite(v[i, c])):
                return i, 1
        if v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2 > vmax2:
            return i, 2
    return -1, 0
