"""Convergence of the observables in the solver settings (docs/accuracy.md).

The periodised stitch's tension converges in the resolution at order 3 to 4 (default suite);
the laddering velocity converges in the time step below 0.35 x the stability limit (slow).
"""

from __future__ import annotations

import math

import pytest

from knitlad.config import CutConfig
from knitlad.protocol import run_ladder
from knitlad.simulation import numba_threads
from knitlad.stitch_model import stitch_tensions


def observed_order(values: list[float], n: list[int]) -> tuple[float, float]:
    """Order p and limit of f(n) = f_inf + C n^-p through three points (bisection on p)."""
    (f1, f2, f3), (n1, n2, n3) = values, n
    ratio = (f1 - f2) / (f2 - f3)

    def mismatch(p: float) -> float:
        return ratio - (n1**-p - n2**-p) / (n2**-p - n3**-p)

    lo, hi = 0.05, 10.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mismatch(lo) * mismatch(mid) > 0 else (lo, mid)
    p = 0.5 * (lo + hi)
    limit = f3 - (f2 - f3) / (n2**-p - n3**-p) * n3**-p
    return p, limit


def test_the_stitch_tension_converges_at_order_3_to_4_in_the_resolution():
    """f_x at (0.39, 0.25) with 36, 48, 64 nodes per stitch (measured 12.47, 11.00, 10.40:
    order 3.1, limit 9.99). Second order would be the floor for a DER discretisation."""
    n = [36, 48, 64]
    with numba_threads(1):
        fx = [stitch_tensions(0.39, 0.25, nodes_per_stitch=k).fx for k in n]
    assert fx[0] > fx[1] > fx[2]  # coarse yarns are too stiff in the tight loops
    p, limit = observed_order(fx, n)
    assert 2.0 < p < 6.0
    assert abs(fx[2] - limit) / limit < 0.06  # 64 nodes per stitch: within 6 % of the limit
    assert math.isfinite(limit) and limit > 0


@pytest.mark.slow
@pytest.mark.parametrize("fx", [4.0, 13.6])
def test_the_laddering_velocity_is_converged_in_the_time_step_below_035(fx):
    """16 x 16, mu = 0.4, from one stretched knit (the FIRE stretch does not depend on dt_safety):
    v_lad at 0.35 and 0.175 x the stability limit agree within 5 % (measured with tail ends at
    f_x^ini = 3.92: 0.270 and 0.266, where 0.7 gives 0.312; with clamped ends at 13.59: 0.738
    at both). An earlier version dropped 13.6 here, reading a NaN at 0.35 as a ladder whose direction
    depends on the step: it was the front read in the column beside the upward ladder, fixed
    since (``measure.laddering_column``). The steps at 13.5 on 42 x 42: docs/accuracy.md."""
    with numba_threads(1):
        v = [run_ladder(CutConfig(n_x=16, n_y=16, fx=fx, dt_safety=dt).settings()).v_lad_over_cb
             for dt in (0.35, 0.175)]
    assert v[1] == pytest.approx(v[0], rel=0.05)
