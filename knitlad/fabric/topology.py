"""Topology of yarn curves: how often a loop pierces the surface spanning another.

A loop of course r+1 is pulled through the head of course r: as a U through a
ring, it pierces the ring's spanning surface twice with opposite signs, so the
two closed curves are *not* linked (a Gauss linking number is 0 for every local
closure, which is why it is not used here). Used to prove each pattern's topology.
"""

import numpy as np
from numba import njit

from knitlad.engine.kernels.vec import cross, dot


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


@njit(cache=True)
def threading_direction(ring, arc):
    """Which way the open polyline ``arc`` first passes through the fan spanning ``ring``: the sign of
    its z-step there (+1 towards +z, -1 towards -z), 0 if it does not pass. A knit stitch's loop is
    drawn through its head from the technical back (+z in knitlad's knits) to the face: -1; a purl
    stitch's: +1 (knitlad.fabric.patterns)."""
    centre = np.zeros(3)
    m = ring.shape[0]
    for i in range(m):
        centre += ring[i]
    centre /= m
    for j in range(arc.shape[0] - 1):
        for i in range(m):
            if _segment_hits_triangle(arc[j], arc[j + 1], centre, ring[i], ring[(i + 1) % m]) != 0:
                step = arc[j + 1, 2] - arc[j, 2]
                return 1 if step > 0 else -1
    return 0
