"""The single-loop model (paper Fig. 5b,c): the loop holds while the lower row is there, lets
go once it is removed, faster under more tension and slower with more friction; the release
time is converged in the resolution. At mu = 0 the tension-driven part of v_lad^2 has the
paper's prefactor, beta = 0.34 within 10 %, but the loop's own bending recoil adds to it, so
the paper's law 0.34 sqrt(f_x) itself is *not* reproduced (pinned below as a known deviation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from knitlad.experiments.config import LoopConfig
from knitlad.experiments.loop_model import LoopRun
from knitlad.fabric.topology import piercings
from tests.validation.references import paper_der_line


def release(fx: float, mu: float, resolution: int = 36):
    r = LoopRun(LoopConfig(fx=fx, mu=mu, resolution=resolution).settings()).run()
    assert r.released, f"f_x = {fx}, mu = {mu}: the loop did not let go"
    return r


def test_the_loop_stays_hooked_while_the_lower_row_is_there():
    run = LoopRun(LoopConfig(fx=4.0, mu=0.0).settings())
    run.relax()
    s, sc, start = run.sim.state, run.scene, run.sim.model.yarn_start
    loop = slice(int(start[sc.loop]), int(start[sc.loop + 1]))
    upper = slice(int(start[sc.upper]), int(start[sc.upper + 1]))
    lower = slice(int(start[sc.lower]), int(start[sc.lower + 1]))
    assert run.result.relax_converged
    assert piercings(s.x[loop], s.x[upper]) == (2, 0)  # the upper row threads the loop
    assert piercings(s.x[lower], s.x[loop]) == (2, 0)  # the loop threads the lower row
    run.sim.run(200e-6)  # at mu = 0 nothing but the lower row holds the loop against f_x
    assert piercings(s.x[loop], s.x[upper]) == (2, 0)
    # the pulled ends stayed on their rails (y, z unchanged)
    for end in (loop.start, loop.stop - 1):
        assert abs(run.sim.state.v[end, 1]) < 1e-12 and abs(run.sim.state.v[end, 2]) < 1e-12


def test_the_release_time_is_converged_in_the_resolution():
    """36 against 48 nodes per stitch: within 5 % (measured 0.6 % to 2.7 % for f_x = 2 to 16)."""
    coarse, fine = release(4.0, 0.0, 36), release(4.0, 0.0, 48)
    assert coarse.tau_s == pytest.approx(fine.tau_s, rel=0.05)


def test_more_tension_releases_faster():
    v2, v8 = release(2.0, 0.0).v_lad_over_cb, release(8.0, 0.0).v_lad_over_cb
    assert v8 > 1.2 * v2  # measured 1.63x


def test_friction_slows_the_release():
    """Paper Fig. 5c: the lower the friction, the higher the velocity (f_x = 4: measured 0.977, 0.890, 0.861)."""
    v = [release(4.0, mu).v_lad_over_cb for mu in (0.0, 0.4, 0.8)]
    assert v[0] > v[1] > v[2]


@pytest.mark.slow
def test_the_freed_loop_leaves_on_its_momentum_not_quasi_statically():
    """Why the model is inertial at every f_x (the paper's mu = 0 law is, its mu > 0 ones are not):
    a weak drag (2e3 /s, decay time 0.5 ms, longer than the ~70 us release) changes v_lad by a few
    per cent (measured -1.4 %, f_x = 8, mu = 0), but a drag that takes the loop's momentum within
    50 us (2e4 /s) leaves it hooked to the upper row: freed slowly, the loop finds an equilibrium."""
    free = release(8.0, 0.0).v_lad_over_cb
    weak = LoopRun(LoopConfig(fx=8.0, mu=0.0).settings(drag_per_s=2e3)).run()
    assert weak.released and weak.v_lad_over_cb == pytest.approx(free, rel=0.05)
    strong = LoopRun(LoopConfig(fx=8.0, mu=0.0, max_time_ms=3.0).settings(drag_per_s=2e4)).run()
    assert not strong.released


def test_at_mu_0_the_tension_driven_part_of_v_squared_has_the_papers_prefactor():
    """At mu = 0 nothing dissipates, and the freed loop leaves on the kinetic energy it gains:
    the work of the tension, proportional to f_x, plus its own bending recoil (a loop of a rod
    with no natural curvature unbends once the lower row is gone: it lets go at 0.50 c_b even
    at f_x = 0.05). So v_lad^2 = v_0^2 + beta^2 f_x, and the paper's inertial law is the
    recoil-free limit beta sqrt(f_x), beta = 0.34 (Fig. 5c, dashed). beta from a straight line
    through v^2 at f_x = 2, 4, 8, 12 (above 12 the held upper row starts to trap the loop's
    head, README), within 10 %: the fit's standard error on beta is ~4 % and 36 against 48
    nodes per stitch moves it by 3 %. Measured: beta = 0.366 (36 nodes), 0.356 (48), with
    v_0 = 0.58 c_b, which is why the absolute law below fails."""
    fx = np.array([2.0, 4.0, 8.0, 12.0])
    v = np.array([release(f, 0.0).v_lad_over_cb for f in fx])
    beta_sq, v0_sq = np.polyfit(fx, v**2, 1)
    assert math.sqrt(beta_sq) == pytest.approx(0.34, rel=0.10)
    assert v0_sq > 0  # the recoil: without it the law would be the paper's


@pytest.mark.xfail(strict=True, reason="known deviation: the model's v_lad/c_b at mu = 0 is 0.98 at f_x = 4, "
                   "44 % above the paper's 0.34 sqrt(f_x) = 0.68 (the held upper row and the loop's own "
                   "bending recoil); see the README, single-loop model")
def test_inertial_law_of_the_paper_at_mu_0():
    assert release(4.0, 0.0).v_lad_over_cb == pytest.approx(0.34 * math.sqrt(4.0), rel=0.15)


@pytest.mark.xfail(strict=True, reason="known deviation: at mu = 0.4 the model's v_lad/c_b is 1.16 at f_x = 8, "
                   "twice the paper's 42 x 42 DER line (0.57; our own 42 x 42 knit: 0.74); see the README, "
                   "single-loop model")
def test_at_mu_0_4_the_loop_matches_the_papers_fabric():
    """Paper Fig. 5c: at mu = 0.4 the single loop agrees with the 42 x 42 DER runs (0.176 c_b at
    f_x 1.58, 1.05 at 15.67, a straight line between them) without adjustable parameters."""
    assert release(8.0, 0.4).v_lad_over_cb == pytest.approx(paper_der_line(8.0), rel=0.2)
