"""The laddering experiment against the paper's DER runs (slow).

Paper (Fig. 5a and appendix "Simulations"; 42 x 42, mu = 0.4, l_y/l0 = 0.25, no natural
curvature): v_lad/c_b = 0.176 at f_x^ini = 1.58 and 1.05 at 15.67, linear in the tension, so
0.062 per unit f_x. Our 42 x 42 runs grow at that rate but lie about 0.15 c_b above the
paper's line (README, "The laddering experiment"); the rate is what is tested here, on a
24 x 24 knit, since a 42 x 42 point costs 7 to 20 minutes. These checks were measured with
the fast preset (24 nodes per stitch, capsules of the yarn's radius; the default up to
2026-12-03) and run with it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from knitlad.experiments.config import CutConfig
from knitlad.experiments.laddering import analyse, cut, propagate, run_ladder
from knitlad.fabric.preparation import stretch
from tests.validation.references import paper_der_line

PAPER_SLOPE = paper_der_line(1.0) - paper_der_line(0.0)


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "read as the paper reads v_lad (the mid-line front, stitches 2-10), the 24 x 24 rate is 0.043 per unit f_x "
    "(v/c_b 0.367 at f_x^ini 4.00, 0.779 at 13.55, fast preset, 2026-12-07): 31 % below the paper's DER line, "
    "whose runs carry a drag the paper does not state (docs/paper_claims.md)"))
def test_the_laddering_velocity_grows_with_tension_at_the_papers_rate():
    """24 x 24 at f_x^ini 4 and 13.6: both ladder up, the tension relaxes as the ladder frees
    yarn (f_x^fin < f_x^ini), and (v(13.6) - v(4)) / (13.6 - 4) is within 25 % of the paper's
    0.062. The 25 %: one run's v_lad scatters by up to +-13 % at f_x 4 and +-2 % at 13.6
    (docs/accuracy.md), which moves the slope by up to ~13 %, and a knit of 24 rows ladders
    slower at low tension than one of 42. Strictly expected to fail while the disagreement stands: a model
    that meets the paper's rate makes it pass, and the reason above must then be re-read."""
    runs = [run_ladder(CutConfig(n_x=24, n_y=24, fx=fx, preset="fast").settings()) for fx in (4.0, 13.6)]
    for r in runs:
        assert math.isfinite(r.v_lad_over_cb), r.stop_reason
        assert r.fx_fin < r.fx_ini
    low, high = runs
    slope = (high.v_lad_over_cb - low.v_lad_over_cb) / (high.fx_ini - low.fx_ini)
    assert slope == pytest.approx(PAPER_SLOPE, rel=0.25)


@pytest.mark.slow
def test_a_weak_global_drag_slows_the_ladder_at_low_tension_only():
    """docs/accuracy.md, "A weak global drag": from one stretched 24 x 24 knit per tension
    (each stretched knit cut twice), a drag of 3e3 /s on every node (momentum decays in 0.33 ms) slows the
    ladder by more than 40 % at f_x^ini 1.58, where a stitch takes ~0.3 ms to let go, and much less at 13.6
    (~0.09 ms per stitch). Measured with the first-arrival front: 0.277 -> 0.128 (-54 %) and 0.916 -> 0.918;
    with the paper's mid-line front at 13.6, 0.779 -> 0.738 (-5.3 %, 2026-12-07). The 40 %: undamped at 1.58,
    v_lad scatters from 0.26 to 0.39 under drags <= 1e3 /s too weak to damp it (six runs), and 0.128 is below
    half of every one of them. At 13.6 the bound is the ratio of the stitch times: a slowing linear in the drag
    times a stitch's release time would be 0.09/0.3 = 0.3 of the slowing at 1.58; it must be less than that."""
    free_low, damped_low = laddering_velocity_by_default_and_with(1.58, drag_per_s=3e3)
    assert damped_low < 0.6 * free_low
    free_high, damped_high = laddering_velocity_by_default_and_with(13.6, drag_per_s=3e3)
    slowing_low, slowing_high = 1 - damped_low / free_low, 1 - damped_high / free_high
    assert abs(slowing_high) < 0.3 * slowing_low


@pytest.mark.slow
def test_the_friction_couple_slows_the_ladder_at_moderate_tension():
    """docs/accuracy.md, "Twist and the friction couple": with twist on, friction also turns
    the yarns. On 16 x 16 knits of the tiled stretch (five per tension, targets 0.5 % apart, each
    laddered twist-free and with twist from one stretch, scripts/twist_ensemble.py at commit 56421cd, 2026-12-03) the
    paired change of v_lad was -13.5 +- 1.6 % (standard error) at f_x^ini 4, each knit between -9.4
    and -18.4 %, and -0.8 +- 2.1 % at 1.58, where the five changes scattered from -6.1 to +5.0 %.
    Here the knit at 4: more than 7 % slower with twist, outside that scatter of a null effect."""
    free, twisted = laddering_velocity_by_default_and_with(4.0, size=16, twist=True)
    assert twisted < 0.93 * free


def laddering_velocity_by_default_and_with(fx: float, size: int = 24, **dynamics) -> tuple[float, float]:
    """v_lad/c_b from one stretched knit, laddered with the default settings and with ``dynamics`` changed."""
    knit = stretch(CutConfig(n_x=size, n_y=size, fx=fx, preset="fast").stretch_settings())
    v = []
    for settings in ({}, dynamics):
        cfg = CutConfig(n_x=size, n_y=size, fx=fx, preset="fast", **settings)
        result = analyse(propagate(cut(knit, cfg.dynamics_settings())))
        assert math.isfinite(result.v_lad_over_cb), result.stop_reason
        v.append(result.v_lad_over_cb)
    return v[0], v[1]


@pytest.mark.slow
def test_a_run_stop_band_of_three_times_the_friction_holds_the_ladder_at_low_tension_not_at_high():
    """docs/snag.md (2026-12-06, 16 x 16, default preset, three knits per point): a band of courses 11-12 with
    three times the friction stops the upward ladder below it at f_x^ini 4 (highest undone course 9 on
    every knit), and the ladder crosses it at 8 (course 14). One knit each here (the middle target)."""
    reach = {}
    for fx in (4.0, 8.0):
        cfg = CutConfig(n_x=16, n_y=16, fx=fx, band_row=11, band_courses=2, band_friction_factor=3.0)
        laddered = run_ladder(cfg.settings()).final_laddered
        reach[fx] = int(np.flatnonzero(laddered.any(axis=1)).max())
    assert reach[4.0] < 11 <= reach[8.0]


@pytest.mark.slow
def test_a_run_stop_band_knitted_in_rib_holds_the_ladder_that_crosses_the_plain_knit():
    """docs/snag.md (2026-12-06, 16 x 16, default preset, three knits per point): two courses of 1x1 rib
    (courses 11-12) stop the upward ladder at course 10 on every knit at f_x^ini 4, where the plain jersey,
    stretched affinely to the same target, ladders to course 14. One knit each here (the middle target)."""
    reach = {}
    for band in (None, 11):
        cfg = CutConfig(n_x=16, n_y=16, fx=4.0, band="rib" if band else "friction", band_row=band,
                        band_courses=2, stretch_start="affine")
        laddered = run_ladder(cfg.settings()).final_laddered
        reach[band] = int(np.flatnonzero(laddered.any(axis=1)).max())
    assert reach[11] < 11 <= reach[None]


@pytest.mark.slow
def test_a_run_stop_band_of_a_yarn_with_memory_holds_the_ladder_at_low_tension_not_at_high():
    """docs/snag.md (2026-12-06, 16 x 16, default preset, twist on, two knits per point): two courses (11-12)
    of a yarn that remembers its knitted shape with K = 3, in a jersey of straight yarn, stop the upward
    ladder at course 10 at f_x^ini 4 on both knits; at 8 it crosses them to course 14. One knit each here."""
    reach = {}
    for fx in (4.0, 8.0):
        cfg = CutConfig(n_x=16, n_y=16, fx=fx, band="curvature", band_row=11, band_courses=2, band_curvature=3.0,
                        max_time_ms=10)
        laddered = run_ladder(cfg.settings()).final_laddered
        reach[fx] = int(np.flatnonzero(laddered.any(axis=1)).max())
    assert reach[4.0] < 11 <= reach[8.0]
