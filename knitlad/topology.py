"""Topology of yarn curves: the Gauss linking number of two closed polygons.

Used to prove the jersey topology (each loop of row n+1 passes through the
loop of row n) and to detect laddered cells (the two no longer link).
"""

import math

import numpy as np
from numba import njit

from knitlad.kernels.vec import cross, dot


@njit(cache=True)
def _solid_angle(p1, p2, p3, p4):
    """Signed solid angle of segment p1p2 seen against segment p3p4 (Klenin & Langowski 2000)."""
    r13 = p3 - p1
    r14 = p4 - p1
    r23 = p3 - p2
    r24 = p4 - p2
    n = np.empty((4, 3))
    for k, (a, b) in enumerate(((r13, r14), (r14, r24), (r24, r23), (r23, r13))):
        cx, cy, cz = cross(a[0], a[1], a[2], b[0], b[1], b[2])
        nn = math.sqrt(cx * cx + cy * cy + cz * cz)
        if nn < 1e-300:
            return 0.0
        n[k, 0] = cx / nn
        n[k, 1] = cy / nn
        n[k, 2] = cz / nn
    omega = 0.0
    for k in range(4):
        c = dot(n[k, 0], n[k, 1], n[k, 2], n[(k + 1) % 4, 0], n[(k + 1) % 4, 1], n[(k + 1) % 4, 2])
        c = min(1.0, max(-1.0, c))
        omega += math.asin(c)
    r34 = p4 - p3
    r12 = p2 - p1
    sx, sy, sz = cross(r34[0], r34[1], r34[2], r12[0], r12[1], r12[2])
    s = dot(sx, sy, sz, r13[0], r13[1], r13[2])
    return omega if s > 0 else -omega


@njit(cache=True)
def linking_number(curve1, curve2):
    """Gauss linking number of two closed polygons (m, 3) and (k, 3) (last point joins the first).

    An integer (up to round-off) when the curves do not intersect.
    """
    total = 0.0
    m = curve1.shape[0]
    k = curve2.shape[0]
    for i in range(m):
        p1 = curve1[i]
        p2 = curve1[(i + 1) % m]
        for j in range(k):
            total += _solid_angle(p1, p2, curve2[j], curve2[(j + 1) % k])
    return total / (4.0 * math.pi)


@njit(cache=True)
def _segment_hits_triangle(p, q, a, b, c):
    """Whether segment pq crosses triangle abc (Moller-Trumbore), and the sign of the crossing."""
    e1 = b - a
    e2 = c - a
    d = q - p
    hx, hy, hz = cross(d[0], d[1], d[2], e2[0], e2[1], e2[2])
    det = dot(e1[0], e1[1], e1[2], hx, hy, hz)
    if abs(det) < 1e-300:
        return 0
    inv = 1.0 / det
    s = p - a
    u = inv * dot(s[0], s[1], s[2], hx, hy, hz)
    if u < 0.0 or u > 1.0:
        return 0
    qx, qy, qz = cross(s[0], s[1], s[2], e1[0], e1[1], e1[2])
    v = inv * dot(d[0], d[1], d[2], qx, qy, qz)
    if v < 0.0 or u + v > 1.0:
        return 0
    t = inv * dot(e2[0], e2[1], e2[2], qx, qy, qz)
    if t < 0.0 or t > 1.0:
        return 0
    return 1 if det > 0 else -1


@njit(cache=True)
def piercings(ring, arc):
    """Crossings of the open polyline ``arc`` through the fan spanning the closed polygon ``ring``.

    The fan joins the ring's centroid to each of its edges. Returns (unsigned
    count, signed sum). A U-shaped loop threaded through a ring crosses it twice
    with opposite signs: (2, 0); a loop lying beside or pulled out of it: (0, 0).
    """
    centre = np.zeros(3)
    m = ring.shape[0]
    for i in range(m):
        centre += ring[i]
    centre /= m
    count = 0
    signed = 0
    for j in range(arc.shape[0] - 1):
        for i in range(m):
            hit = _segment_hits_triangle(arc[j], arc[j + 1], centre, ring[i], ring[(i + 1) % m])
            if hit != 0:
                count += 1
                signed += hit
    return count, signed
