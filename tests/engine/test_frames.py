"""Reference frames (knitlad.engine.kernels.frames): the signed angle that advances the reference twist, the
reference twist by the holonomy of the tangents, and the frames rebuilt from anchors and that twist."""

import math

import numpy as np
import pytest

from knitlad.engine.kernels.frames import (
    _signed_angle,
    bishop_reference_directors,
    parallel_transport,
    rebuild_reference_frames,
    reference_twist_by_holonomy,
    store_tangents,
    transport_reference_frames,
    update_reference_twist,
)


@pytest.mark.parametrize("angle", [0.0, 1e-12, -3e-9, 2e-6, -7e-5, 9.99e-4, 1.0e-3, 0.3, -2.0, 3.1])
def test_signed_angle_is_atan2_to_round_off(angle):
    # u and w = u turned by `angle` about n, in a plane tilted off the axes
    rng = np.random.default_rng(7)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    u = np.cross(n, rng.normal(size=3))
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    w = math.cos(angle) * u + math.sin(angle) * v
    got = _signed_angle(*u, *w, *n)
    exact = math.atan2(np.dot(np.cross(u, w), n), np.dot(u, w))
    # unit vectors: y and x carry absolute round-off ~1e-16 (the kernel's fast-math sums differ from
    # numpy's), and so does the angle; dropping the z^3/3 term would miss by 3e-10 at z = 1e-3
    assert abs(got - exact) <= 4e-16 * (1.0 + abs(exact))
    assert abs(got - angle) <= 1e-15 * (1.0 + abs(angle))


def wavy_helix(n: int, rng) -> np.ndarray:
    s = np.linspace(0.0, 4.0 * np.pi, n)
    return np.column_stack([np.cos(s), np.sin(s), 0.3 * s]) + rng.normal(scale=0.05, size=(n, 3))


def test_the_bishop_directors_are_unit_normal_and_untwisted_along_each_yarn():
    """bishop_reference_directors: unit, normal to the tangents, zero reference twist at every hinge
    inside a yarn, and each yarn's first edge on its seed: z made normal to the tangent, or x where
    the tangent is within 26 degrees of +-z (the second yarn starts along z)."""
    rng = np.random.default_rng(3)
    first = wavy_helix(30, rng)
    second = np.column_stack([0.1 * np.sin(np.linspace(0, 3, 20)), np.zeros(20), np.linspace(0, 5, 20)])
    e = np.concatenate([np.diff(first, axis=0), np.diff(second, axis=0)])
    tangent = e / np.linalg.norm(e, axis=1)[:, None]
    edge_yarn = np.repeat([0, 1], [29, 19])
    ref_u = np.zeros_like(tangent)
    bishop_reference_directors(tangent, edge_yarn, ref_u)
    np.testing.assert_allclose(np.linalg.norm(ref_u, axis=1), 1.0, rtol=0, atol=1e-14)
    assert np.abs(np.einsum("ij,ij->i", ref_u, tangent)).max() < 1e-14
    h0 = np.array([k for k in range(47) if edge_yarn[k] == edge_yarn[k + 1]])
    ref_twist = np.zeros(h0.shape[0])
    update_reference_twist(tangent, ref_u, h0, h0 + 1, ref_twist)
    assert np.abs(ref_twist).max() < 1e-13
    for k, seed in ((0, [0.0, 0.0, 1.0]), (29, [1.0, 0.0, 0.0])):
        t = tangent[k]
        u = np.array(seed) - np.dot(seed, t) * t
        np.testing.assert_allclose(ref_u[k], u / np.linalg.norm(u), rtol=0, atol=1e-15)


@pytest.mark.parametrize("step, n_steps", [(1e-4, 400), (1e-2, 60)])
def test_the_reference_twist_by_holonomy_is_that_of_the_transported_frames(step, n_steps):
    """reference_twist_by_holonomy advances the reference twist as transport_reference_frames +
    update_reference_twist do (Gauss-Bonnet: the holonomy of the tangents' quadrilateral), over
    many steps of a wobbling helix: small steps like a run's, and large ones (0.03 of an edge)."""
    # the helix's edges are 0.33 long: the walk stays well short of folding a hinge back
    rng = np.random.default_rng(11)
    x = wavy_helix(40, rng)
    n_edges = x.shape[0] - 1
    h0 = np.arange(n_edges - 1)
    h1 = h0 + 1

    def edges(x):
        e = np.ascontiguousarray(x[1:] - x[:-1])
        return e, np.linalg.norm(e, axis=1)

    e, elen = edges(x)
    tangent = e / elen[:, None]
    ref_u = np.zeros_like(tangent)
    first = np.cross(tangent[0], [0.0, 0.0, 1.0])
    ref_u[0] = first / np.linalg.norm(first)
    for k in range(1, n_edges):  # Bishop: ref_twist starts at zero
        u = np.array(parallel_transport(*ref_u[k - 1], *tangent[k - 1], *tangent[k]))
        ref_u[k] = u / np.linalg.norm(u)
    framed = np.zeros(n_edges - 1)
    update_reference_twist(tangent, ref_u, h0, h1, framed)
    assert np.abs(framed).max() < 1e-12
    holonomy = framed.copy()
    tangent_h = tangent.copy()
    for _ in range(n_steps):
        x = x + rng.normal(scale=step, size=x.shape)
        e, elen = edges(x)
        transport_reference_frames(e, elen, tangent, ref_u)
        update_reference_twist(tangent, ref_u, h0, h1, framed)
        reference_twist_by_holonomy(tangent_h, e, elen, h0, h1, holonomy)
        tangent_h[:] = e / elen[:, None]
    assert np.abs(framed).max() > 20 * step  # the frames have turned
    np.testing.assert_allclose(holonomy, framed, rtol=0, atol=1e-13)


def test_frames_rebuilt_from_the_anchors_are_the_transported_ones():
    """store_tangents (frames carried on the anchors only) + rebuild_reference_frames give every edge the
    frame that time-parallel transport of all edges gives, to round-off, after 300 steps of a wobbling
    helix turning its frames by ~0.1 rad: on an open chain cut in two (a second anchor mid-way, no hinge
    across the cut) and on a closed loop (its seam hinge ends on the anchor, and is skipped)."""
    rng = np.random.default_rng(5)
    x = wavy_helix(41, rng)
    n_edges = x.shape[0] - 1

    def edges(x):
        e = np.ascontiguousarray(x[1:] - x[:-1])
        return e, np.linalg.norm(e, axis=1)

    for layout in ("cut chain", "closed loop"):
        if layout == "cut chain":  # edges 0..19 and 20..39, no hinge (19, 20)
            h0 = np.array([k for k in range(n_edges - 1) if k != 19])
            anchor = np.zeros(n_edges, dtype=bool)
            anchor[[0, 20]] = True
        else:  # the seam hinge (39, 0) first, as the periodised stitch stores it
            h0 = np.concatenate([[n_edges - 1], np.arange(n_edges - 1)])
            anchor = np.zeros(n_edges, dtype=bool)
            anchor[0] = True
        h1 = (h0 + 1) % n_edges
        e, elen = edges(x)
        tangent = e / elen[:, None]
        ref_u = np.zeros_like(tangent)
        for k in range(n_edges):
            seed = np.cross(tangent[k], [0.0, 0.0, 1.0])
            ref_u[k] = seed / np.linalg.norm(seed)  # any frames: the reference twist records them
        ref_twist = np.zeros(h0.shape[0])
        update_reference_twist(tangent, ref_u, h0, h1, ref_twist)
        transported, t_transported, twist_framed = ref_u.copy(), tangent.copy(), ref_twist.copy()
        xs = x.copy()
        for _ in range(300):
            xs = xs + rng.normal(scale=2e-3, size=xs.shape)
            e, elen = edges(xs)
            transport_reference_frames(e, elen, t_transported, transported)
            update_reference_twist(t_transported, transported, h0, h1, twist_framed)
            reference_twist_by_holonomy(tangent, e, elen, h0, h1, ref_twist)
            store_tangents(e, elen, tangent, ref_u, anchor)
        assert np.abs(ref_u[~anchor] - transported[~anchor]).max() > 1e-2  # stale before the rebuild
        rebuild_reference_frames(tangent, ref_u, ref_twist, h0, h1, anchor)
        assert np.abs(ref_u - transported).max() < 1e-12, layout
        np.testing.assert_array_equal(tangent, t_transported)
        np.testing.assert_allclose(ref_twist, twist_framed, rtol=0, atol=1e-12)
        assert np.abs(twist_framed).max() > 0.05  # the frames have turned
