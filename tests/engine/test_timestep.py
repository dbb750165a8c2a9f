"""knitlad.engine.timestep: the damped oscillator's stability limit under this code's Verlet, against the map itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

from knitlad.engine.timestep import damped_limit_factor


def grows(h: float, zeta: float, predicted: bool, steps: int = 4000) -> bool:
    """Kick-drift-kick of x'' = -x - 2 zeta v (unit frequency) with step h: does it blow up?"""
    x, v = 1.0, 0.0
    a = -x - 2 * zeta * v
    for _ in range(steps):
        v_half = v + 0.5 * h * a
        x = x + h * v_half
        v_damp = v_half + 0.5 * h * a if predicted else v_half
        a = -x - 2 * zeta * v_damp
        v = v_half + 0.5 * h * a
        if abs(x) > 1e6:
            return True
    return False


def test_undamped_limit_is_the_textbook_two_over_omega():
    assert damped_limit_factor(0.0) == 1.0 and damped_limit_factor(0.0, predicted=True) == 1.0


@pytest.mark.parametrize("zeta", [0.1, 0.2, 0.3])
@pytest.mark.parametrize("predicted", [False, True])
def test_the_stated_limit_separates_stable_from_unstable_steps(zeta, predicted):
    factor = damped_limit_factor(zeta, predicted)
    assert not grows(2 * factor * 0.99, zeta, predicted)
    assert grows(2 * factor * 1.02, zeta, predicted)
    if not predicted:
        assert factor == pytest.approx(math.sqrt(1 + zeta**2) - zeta, rel=1e-12)
    assert np.isfinite(factor) and 0 < factor < 1
