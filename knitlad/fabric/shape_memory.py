"""Shape memory: the natural curvature a knitted thread keeps from the shape it was knitted in.

The paper (appendix "Natural curvature") measures on threads pulled out of the fabric
(kbar/kappa0)^2 of about 1 on average and 3.5 at most over four stitches, and proposes
that this memory sets the threshold tension f_x^thr = (kbar/kappa0)^2. Here the
memory is a fraction of the shape of the unloaded fabric: the natural material
curvature of every hinge is

    kappa_bar_h = alpha (kappa_1, kappa_2)_h of the reference shape,

alpha chosen so that the mean over the hinges of (|kappa_bar_h| / (l_h kappa0))^2 is
the given K (DER's discrete curvature: the integrated material curvature over the
Voronoi length l_h). The reference is the periodised stitch relaxed on the f_x = 0
curve (the fabric neither pulled nor compressed), in its own material frames, which
the stretch then carries to the target continuously; the natural twist is the
reference twist there, so a thread freed of the fabric relaxes to alpha times the
reference curvature with no twist stored. alpha = sqrt(K / K_ref), K_ref the mean of
the reference shape itself.
"""

from __future__ import annotations

import numpy as np

from knitlad.engine import units
from knitlad.engine.kernels.elastic import edge_vectors, material_curvatures
from knitlad.engine.kernels.frames import material_frames
from knitlad.engine.state import Rods, with_twist
from knitlad.engine.units import Material


def material_curvature(rods: Rods) -> np.ndarray:
    """(kappa_1, kappa_2) of every hinge (nh, 2), integrated (dimensionless), in the current material frames."""
    m, s = rods.model, rods.state
    ne = m.edge_a.shape[0]
    e, elen = np.zeros((ne, 3)), np.zeros(ne)
    edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, e, elen)
    d1, d2 = np.zeros((ne, 3)), np.zeros((ne, 3))
    material_frames(s.tangent, s.ref_u, s.theta, d1, d2)
    out = np.zeros((m.hinge_e0.shape[0], 2))
    material_curvatures(e, elen, d1, d2, m.hinge_e0, m.hinge_e1, out)
    return out


def voronoi_lengths(rods: Rods) -> np.ndarray:
    """l_h = (|e_bar^{h-1}| + |e_bar^h|) / 2 of every hinge [internal length]."""
    m = rods.model
    return 0.5 * (m.rest_length[m.hinge_e0] + m.rest_length[m.hinge_e1])


def mean_squared_curvature(kappa: np.ndarray, lengths: np.ndarray, material: Material) -> float:
    """mean over hinges of (|kappa_h| / (l_h kappa0))^2, ``kappa`` (nh, 2) integrated, ``lengths`` internal."""
    kappa0 = material.kappa0 * units.LENGTH  # [1 / internal length]
    return float(np.mean(np.sum(kappa**2, axis=1) / (lengths * kappa0) ** 2))


def remember_shape(rods: Rods, K: float, hinges: np.ndarray, material: Material,
                   peak_ratio: float | None = None) -> Rods:
    """A copy of ``rods`` carrying twist whose natural curvature is alpha x its current material curvature,
    alpha set so that the mean of (kappa_bar / kappa0)^2 over ``hinges`` is ``K`` (module docstring).

    ``peak_ratio``: the memory is concentrated where the shape is most bent (the loop heads), so that the
    max over ``hinges`` of (kappa_bar/kappa0)^2 is ``peak_ratio`` times its mean (the paper's thread: about
    3.5; the scaled copy's own ratio, about 1.6, is the least): kappa_bar_h = c w_h kappa_h with
    w_h^2 q_h = (q_h - t)+, q_h = (|kappa_h|/(l_h kappa0))^2, t found by bisection (:func:`peaked_weights`)
    and c setting the mean to K.

    Twist is switched on first (:func:`knitlad.engine.state.with_twist`: Bishop frames along the current
    tangents, natural twist = the current reference twist), if it is not on yet.
    """
    if K < 0:
        raise ValueError(f"the natural curvature K must be >= 0, got {K!r}")
    if not rods.twist:
        rods = with_twist(rods, material.twisting_stiffness / material.bending_stiffness)
    kappa = material_curvature(rods)
    lengths = voronoi_lengths(rods)
    if peak_ratio is not None:
        kappa = kappa * peaked_weights(kappa, lengths, hinges, material, peak_ratio)[:, None]
    reference = mean_squared_curvature(kappa[hinges], lengths[hinges], material)
    alpha = np.sqrt(K / reference) if reference > 0 else 0.0
    return rods.replace_model(kappa_bar=alpha * kappa, twist_bar=rods.state.ref_twist.copy(), framed=K > 0)


def peaked_weights(kappa: np.ndarray, lengths: np.ndarray, hinges: np.ndarray, material: Material,
                   peak_ratio: float) -> np.ndarray:
    """Weights w_h of every hinge (see :func:`remember_shape`) for which the max over ``hinges`` of
    w^2 q is ``peak_ratio`` times its mean: w_h^2 q_h = (q_h - t)+, the memory kept only where the shape
    bends more than a threshold t, in proportion to the excess (t by bisection; t = 0 is the scaled copy).
    ValueError if the shape's own ratio exceeds ``peak_ratio``, or if the hinges sharing its maximum allow
    no more (symmetric maxima: the ratio tends to the hinges over those sharing the maximum)."""
    kappa0 = material.kappa0 * units.LENGTH
    q = np.sum(kappa**2, axis=1) / (lengths * kappa0) ** 2
    qh = q[hinges]

    def ratio(t: float) -> float:
        excess = np.maximum(qh - t, 0.0)
        return float(excess.max() / excess.mean())

    if ratio(0.0) > peak_ratio:
        raise ValueError(f"peak_ratio {peak_ratio:g} is below the shape's own max/mean of "
                         f"(kappa/kappa0)^2, {ratio(0.0):.3g}")
    low, high = 0.0, float(qh.max())
    reach = ratio(high * (1 - 1e-9))
    if reach < peak_ratio:
        raise ValueError(f"peak_ratio {peak_ratio:g} is out of reach of {len(hinges)} hinges ({reach:.3g} at "
                         "most): a finer resolution reaches more")
    for _ in range(80):  # ratio(t) rises with t: bisection to round-off
        mid = 0.5 * (low + high)
        low, high = (mid, high) if ratio(mid) < peak_ratio else (low, mid)
    excess = np.maximum(q - 0.5 * (low + high), 0.0)
    return np.sqrt(np.divide(excess, q, out=np.zeros_like(q), where=q > 0))


def positional_curvature(rods: Rods, x: np.ndarray, hinges: np.ndarray, material: Material) -> np.ndarray:
    """(kappa/kappa0)^2 of ``hinges`` read from positions ``x`` alone [-]: |kb| = 2 tan(phi/2) over the
    Voronoi length (DER's discrete curvature, no frames): what a photograph of the yarn would give."""
    m = rods.model
    e, elen = np.zeros((m.edge_a.size, 3)), np.zeros(m.edge_a.size)
    edge_vectors(x, m.edge_a, m.edge_b, m.edge_shift, e, elen)
    t0 = e[m.hinge_e0[hinges]] / elen[m.hinge_e0[hinges], None]
    t1 = e[m.hinge_e1[hinges]] / elen[m.hinge_e1[hinges], None]
    kb = 2 * np.linalg.norm(np.cross(t0, t1), axis=1) / (1 + np.sum(t0 * t1, axis=1))
    return (kb / (voronoi_lengths(rods)[hinges] * material.kappa0 * units.LENGTH)) ** 2


def flattened_curvature(points: np.ndarray) -> np.ndarray:
    """Curvature [1/length of ``points``] at the interior vertices of an open polyline laid flat: projected
    on its best-fitting plane (the two leading principal axes), as the paper measured its thread, on a
    photograph of it lying on a plane (appendix "Natural curvature"). Discrete curvature of the 2-D
    outline: the turning angle at a vertex over the Voronoi length of its two edges, signed (left +)."""
    x = np.asarray(points, dtype=float)
    centred = x - x.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2][:2]
    flat = centred @ axes.T  # (n, 2) coordinates in the plane
    e = np.diff(flat, axis=0)
    length = np.hypot(e[:, 0], e[:, 1])
    turn = np.arctan2(e[:-1, 0] * e[1:, 1] - e[:-1, 1] * e[1:, 0], np.sum(e[:-1] * e[1:], axis=1))
    return turn / (0.5 * (length[:-1] + length[1:]))
