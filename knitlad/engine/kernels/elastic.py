"""Elastic forces of discrete elastic rods (DER).

References: Bergou et al. 2008, "Discrete Elastic Rods" (DER08); Bergou et al.
2010, "Discrete Viscous Threads" (DVT10). Notation of ``shared/notes``:
edge e^k, rest length |e_bar^k|, Voronoi length l_h = (|e_bar^{h-1}|+|e_bar^h|)/2,
curvature binormal (kb)_h = 2 e^{h-1} x e^h / (|e^{h-1}||e^h| + e^{h-1}.e^h).

Every ``*_forces`` kernel *adds* into its output, so a caller zeroes once and
sums all contributions.
"""

import math

from numba import njit

from knitlad.engine.kernels.frames import holonomy_twist_change
from knitlad.engine.kernels.options import NUMBA_OPTS
from knitlad.engine.kernels.vec import cross, dot



@njit(**NUMBA_OPTS)
def edge_vectors(x, edge_a, edge_b, edge_shift, e, elen, first=0, last=-1):
    """e^k = x_b + shift - x_a and |e^k| into ``e`` (ne, 3) and ``elen`` (ne,), for edges [first, last)."""
    if last < 0:
        last = edge_a.shape[0]
    for k in range(first, last):
        a = edge_a[k]
        b = edge_b[k]
        ex = x[b, 0] + edge_shift[k, 0] - x[a, 0]
        ey = x[b, 1] + edge_shift[k, 1] - x[a, 1]
        ez = x[b, 2] + edge_shift[k, 2] - x[a, 2]
        e[k, 0] = ex
        e[k, 1] = ey
        e[k, 2] = ez
        elen[k] = math.sqrt(ex * ex + ey * ey + ez * ez)


@njit(inline="always", **NUMBA_OPTS)
def add_hinge_forces(F, prev, centre, nxt, gax, gay, gaz, gbx, gby, gbz):
    """Forces of a hinge energy E(e0, e1), e0 = x_c - x_p, e1 = x_n - x_c, from g_a = dE/de0, g_b = dE/de1."""
    F[prev, 0] += gax
    F[prev, 1] += gay
    F[prev, 2] += gaz
    F[centre, 0] += gbx - gax
    F[centre, 1] += gby - gay
    F[centre, 2] += gbz - gaz
    F[nxt, 0] -= gbx
    F[nxt, 1] -= gby
    F[nxt, 2] -= gbz


@njit(**NUMBA_OPTS)
def stretching_forces(e, elen, v, edge_a, edge_b, rest_length, EA, damping, F, first=0, last=-1, loss=None, dt=0.0):
    """Axial spring plus internal dashpot on every edge.

    Energy E_s = EA (|e| - |e_bar|)^2 / (2 |e_bar|); tension
    T = EA (|e|/|e_bar| - 1) + c d|e|/dt, with c the edge's dashpot coefficient
    (Kelvin-Voigt: it damps axial vibration, never rigid motion or bending).
    Edges [first, last) (all by default). With ``loss`` (a slice of the ledger), adds to ``loss[0]`` what the
    dashpots took out over ``dt``, sum c (d|e|/dt)^2 dt [uJ].
    """
    if last < 0:
        last = edge_a.shape[0]
    power = 0.0
    for k in range(first, last):
        a = edge_a[k]
        b = edge_b[k]
        inv = 1.0 / elen[k]
        tx = e[k, 0] * inv
        ty = e[k, 1] * inv
        tz = e[k, 2] * inv
        stretch_rate = (v[b, 0] - v[a, 0]) * tx + (v[b, 1] - v[a, 1]) * ty + (v[b, 2] - v[a, 2]) * tz
        tension = EA[k] * (elen[k] / rest_length[k] - 1.0) + damping[k] * stretch_rate
        F[a, 0] += tension * tx
        F[a, 1] += tension * ty
        F[a, 2] += tension * tz
        F[b, 0] -= tension * tx
        F[b, 1] -= tension * ty
        F[b, 2] -= tension * tz
        power += damping[k] * stretch_rate * stretch_rate
    if loss is not None:
        loss[0] += dt * power


@njit(inline="always", **NUMBA_OPTS)
def rail_share(rail, rail_axis, ux, uy, uz, wx, wy, wz):
    """u . P w, P the projector of a node's motion: a a^T on rail ``rail`` of axis a, the identity off rails (-1)."""
    if rail < 0:
        return ux * wx + uy * wy + uz * wz
    ax, ay, az = rail_axis[rail, 0], rail_axis[rail, 1], rail_axis[rail, 2]
    return (ux * ax + uy * ay + uz * az) * (wx * ax + wy * ay + wz * az)


@njit(**NUMBA_OPTS)
def implicit_stretching_forces(e, elen, v, held, mass, edge_a, edge_b, rest_length, EA, damping, dt, F, sweep,
                               first, last, loss=None, rail_of_node=None, rail_axis=None):
    """Axial springs and dashpots of edges [first, last) at the end of the step (linearly implicit).

    The tension of :func:`stretching_forces`, T = g/eps + c dg/dt with g = |e| - |e_bar| and the
    compliance eps = |e_bar|/EA, is taken at the end of the kick v+ = v + dt M^-1 (F - G^T T)
    that follows (G: the rows dg/dx, -t at node a, +t at b), with g linearised along the current
    tangents, g+ = g + dt t.(v+_b - v+_a): the backward-Euler step of a compliant constraint
    (Servin, Lacoursiere and Melin 2006, "Interactive simulation of elastic deformable
    materials", with the regularisation set by the material). With beta = dt (dt/eps + c):

        (G M^-1 G^T + 1/beta) T = g/(eps beta) + G v/dt + G M^-1 F

    where G v = t.(v_b - v_a) is the stretch rate and F the other forces. G M^-1 G^T is
    tridiagonal along a chain of edges (diagonal 1/m_a + 1/m_b, t_k.t_k+1/m at the shared node,
    1/m = 0 on held nodes), solved by the Thomas algorithm in ``sweep`` (ne, 4: its two coefficients, and the
    stretch rate and elastic tension the returned power needs). A static state
    keeps the explicit tension T = g/eps exactly; the axial waves, which the laddering does not
    need, lose their stability limit and are damped (without a dashpot, by 1/sqrt(1 + (omega dt)^2)
    per step).
    Consecutive edges couple where they share a node (edge_b[k] == edge_a[k + 1]); a ring's
    closing node is not coupled, so the caller keeps rings explicit. Adds T t to F[a], -T t to F[b].
    With ``loss``, adds to ``loss[0]`` the energy taken out over dt by what is not the elastic tension,
    sum (T - EA g/|e_bar|) dg/dt dt at the half-step velocity [uJ]: the dashpot and the scheme's own damping
    of the axial waves (a caller's slice of the ledger: a value returned into a parallel loop's array costs
    the solve a fifth).
    With ``rail_of_node`` (n,: the row of ``rail_axis`` of each node on a rail, -1 elsewhere), a node on a rail of
    axis a moves only along it: its inverse mass is (a a^T)/m, so it enters the diagonal as (t.a)^2/m and the
    coupling as (t_k.a)(a.t_k+1)/m; the caller projects its forces onto the rail after the solve.
    """
    if last <= first:
        return
    inv_dt = 1.0 / dt
    couple = 0.0  # G_k-1 M^-1 G_k^T, the coupling of edge k to the edge before it
    previous_c = 0.0  # the forward sweep's last coefficients
    previous_d = 0.0
    inv_a = 0.0 if held[edge_a[first]] else 1.0 / mass[edge_a[first]]
    inv_l = 1.0 / elen[first]
    for k in range(first, last):
        a = edge_a[k]
        b = edge_b[k]
        if k > first and a != edge_b[k - 1]:  # a new chain: its first node's inverse mass
            inv_a = 0.0 if held[a] else 1.0 / mass[a]
        inv_b = 0.0 if held[b] else 1.0 / mass[b]
        tx, ty, tz = e[k, 0] * inv_l, e[k, 1] * inv_l, e[k, 2] * inv_l
        # 1/beta = rest r and 1/(eps beta) = EA r, r = 1 / (dt (dt EA + c rest)): one division
        r = 1.0 / (dt * (dt * EA[k] + damping[k] * rest_length[k]))
        inv_beta = rest_length[k] * r
        rate = (v[b, 0] - v[a, 0]) * tx + (v[b, 1] - v[a, 1]) * ty + (v[b, 2] - v[a, 2]) * tz
        accel = ((inv_b * F[b, 0] - inv_a * F[a, 0]) * tx + (inv_b * F[b, 1] - inv_a * F[a, 1]) * ty
                 + (inv_b * F[b, 2] - inv_a * F[a, 2]) * tz)
        rhs = (elen[k] - rest_length[k]) * EA[k] * r + rate * inv_dt + accel
        if rail_of_node is None:
            inv_denom = 1.0 / (inv_a + inv_b + inv_beta - couple * previous_c)
        else:
            inv_denom = 1.0 / (inv_a * rail_share(rail_of_node[a], rail_axis, tx, ty, tz, tx, ty, tz)
                               + inv_b * rail_share(rail_of_node[b], rail_axis, tx, ty, tz, tx, ty, tz)
                               + inv_beta - couple * previous_c)
        # the coupling to the next edge, through node b
        nxt = 0.0
        inv_l_next = 0.0
        if k + 1 < last:
            inv_l_next = 1.0 / elen[k + 1]
            if edge_a[k + 1] == b:
                if rail_of_node is None:
                    nxt = -inv_b * (tx * e[k + 1, 0] + ty * e[k + 1, 1] + tz * e[k + 1, 2]) * inv_l_next
                else:
                    nxt = -inv_b * rail_share(rail_of_node[b], rail_axis, tx, ty, tz, e[k + 1, 0], e[k + 1, 1],
                                              e[k + 1, 2]) * inv_l_next
        previous_c = nxt * inv_denom  # kept in registers: the recurrence is the kernel's critical path
        previous_d = (rhs - couple * previous_d) * inv_denom
        sweep[k, 0] = previous_c
        sweep[k, 1] = previous_d
        sweep[k, 2] = rate  # for the ledger: the stretch rate and the elastic tension
        sweep[k, 3] = (elen[k] - rest_length[k]) * EA[k] / rest_length[k]
        couple = nxt
        inv_a = inv_b
        inv_l = inv_l_next
    tension = 0.0
    power = 0.0
    for k in range(last - 1, first - 1, -1):
        tension = sweep[k, 1] - sweep[k, 0] * tension  # sweep[k, 0] is 0 at a chain's last edge
        a = edge_a[k]
        b = edge_b[k]
        scale = tension / elen[k]
        F[a, 0] += scale * e[k, 0]
        F[a, 1] += scale * e[k, 1]
        F[a, 2] += scale * e[k, 2]
        F[b, 0] -= scale * e[k, 0]
        F[b, 1] -= scale * e[k, 1]
        F[b, 2] -= scale * e[k, 2]
        power += (tension - sweep[k, 3]) * sweep[k, 2]
    if loss is not None:
        loss[0] += dt * power


@njit(**NUMBA_OPTS)
def stretching_energy(elen, rest_length, EA):
    """E_s = sum_k EA (|e| - |e_bar|)^2 / (2 |e_bar|)."""
    total = 0.0
    for k in range(elen.shape[0]):
        s = elen[k] - rest_length[k]
        total += 0.5 * EA[k] * s * s / rest_length[k]
    return total


@njit(inline="always", **NUMBA_OPTS)
def isotropic_bending_gradient(ax, ay, az, bx, by, bz, la, lb, s):
    """kb and (dE/da, dE/db) of E = s |kb|^2 / 2 at the hinge of edges a, b (see :func:`bending_forces`)."""
    inv_D = 1.0 / (la * lb + dot(ax, ay, az, bx, by, bz))
    cx, cy, cz = cross(ax, ay, az, bx, by, bz)
    kbx, kby, kbz = 2.0 * cx * inv_D, 2.0 * cy * inv_D, 2.0 * cz * inv_D
    rx, ry, rz = s * kbx, s * kby, s * kbz
    kr = dot(kbx, kby, kbz, rx, ry, rz)
    brx, bry, brz = cross(bx, by, bz, rx, ry, rz)
    arx, ary, arz = cross(ax, ay, az, rx, ry, rz)
    fa = lb / la
    fb = la / lb
    gax = (2.0 * brx - kr * (fa * ax + bx)) * inv_D
    gay = (2.0 * bry - kr * (fa * ay + by)) * inv_D
    gaz = (2.0 * brz - kr * (fa * az + bz)) * inv_D
    gbx = (-2.0 * arx - kr * (fb * bx + ax)) * inv_D
    gby = (-2.0 * ary - kr * (fb * by + ay)) * inv_D
    gbz = (-2.0 * arz - kr * (fb * bz + az)) * inv_D
    return kbx, kby, kbz, gax, gay, gaz, gbx, gby, gbz


@njit(**NUMBA_OPTS)
def bending_forces(e, elen, edge_a, edge_b, hinge_e0, hinge_e1, B_over_l, F, first=0, last=-1):
    """Isotropic DER bending of a rod straight at rest (no material frame).

    E_b = sum_h B |kb_h|^2 / (2 l_h), DER08 eq. for an isotropic rod with zero
    natural curvature. With a = e^{h-1}, b = e^h, D = |a||b| + a.b and
    r = (B/l) kb, the exact gradients are
        dE/da = (2 b x r - (kb.r)(|b| a/|a| + b)) / D
        dE/db = (-2 a x r - (kb.r)(|a| b/|b| + a)) / D.
    Hinges [first, last) (all by default).
    """
    if last < 0:
        last = hinge_e0.shape[0]
    for h in range(first, last):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        _, _, _, gax, gay, gaz, gbx, gby, gbz = isotropic_bending_gradient(
            e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2], elen[k0], elen[k1], B_over_l[h])
        add_hinge_forces(F, edge_a[k0], edge_b[k0], edge_b[k1], gax, gay, gaz, gbx, gby, gbz)


@njit(**NUMBA_OPTS)
def straight_bending_twisting_forces(
    e, elen, tangent, edge_a, edge_b, hinge_e0, hinge_e1, B_over_l, GJ_over_l, ref_twist, twist_bar, theta, F, torque,
    first=0, last=-1,
):
    """Isotropic bending and twisting of a rod straight at rest, without material frames.

    E = sum_h B |kb_h|^2 / (2 l_h) + GJ (m_h - m_bar_h)^2 / (2 l_h), m_h = theta^h - theta^{h-1} + ref_twist_h
    (DER08 sec. 4.2: an isotropic rod straight at rest bends as |kb|^2, whatever its twist). Each hinge's
    reference twist is first advanced by the holonomy of its tangents' motion from ``tangent`` (the
    stored ones, not changed here) to e/|e| (:func:`knitlad.engine.kernels.frames.reference_twist_by_holonomy`,
    in the same pass over the hinges). The bending gradient is :func:`bending_forces`'; the twist's is
    d m/d e^{h-1} = kb/(2|e^{h-1}|), d m/d e^h = kb/(2|e^h|), d m/d theta^h = -d m/d theta^{h-1} = 1
    (DER08 sec. 7). Forces go to F (n, 3), torques about the edge tangents to ``torque`` (ne,). Hinges
    [first, last).
    """
    if last < 0:
        last = hinge_e0.shape[0]
    for h in range(first, last):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        la = elen[k0]
        lb = elen[k1]
        i0 = 1.0 / la
        i1 = 1.0 / lb
        ref_twist[h] += holonomy_twist_change(
            tangent[k0, 0], tangent[k0, 1], tangent[k0, 2], tangent[k1, 0], tangent[k1, 1], tangent[k1, 2],
            e[k0, 0] * i0, e[k0, 1] * i0, e[k0, 2] * i0, e[k1, 0] * i1, e[k1, 1] * i1, e[k1, 2] * i1)
        kbx, kby, kbz, gax, gay, gaz, gbx, gby, gbz = isotropic_bending_gradient(
            e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2], la, lb, B_over_l[h])
        gm = GJ_over_l[h] * (theta[k1] - theta[k0] + ref_twist[h] - twist_bar[h])
        ga = 0.5 * gm / la
        gb = 0.5 * gm / lb
        add_hinge_forces(F, edge_a[k0], edge_b[k0], edge_b[k1], gax + ga * kbx, gay + ga * kby, gaz + ga * kbz,
                          gbx + gb * kbx, gby + gb * kby, gbz + gb * kbz)
        torque[k0] += gm
        torque[k1] -= gm


@njit(**NUMBA_OPTS)
def bending_energy(e, elen, hinge_e0, hinge_e1, B_over_l):
    """E_b = sum_h B |kb_h|^2 / (2 l_h) (rod straight at rest)."""
    total = 0.0
    for h in range(hinge_e0.shape[0]):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        D = elen[k0] * elen[k1] + dot(e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2])
        cx, cy, cz = cross(e[k0, 0], e[k0, 1], e[k0, 2], e[k1, 0], e[k1, 1], e[k1, 2])
        kb2 = 4.0 * (cx * cx + cy * cy + cz * cz) / (D * D)
        total += 0.5 * B_over_l[h] * kb2
    return total


@njit(**NUMBA_OPTS)
def twisting_energy(hinge_e0, hinge_e1, GJ_over_l, ref_twist, twist_bar, theta):
    """E_t = sum_h GJ (m_h - m_bar_h)^2 / (2 l_h), m_h = theta^h - theta^{h-1} + ref_twist_h."""
    total = 0.0
    for h in range(hinge_e0.shape[0]):
        m = theta[hinge_e1[h]] - theta[hinge_e0[h]] + ref_twist[h] - twist_bar[h]
        total += 0.5 * GJ_over_l[h] * m * m
    return total


@njit(**NUMBA_OPTS)
def _hinge_tangents(e, elen, k0, k1):
    """Unit tangents t^{h-1}, t^h, chi = 1 + t^{h-1}.t^h and kb = 2 t^{h-1} x t^h / chi at the hinge of edges k0, k1."""
    i0 = 1.0 / elen[k0]
    i1 = 1.0 / elen[k1]
    t0x, t0y, t0z = e[k0, 0] * i0, e[k0, 1] * i0, e[k0, 2] * i0
    t1x, t1y, t1z = e[k1, 0] * i1, e[k1, 1] * i1, e[k1, 2] * i1
    chi = 1.0 + dot(t0x, t0y, t0z, t1x, t1y, t1z)
    cx, cy, cz = cross(t0x, t0y, t0z, t1x, t1y, t1z)
    return t0x, t0y, t0z, t1x, t1y, t1z, chi, 2.0 * cx / chi, 2.0 * cy / chi, 2.0 * cz / chi


@njit(**NUMBA_OPTS)
def _material_curvature(kbx, kby, kbz, d1, d2, k0, k1):
    """(kappa_1, kappa_2) = (kb.(d2^{h-1} + d2^h)/2, -kb.(d1^{h-1} + d1^h)/2) (DER08 sec. 4.2)."""
    kap1 = 0.5 * dot(kbx, kby, kbz, d2[k0, 0] + d2[k1, 0], d2[k0, 1] + d2[k1, 1], d2[k0, 2] + d2[k1, 2])
    kap2 = -0.5 * dot(kbx, kby, kbz, d1[k0, 0] + d1[k1, 0], d1[k0, 1] + d1[k1, 1], d1[k0, 2] + d1[k1, 2])
    return kap1, kap2


@njit(**NUMBA_OPTS)
def _hinge_material_curvature(e, elen, d1, d2, k0, k1):
    """(kappa_1, kappa_2) at the hinge between edges k0 and k1."""
    _, _, _, _, _, _, _, kbx, kby, kbz = _hinge_tangents(e, elen, k0, k1)
    return _material_curvature(kbx, kby, kbz, d1, d2, k0, k1)


@njit(**NUMBA_OPTS)
def framed_bending_twisting_forces(
    e, elen, d1, d2, edge_a, edge_b, hinge_e0, hinge_e1,
    B_over_l, GJ_over_l, kappa_bar, ref_twist, twist_bar, theta, F, torque, first=0, last=-1,
):
    """DER bending with natural curvature, and twisting, with material frames.

    E_b = sum_h B/(2 l_h) [(kappa_1 - kappa_bar_1)^2 + (kappa_2 - kappa_bar_2)^2]
    E_t = sum_h GJ/(2 l_h) (m_h - m_bar_h)^2,  m_h = theta^h - theta^{h-1} + ref_twist_h.
    Gradients (DER08 sec. 7; derived again in docs): with t~ = (t^{h-1}+t^h)/chi,
    d~_j = (d_j^{h-1} + d_j^h)/chi,
        d kappa_1/d e^{h-1} = (-kappa_1 t~ + t^h x d~_2)/|e^{h-1}|
        d kappa_1/d e^h     = (-kappa_1 t~ - t^{h-1} x d~_2)/|e^h|
        d kappa_2/d e^{h-1} = (-kappa_2 t~ - t^h x d~_1)/|e^{h-1}|
        d kappa_2/d e^h     = (-kappa_2 t~ + t^{h-1} x d~_1)/|e^h|
        d kappa_1/d theta^j = -kb.d1^j/2,  d kappa_2/d theta^j = -kb.d2^j/2
        d m/d e^{h-1} = kb/(2|e^{h-1}|),  d m/d e^h = kb/(2|e^h|).
    Forces go to F (n, 3), torques about the edge tangents to ``torque`` (ne,). Hinges [first, last).
    """
    if last < 0:
        last = hinge_e0.shape[0]
    for h in range(first, last):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        t0x, t0y, t0z, t1x, t1y, t1z, chi, kbx, kby, kbz = _hinge_tangents(e, elen, k0, k1)
        kap1, kap2 = _material_curvature(kbx, kby, kbz, d1, d2, k0, k1)
        ttx, tty, ttz = (t0x + t1x) / chi, (t0y + t1y) / chi, (t0z + t1z) / chi
        a1x, a1y, a1z = (d1[k0, 0] + d1[k1, 0]) / chi, (d1[k0, 1] + d1[k1, 1]) / chi, (d1[k0, 2] + d1[k1, 2]) / chi
        a2x, a2y, a2z = (d2[k0, 0] + d2[k1, 0]) / chi, (d2[k0, 1] + d2[k1, 1]) / chi, (d2[k0, 2] + d2[k1, 2]) / chi
        # generalised forces dE/dkappa_j and dE/dm
        g1 = B_over_l[h] * (kap1 - kappa_bar[h, 0])
        g2 = B_over_l[h] * (kap2 - kappa_bar[h, 1])
        gm = GJ_over_l[h] * (theta[k1] - theta[k0] + ref_twist[h] - twist_bar[h])
        i0 = 1.0 / elen[k0]
        i1 = 1.0 / elen[k1]
        c1x, c1y, c1z = cross(t1x, t1y, t1z, a2x, a2y, a2z)  # t^h x d~2
        c2x, c2y, c2z = cross(t1x, t1y, t1z, a1x, a1y, a1z)  # t^h x d~1
        c3x, c3y, c3z = cross(t0x, t0y, t0z, a2x, a2y, a2z)  # t^{h-1} x d~2
        c4x, c4y, c4z = cross(t0x, t0y, t0z, a1x, a1y, a1z)  # t^{h-1} x d~1
        # dE/de^{h-1}
        gax = i0 * (g1 * (-kap1 * ttx + c1x) + g2 * (-kap2 * ttx - c2x) + 0.5 * gm * kbx)
        gay = i0 * (g1 * (-kap1 * tty + c1y) + g2 * (-kap2 * tty - c2y) + 0.5 * gm * kby)
        gaz = i0 * (g1 * (-kap1 * ttz + c1z) + g2 * (-kap2 * ttz - c2z) + 0.5 * gm * kbz)
        # dE/de^h
        gbx = i1 * (g1 * (-kap1 * ttx - c3x) + g2 * (-kap2 * ttx + c4x) + 0.5 * gm * kbx)
        gby = i1 * (g1 * (-kap1 * tty - c3y) + g2 * (-kap2 * tty + c4y) + 0.5 * gm * kby)
        gbz = i1 * (g1 * (-kap1 * ttz - c3z) + g2 * (-kap2 * ttz + c4z) + 0.5 * gm * kbz)
        add_hinge_forces(F, edge_a[k0], edge_b[k0], edge_b[k1], gax, gay, gaz, gbx, gby, gbz)
        # torques -dE/dtheta
        kd1_0 = dot(kbx, kby, kbz, d1[k0, 0], d1[k0, 1], d1[k0, 2])
        kd2_0 = dot(kbx, kby, kbz, d2[k0, 0], d2[k0, 1], d2[k0, 2])
        kd1_1 = dot(kbx, kby, kbz, d1[k1, 0], d1[k1, 1], d1[k1, 2])
        kd2_1 = dot(kbx, kby, kbz, d2[k1, 0], d2[k1, 1], d2[k1, 2])
        torque[k0] -= -0.5 * (g1 * kd1_0 + g2 * kd2_0) - gm
        torque[k1] -= -0.5 * (g1 * kd1_1 + g2 * kd2_1) + gm


@njit(**NUMBA_OPTS)
def framed_bending_twisting_energy(
    e, elen, d1, d2, hinge_e0, hinge_e1, B_over_l, GJ_over_l, kappa_bar, ref_twist, twist_bar, theta
):
    """(E_b, E_t) of :func:`framed_bending_twisting_forces` (E_t: :func:`twisting_energy`)."""
    eb = 0.0
    for h in range(hinge_e0.shape[0]):
        kap1, kap2 = _hinge_material_curvature(e, elen, d1, d2, hinge_e0[h], hinge_e1[h])
        dk1 = kap1 - kappa_bar[h, 0]
        dk2 = kap2 - kappa_bar[h, 1]
        eb += 0.5 * B_over_l[h] * (dk1 * dk1 + dk2 * dk2)
    return eb, twisting_energy(hinge_e0, hinge_e1, GJ_over_l, ref_twist, twist_bar, theta)


@njit(**NUMBA_OPTS)
def material_curvatures(e, elen, d1, d2, hinge_e0, hinge_e1, out):
    """(kappa_1, kappa_2) per hinge into ``out`` (nh, 2): used to set a rest shape."""
    for h in range(hinge_e0.shape[0]):
        out[h, 0], out[h, 1] = _hinge_material_curvature(e, elen, d1, d2, hinge_e0[h], hinge_e1[h])
