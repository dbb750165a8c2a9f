"""Reference frames (knitlad.kernels.frames): the signed angle that advances the reference twist."""

import math

import numpy as np
import pytest

from knitlad.kernels.frames import _signed_angle


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
