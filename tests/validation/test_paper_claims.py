"""The paper's explanations tested on the fabric (slow; docs/paper_claims.md, docs/reference/velocity24_mu.yaml).

24 x 24 knits of straight yarn (as the paper's DER runs), l_y/l0 = 0.25, the default preset. Measured
2026-12-04 (scripts/paper/velocity_friction.py): at mu = 0, v_lad/c_b = 0.618, 0.786, 1.042, 1.725 at
f_x^ini 2, 4, 8, 16 (a power law of exponent 0.49 +- 0.06: the paper's inertial sqrt(f_x)); at mu = 0.4,
0.293, 0.362, 0.656, 1.052 (exponent 0.64 +- 0.08).
"""

from __future__ import annotations

import pytest

from knitlad.experiments.config import CutConfig
from knitlad.experiments.laddering import analyse, cut, propagate
from knitlad.fabric.preparation import stretch
from knitlad.engine.simulation import numba_threads


def velocities(fx: float, mus: list[float]) -> list[float]:
    """v_lad/c_b of one stretched 24 x 24 knit cut at each mu (paired: the same knit)."""
    cfg = CutConfig(n_x=24, n_y=24, fx=fx, max_time_ms=10)
    with numba_threads(1):
        knit = stretch(cfg.stretch_settings())
        return [analyse(propagate(cut(knit, cfg.replace(mu=mu).dynamics_settings()))).v_lad_over_cb for mu in mus]


@pytest.mark.slow
def test_without_friction_the_ladder_speeds_up_as_the_square_root_of_the_tension_and_friction_slows_it():
    """Paper (Fig. 5c, mu = 0): v_lad/c_b = 0.34 sqrt(f_x), inertial. Quadrupling f_x^ini at mu = 0 then
    doubles v (measured 1.69; a linear law would give 4): between 1.4 and 2.6. Friction slows the same
    knit: at f_x^ini 2, mu = 0.4 runs at less than 2/3 of the frictionless speed (measured 1/2.1)."""
    frictionless, frictional = velocities(2.0, [0.0, 0.4])
    fast = velocities(8.0, [0.0])[0]
    assert 1.4 < fast / frictionless < 2.6
    assert frictional < frictionless / 1.5
    assert 0.34 * 2**0.5 * 0.8 < frictionless < 0.34 * 2**0.5 * 1.6  # the paper's prefactor, within the preset's error
