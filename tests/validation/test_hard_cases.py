"""Numerical stability on hard cases: high tension, strong friction, a jammed
knit, the time step at its limit, a long undamped run, interpenetration.

Each case either runs with every position finite and no two yarns overlapping by more
than a stated fraction of d, or stops before/while running with a one-line error.
Small knits (6 x 8 stitches, 16 nodes per stitch) keep the suite short.
"""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.experiments.config import CutConfig
from knitlad.engine.contact import ContactModel
from knitlad.fabric.observers import Interpenetration
from knitlad.experiments.laddering import analyse, cut, propagate
from knitlad.fabric.preparation import stretch, stretch_contact
from knitlad.fabric.scenes.weave import plain_weave
from knitlad.engine.simulation import energy_history, numba_threads

# The contact is designed to overlap 5 % of d under 20 f0; a quarter of d is five times that.
OVERLAP_BOUND = 0.25


def small(**kw) -> CutConfig:
    return CutConfig(**{**dict(n_x=6, n_y=8, preset="fast", resolution=16, max_time_ms=5.0), **kw})


def run(cfg: CutConfig):
    with numba_threads(1):
        knit = stretch(cfg.stretch_settings())
        laddering = cut(knit, cfg.dynamics_settings())
        res = analyse(propagate(laddering))
    assert np.isfinite(laddering.sim.state.x).all() and np.isfinite(laddering.sim.state.v).all()
    return knit, res


def test_tension_25_is_reached_and_ladders_without_deep_overlap():
    """f_x^ini = 25 (above the paper's highest point, 15.67), force control within 2 %."""
    _, res = run(small(fx=25.0))
    assert res.fx_within_tolerance and res.fx_ini == pytest.approx(25.0, rel=0.02)
    assert 0.0 < res.peak_overlap_over_d < OVERLAP_BOUND
    assert res.n_lad_over_ny >= 0.25 and res.fx_fin < res.fx_ini


def test_friction_08_runs_without_deep_overlap():
    _, res = run(small(lx=0.42, mu=0.8))
    assert res.fx_ini > 2.0
    assert 0.0 < res.peak_overlap_over_d < OVERLAP_BOUND


@pytest.mark.slow
def test_a_jammed_thick_yarn_knit_is_built_narrower_and_runs():
    """d/l0 = 1/20: no jersey centreline holds l0 per stitch at l_x = 0.30 l0, so the knit
    is built at the widest l_x (0.01 l0 steps) where it does, then run as any other."""
    knit, res = run(small(lx=0.24, d_over_l0=1 / 20))
    assert knit.knit.geometry.l_x / knit.settings.material.stitch_length <= 0.23 + 1e-9
    assert res.box_lx_over_l0 == pytest.approx(0.24)
    assert res.peak_overlap_over_d < OVERLAP_BOUND


def test_a_contact_too_soft_for_the_tension_stops_with_an_interpenetration_error():
    """k_n 400 times below the default (20 f0 -> 0.05 f0 at 5 % of d): the loops sink into each other."""
    with pytest.raises(Interpenetration, match=r"yarns overlap by .* d .*raise contact_force_f0"):
        run(small(lx=0.42, contact_force_f0=0.05))


@pytest.mark.parametrize("implicit_axial, predicted_dashpots", [(False, False), (True, False), (False, True),
                                                                (True, True)])
def test_a_knit_stepped_at_the_stability_limit_stays_finite(implicit_axial, predicted_dashpots):
    """safety = 1: the largest step knitlad accepts (Gershgorin bound over stretching,
    bending and contact springs, or contact and bending with implicit axial springs; the
    dashpots' factor for their velocities); 3000 steps of a relaxed 4 x 4 knit with friction."""
    with numba_threads(1):
        knit = stretch(small(n_x=4, n_y=4, lx=0.36).stretch_settings())
        contact = stretch_contact(knit.settings)
        sim = kl.Simulation(knit.knit.rods.copy(), contact=contact, safety=1.0, implicit_axial=implicit_axial,
                            predicted_dashpots=predicted_dashpots)
        if implicit_axial:
            explicit = kl.Simulation(knit.knit.rods.copy(), contact=contact, safety=1.0,
                                     predicted_dashpots=predicted_dashpots)
            assert sim.dt > 1.2 * explicit.dt  # the axial springs no longer bind
        sim.set_friction(0.4)
        sim.step(3000)  # raises SimulationBlowUp on a non-finite value or a supersonic node
        assert np.isfinite(sim.state.x).all()
        assert sim.peak_overlap_m() < OVERLAP_BOUND * kl.NYLON.diameter


def undamped_weave_energy(safety: float, counting: str = "union") -> np.ndarray:
    """Relative change of the total energy of a pressed plain weave, mu = 0, no damping
    anywhere, every 0.05 ms over 0.4 ms. The crossings start 3 % of d into each other."""
    d = kl.NYLON.diameter
    state = plain_weave(4, 1.0e-3, nodes_per_spacing=8, amplitude=0.47 * d).build(stretch_damping_ratio=0.0)
    model = ContactModel.for_force(20 * kl.NYLON.f0, d, mu=0.0, damping_ratio=0.0, tangential_damping_ratio=0.0,
                                   counting=counting)
    with numba_threads(1):
        total, _ = energy_history(kl.Simulation(state, contact=model, safety=safety), 8, 0.05e-3)
    return total[1:] / total[0] - 1.0


@pytest.mark.xfail(strict=True, reason=(
    "known defect of the default counting: the contact is counted once per local minimum of the "
    "distance between two chains of capsules (counted_overlaps). Where a crossing sits at a kink node of both "
    "yarns, each of the four chord pairs around it has its own minimum (here 64 counted pairs for 16 crossings "
    "at t = 0); they merge into one pair and split again as the crossing moves, and a split at finite overlap "
    "adds three penalties at once. Undamped, this weave gains 3 x its energy in 0.4 ms at any dt. The "
    "conservative counting (all_pairs) passes the tests below."
))
def test_union_counting_keeps_a_pressed_weaves_energy():
    """Velocity Verlet on a conservative contact force: bounded energy error, smaller with dt."""
    coarse = np.max(np.abs(undamped_weave_energy(0.5)))
    fine = np.max(np.abs(undamped_weave_energy(0.25)))
    assert coarse < 0.03
    assert fine < coarse / 3


def test_all_pairs_counting_keeps_a_pressed_weaves_energy_and_the_error_falls_with_dt():
    """Counting every touching pair is a sum of pair potentials: energy conserved up to the
    integrator's error. Measured: 0.56 % at 0.35 x the limit (the laddering step), 0.084 % at
    0.175 (1.5 % and 0.44 % at 0.5 and 0.25: below ~0.35 the violent first contacts are resolved)."""
    coarse = np.max(np.abs(undamped_weave_energy(0.35, "all_pairs")))
    fine = np.max(np.abs(undamped_weave_energy(0.175, "all_pairs")))
    assert coarse < 0.01
    assert fine < coarse / 3


def undamped_ladder_energy(safety: float, counting: str) -> float:
    """A 6 x 8 knit stretched to f_x^ini = 13.6 (mu = 0), cut, and left to ladder for 2 ms with
    mu = 0 and no dashpot anywhere (from rest at the cut; the held ends do no work): the
    largest change of the total energy, over the peak kinetic energy."""
    with numba_threads(1):
        cfg = small(fx=13.6, mu=0.0, dt_safety=safety, contact_damping_ratio=0.0, stretch_damping_ratio=0.0,
                    contact_counting=counting, implicit_axial=False)
        sim = cut(stretch(cfg.stretch_settings()), cfg.dynamics_settings()).sim
        sim.state.v[:] = 0.0
        total, kinetic = energy_history(sim, 20, 0.1e-3)
    assert kinetic.max() > 1e-3 * total[0]  # the ladder ran: the check below is not vacuous
    return float(np.max(np.abs(total[1:] - total[0])) / kinetic.max())


@pytest.mark.slow
def test_a_long_undamped_frictionless_ladder_keeps_its_energy_with_all_pairs_counting():
    """The laddering scene itself, undamped, mu = 0, at the laddering step (0.35 x the limit)
    and half of it. Bound: 1 % of the peak kinetic energy, falling with dt (measured 0.045 %
    and 0.019 %; the default union counting: 7.1 % and 8.0 %, not falling; docs/accuracy.md)."""
    coarse = undamped_ladder_energy(0.35, "all_pairs")
    fine = undamped_ladder_energy(0.175, "all_pairs")
    assert coarse < 0.01
    assert fine < coarse / 1.5


@pytest.mark.slow
def test_a_ladder_freed_slowly_is_held_by_friction():
    """16 x 16, f_x^ini = 13.6, under a global drag of 3e4 /s (momentum gone in 33 us): at
    mu = 0.4 the ladder stops before any edge course, at mu = 0 it still runs to one (measured,
    clamped course ends: 0.44 c_b). Undamped, at mu = 0.4, it reaches an edge too (n_lad/n_y
    1.56). So the model's ladders run on the momentum of the freed loops, and friction holds
    loops freed slowly (README). With tail ends the same held: 1.0 damped against 1.5 undamped."""
    with numba_threads(1):
        held = run(CutConfig(n_x=16, n_y=16, fx=13.6, drag_per_s=3e4, preset="fast"))[1]
        free = run(CutConfig(n_x=16, n_y=16, fx=13.6, drag_per_s=3e4, mu=0.0, preset="fast"))[1]
    assert not held.reached_edge
    assert free.reached_edge
