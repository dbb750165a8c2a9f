"""Reference and material frames of DER edges (DVT10 sec. 4.1, "time-parallel").

Each edge k carries a unit reference director u^k orthogonal to its tangent
t^k. After every position update u^k is parallel-transported from the old
tangent to the new one (the rotation of least angle), and the reference twist
of each hinge is advanced by the signed angle between the space-parallel
transport of u^{h-1} onto t^h and u^h. The material frame is then
d1 = cos(theta) u + sin(theta) v, d2 = -sin(theta) u + cos(theta) v, v = t x u.
"""

import math

from numba import njit

from knitlad.engine.kernels.options import INLINE_OPTS, NUMBA_OPTS
from knitlad.engine.kernels.vec import cross, dot, sincos



@njit(**NUMBA_OPTS)
def parallel_transport(ux, uy, uz, ax, ay, az, bx, by, bz):
    """Parallel transport of u from unit tangent a to unit tangent b."""
    nx, ny, nz = cross(ax, ay, az, bx, by, bz)
    s = math.sqrt(nx * nx + ny * ny + nz * nz)
    c = dot(ax, ay, az, bx, by, bz)
    if s < 1e-14:
        return ux, uy, uz
    nx /= s
    ny /= s
    nz /= s
    # Rodrigues rotation about n by the angle between a and b (cos c, sin s)
    ndu = dot(nx, ny, nz, ux, uy, uz)
    wx, wy, wz = cross(nx, ny, nz, ux, uy, uz)
    rx = ux * c + wx * s + nx * ndu * (1.0 - c)
    ry = uy * c + wy * s + ny * ndu * (1.0 - c)
    rz = uz * c + wz * s + nz * ndu * (1.0 - c)
    return rx, ry, rz


@njit(**INLINE_OPTS)
def _unit_normal_part(ux, uy, uz, tx, ty, tz):
    """u made normal to the unit tangent t and of unit length: a transported director drifts out of
    the normal plane by round-off, and a seed lies anywhere."""
    p = dot(ux, uy, uz, tx, ty, tz)
    ux, uy, uz = ux - p * tx, uy - p * ty, uz - p * tz
    nrm = 1.0 / math.sqrt(ux * ux + uy * uy + uz * uz)
    return ux * nrm, uy * nrm, uz * nrm


@njit(**NUMBA_OPTS)
def bishop_reference_directors(tangent, edge_yarn, ref_u):
    """Space-parallel reference directors along each yarn (a Bishop frame), into ``ref_u`` (ne, 3):
    a yarn's first edge takes the seed normal z (x where its tangent is within 26 degrees of +-z) made
    normal to its tangent, and each next edge of the yarn the parallel transport of its predecessor's."""
    for k in range(tangent.shape[0]):
        tx, ty, tz = tangent[k, 0], tangent[k, 1], tangent[k, 2]
        if k > 0 and edge_yarn[k] == edge_yarn[k - 1]:
            ux, uy, uz = parallel_transport(ref_u[k - 1, 0], ref_u[k - 1, 1], ref_u[k - 1, 2],
                                            tangent[k - 1, 0], tangent[k - 1, 1], tangent[k - 1, 2], tx, ty, tz)
        else:
            ux, uy, uz = (0.0, 0.0, 1.0) if abs(tz) < 0.9 else (1.0, 0.0, 0.0)
        ref_u[k, 0], ref_u[k, 1], ref_u[k, 2] = _unit_normal_part(ux, uy, uz, tx, ty, tz)


@njit(**NUMBA_OPTS)
def _small_atan2(y, x):
    """atan2(y, x), by its series where the angle is small: below |z| = |y / x| < 1e-3 (x > 0) it is
    atan z = z - z^3/3 + z^5/5, whose next term (z^7/7 < 1.5e-22) is below round-off. The angles of
    one step are small: the reference-twist update then costs half as much as with atan2 (docs/history.md)."""
    if x > 0.0 and abs(y) < 1e-3 * x:
        z = y / x
        z2 = z * z
        return z * (1.0 - z2 * (1.0 / 3.0 - 0.2 * z2))
    return math.atan2(y, x)


@njit(**NUMBA_OPTS)
def _signed_angle(ux, uy, uz, wx, wy, wz, nx, ny, nz):
    """Angle from u to w about axis n: atan2((u x w).n, u.w)."""
    cx, cy, cz = cross(ux, uy, uz, wx, wy, wz)
    return _small_atan2(dot(cx, cy, cz, nx, ny, nz), dot(ux, uy, uz, wx, wy, wz))


@njit(**NUMBA_OPTS)
def transport_reference_frames(e, elen, tangent, ref_u, first=0, last=-1):
    """Carry u^k from the stored tangent to the current one, in place (both updated); edges [first, last)."""
    if last < 0:
        last = e.shape[0]
    for k in range(first, last):
        inv = 1.0 / elen[k]
        bx, by, bz = e[k, 0] * inv, e[k, 1] * inv, e[k, 2] * inv
        ux, uy, uz = parallel_transport(ref_u[k, 0], ref_u[k, 1], ref_u[k, 2], tangent[k, 0], tangent[k, 1], tangent[k, 2], bx, by, bz)
        ref_u[k, 0], ref_u[k, 1], ref_u[k, 2] = _unit_normal_part(ux, uy, uz, bx, by, bz)
        tangent[k, 0] = bx
        tangent[k, 1] = by
        tangent[k, 2] = bz


@njit(**NUMBA_OPTS)
def update_reference_twist(tangent, ref_u, hinge_e0, hinge_e1, ref_twist, first=0, last=-1):
    """Advance the reference twist of every hinge in [first, last), keeping it continuous in time."""
    if last < 0:
        last = hinge_e0.shape[0]
    for h in range(first, last):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        px, py, pz = parallel_transport(
            ref_u[k0, 0], ref_u[k0, 1], ref_u[k0, 2],
            tangent[k0, 0], tangent[k0, 1], tangent[k0, 2],
            tangent[k1, 0], tangent[k1, 1], tangent[k1, 2],
        )
        # rotate the transported director by the previous twist, then add the residual angle
        s, c = sincos(ref_twist[h])
        tx, ty, tz = tangent[k1, 0], tangent[k1, 1], tangent[k1, 2]
        wx, wy, wz = cross(tx, ty, tz, px, py, pz)
        qx, qy, qz = c * px + s * wx, c * py + s * wy, c * pz + s * wz
        ref_twist[h] += _signed_angle(qx, qy, qz, ref_u[k1, 0], ref_u[k1, 1], ref_u[k1, 2], tx, ty, tz)


@njit(**NUMBA_OPTS)
def _signed_solid_angle(ax, ay, az, bx, by, bz, cx, cy, cz, triple):
    """Signed solid angle of the geodesic triangle a -> b -> c on the unit sphere (Van Oosterom and
    Strackee 1983): tan(Omega/2) = a.(b x c) / (1 + a.b + b.c + c.a), ``triple`` = a.(b x c) given
    (computed from the small differences by the caller, for precision)."""
    x = 1.0 + dot(ax, ay, az, bx, by, bz) + dot(bx, by, bz, cx, cy, cz) + dot(cx, cy, cz, ax, ay, az)
    return 2.0 * _small_atan2(triple, x)


@njit(**NUMBA_OPTS)
def reference_twist_by_holonomy(tangent, e, elen, hinge_e0, hinge_e1, ref_twist, first=0, last=-1):
    """Advance the reference twist of every hinge in [first, last) from the old tangents
    (``tangent``, not changed) to the new ones (e / |e|), without the reference frames.

    Time-parallel transport along both edges and space-parallel transport between them are
    rotations of least angle, i.e. parallel transport along great circles of the unit sphere, and
    a rotation about t^h commutes with them. So the change of the reference twist that
    :func:`transport_reference_frames` and :func:`update_reference_twist` give is the holonomy of
    the geodesic quadrilateral t0 -> t0' -> t1' -> t1 (old and new tangents of edges h-1 and h):
    minus its signed area, the sum of the triangles (t0, t0', t1') and (t0, t1', t1) (Gauss-Bonnet
    on the sphere). Same values to round-off, without sine or cosine and without the frames;
    only the isotropic bending of rods straight at rest, whose energy needs no material frame,
    can use it (with :func:`store_tangents`, which carries the anchors' frames, and
    :func:`rebuild_reference_frames` when the state is read).
    """
    if last < 0:
        last = hinge_e0.shape[0]
    for h in range(first, last):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        i0 = 1.0 / elen[k0]
        i1 = 1.0 / elen[k1]
        ref_twist[h] += holonomy_twist_change(
            tangent[k0, 0], tangent[k0, 1], tangent[k0, 2], tangent[k1, 0], tangent[k1, 1], tangent[k1, 2],
            e[k0, 0] * i0, e[k0, 1] * i0, e[k0, 2] * i0, e[k1, 0] * i1, e[k1, 1] * i1, e[k1, 2] * i1)


@njit(**INLINE_OPTS)
def holonomy_twist_change(a0x, a0y, a0z, a1x, a1y, a1z, b0x, b0y, b0z, b1x, b1y, b1z):
    """The change of a hinge's reference twist as its edges' unit tangents go from (a0, a1) to (b0, b1):
    minus the signed area of the geodesic quadrilateral a0 -> b0 -> b1 -> a1 (:func:`reference_twist_by_holonomy`)."""
    # t0.(t0' x t1') = (t0' - t0).(t1' x t0) and t0.(t1' x t1) = (t1' - t1).(t1 x t0): the steps
    # are small, so the triple products are taken from the tangents' changes
    px, py, pz = cross(b1x, b1y, b1z, a0x, a0y, a0z)
    qx, qy, qz = cross(a1x, a1y, a1z, a0x, a0y, a0z)
    first_triple = dot(b0x - a0x, b0y - a0y, b0z - a0z, px, py, pz)
    second_triple = dot(b1x - a1x, b1y - a1y, b1z - a1z, qx, qy, qz)
    area = (_signed_solid_angle(a0x, a0y, a0z, b0x, b0y, b0z, b1x, b1y, b1z, first_triple)
            + _signed_solid_angle(a0x, a0y, a0z, b1x, b1y, b1z, a1x, a1y, a1z, second_triple))
    if abs(area) > math.pi:  # as update_reference_twist, the turn of least angle (each is exact mod 2 pi)
        area -= 2.0 * math.pi * round(area / (2.0 * math.pi))
    return -area


@njit(**NUMBA_OPTS)
def material_frames(tangent, ref_u, theta, d1, d2, first=0, last=-1):
    """d1, d2 of every edge in [first, last) from the reference frame and the twist angle theta."""
    if last < 0:
        last = theta.shape[0]
    for k in range(first, last):
        tx, ty, tz = tangent[k, 0], tangent[k, 1], tangent[k, 2]
        ux, uy, uz = ref_u[k, 0], ref_u[k, 1], ref_u[k, 2]
        vx, vy, vz = cross(tx, ty, tz, ux, uy, uz)
        s, c = sincos(theta[k])
        d1[k, 0] = c * ux + s * vx
        d1[k, 1] = c * uy + s * vy
        d1[k, 2] = c * uz + s * vz
        d2[k, 0] = -s * ux + c * vx
        d2[k, 1] = -s * uy + c * vy
        d2[k, 2] = -s * uz + c * vz


@njit(**NUMBA_OPTS)
def store_tangents(e, elen, tangent, ref_u, frame_anchor, first=0, last=-1):
    """The tangents of edges [first, last) set to e / |e|, the reference director carried along
    (time-parallel transport, as :func:`transport_reference_frames`) only on the anchor edges.

    The frame-free path (:func:`reference_twist_by_holonomy`) needs the old tangents and no frame:
    the other edges' directors follow from the anchors and the reference twist
    (:func:`rebuild_reference_frames`), so they are rebuilt when the state is read, not each step.
    """
    if last < 0:
        last = e.shape[0]
    for k in range(first, last):
        inv = 1.0 / elen[k]
        bx, by, bz = e[k, 0] * inv, e[k, 1] * inv, e[k, 2] * inv
        if frame_anchor[k]:
            ux, uy, uz = parallel_transport(ref_u[k, 0], ref_u[k, 1], ref_u[k, 2],
                                            tangent[k, 0], tangent[k, 1], tangent[k, 2], bx, by, bz)
            ref_u[k, 0], ref_u[k, 1], ref_u[k, 2] = _unit_normal_part(ux, uy, uz, bx, by, bz)
        tangent[k, 0] = bx
        tangent[k, 1] = by
        tangent[k, 2] = bz


@njit(**NUMBA_OPTS)
def rebuild_reference_frames(tangent, ref_u, ref_twist, hinge_e0, hinge_e1, frame_anchor, first=0, last=-1):
    """The reference directors of the edges that are not anchors, from those of the hinges' first edges:
    u^h = R(t^h, m_h) P(t^{h-1} -> t^h) u^{h-1}, the definition of the reference twist m_h that
    :func:`update_reference_twist` keeps (DVT10 sec. 4.1), hinges [first, last) in order along the yarn
    (``Workspace.frame_anchor`` checks that each hinge's first edge is an anchor or an earlier hinge's second).

    Time-parallel transport of every edge and this rebuild from time-transported anchors give the same
    frames, to round-off: both leave the reference twist the holonomy of the tangents' motion.
    """
    if last < 0:
        last = hinge_e0.shape[0]
    for h in range(first, last):
        k0 = hinge_e0[h]
        k1 = hinge_e1[h]
        if frame_anchor[k1]:
            continue
        tx, ty, tz = tangent[k1, 0], tangent[k1, 1], tangent[k1, 2]
        px, py, pz = parallel_transport(ref_u[k0, 0], ref_u[k0, 1], ref_u[k0, 2],
                                        tangent[k0, 0], tangent[k0, 1], tangent[k0, 2], tx, ty, tz)
        s, c = sincos(ref_twist[h])
        wx, wy, wz = cross(tx, ty, tz, px, py, pz)
        ux, uy, uz = c * px + s * wx, c * py + s * wy, c * pz + s * wz
        ref_u[k1, 0], ref_u[k1, 1], ref_u[k1, 2] = _unit_normal_part(ux, uy, uz, tx, ty, tz)
