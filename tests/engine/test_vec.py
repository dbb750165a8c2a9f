"""Scalar vector helpers (knitlad.engine.kernels.vec): the sine and cosine the frames use."""

import numpy as np

from knitlad.engine.kernels.vec import sincos


def test_sincos_is_libm_to_an_ulp():
    rng = np.random.default_rng(3)
    # small angles, the quadrant boundaries and the twist angles a long run can reach
    x = np.concatenate([rng.normal(0.0, 1e-3, 2000), rng.uniform(-4.0, 4.0, 4000),
                        np.pi / 4 * np.arange(-40, 41) + rng.normal(0.0, 1e-12, 81), rng.uniform(-1e5, 1e5, 4000)])
    got = np.array([sincos(v) for v in x])
    ulp = np.spacing(1.0)
    assert np.all(np.abs(got[:, 0] - np.sin(x)) <= ulp)
    assert np.all(np.abs(got[:, 1] - np.cos(x)) <= ulp)
    # where sin x is tiny it keeps its relative precision, as libm does
    tiny = np.abs(x) < 1e-2
    assert np.all(np.abs(got[tiny, 0] - np.sin(x[tiny])) <= 2 * np.spacing(np.abs(np.sin(x[tiny]))))
