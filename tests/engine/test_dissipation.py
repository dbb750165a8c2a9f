"""knitlad/engine/dissipation.py: the material damping's parameters, the air's, and the energy ledger on rods."""

import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.fabric.scenes.rod import Cantilever


@pytest.mark.parametrize("eta", [0.01, 0.03, 0.1])
def test_the_standard_linear_solid_peaks_at_its_loss_factor_and_frequency(eta):
    """eta(omega) = r omega tau / (1 + (1 + r)(omega tau)^2) is largest, and equal to the asked loss factor, at
    the asked frequency; a decade away it has fallen to a fifth or less (the stated frequency dependence)."""
    m = kl.MaterialDamping(loss_factor=eta, peak_hz=3.1e3)
    assert m.loss_factor_at(3.1e3) == pytest.approx(eta, rel=1e-12)
    f = np.geomspace(3.1e2, 3.1e4, 401)
    assert f[np.argmax([m.loss_factor_at(x) for x in f])] == pytest.approx(3.1e3, rel=0.02)
    assert max(m.loss_factor_at(310.0), m.loss_factor_at(31e3)) < 0.21 * eta
    assert m.storage_factor_at(0.0) == 1.0 and m.storage_factor_at(1e12) == pytest.approx(1 + m.branch_ratio)


@pytest.mark.parametrize("bad", [dict(loss_factor=0.0), dict(loss_factor=-0.1), dict(loss_factor=math.nan),
                                 dict(peak_hz=0.0), dict(peak_hz=math.inf)])
def test_a_material_damping_out_of_range_is_refused_with_its_name(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        kl.MaterialDamping(**bad)


def test_an_air_out_of_range_is_refused_with_its_name():
    with pytest.raises(ValueError, match="density_kg_m3"):
        kl.AirDrag(density_kg_m3=-1.0)
    with pytest.raises(TypeError, match="AirDrag"):
        kl.Simulation(Cantilever(0.02, 11).build()).set_air(1.2)


def swinging_cantilever(**dissipation) -> kl.Simulation:
    rods = Cantilever(0.02, 41).build(tip_force=(0.0, 0.0, -2e-5))
    sim = kl.Simulation(rods, **dissipation)
    tip = 0.02 / kl.units.LENGTH
    sim.state.v[:, 2] = 3.0 / kl.units.VELOCITY * np.clip(sim.state.x[:, 0], 0, None) / tip  # a swing, as if struck
    sim.reset_ledger()
    return sim


@pytest.mark.parametrize("dissipation", [
    {}, {"material_damping": kl.MaterialDamping(0.05, 200.0)}, {"air": kl.AirDrag()}, {"drag_per_s": 300.0}],
    ids=["none", "material", "air", "global drag"])
def test_the_ledger_of_a_swinging_cantilever_closes(dissipation):
    """Energy stored now + energy taken out - work put in = energy stored at the start, to 1e-3 of the energy
    turned over (without dissipation, of the energy stored: Verlet's own error), whatever dissipates; each
    mechanism that is on takes out a share, those off none."""
    sim = swinging_cantilever(**dissipation)
    sim.step(20000)
    ledger = sim.ledger()
    assert abs(ledger.residual) < 1e-3 * (ledger.turnover if dissipation else ledger.start)
    assert ledger.start > 0 and ledger.kinetic > 0
    on = {"material_damping": "material", "air": "air", "drag_per_s": "global_drag"}
    for key, channel in on.items():
        taken = getattr(ledger, channel)
        assert (taken > 0.01 * ledger.start) if key in dissipation else taken == 0.0
    assert ledger.friction == ledger.contact_dashpot == ledger.support_work == 0.0


def test_the_ledger_starts_again_at_a_reset_and_after_a_relaxation():
    sim = swinging_cantilever(air=kl.AirDrag())
    sim.step(2000)
    assert sim.ledger().air > 0
    sim.reset_ledger()
    fresh = sim.ledger()
    assert fresh.air == 0.0 and fresh.time_s == 0.0 and fresh.residual == pytest.approx(0.0, abs=1e-18)
    sim.step(100)
    sim.relax(force_tol_N=1e-9)
    assert sim.ledger().air == 0.0 and sim.ledger().kinetic == 0.0


def test_moving_supports_put_their_work_in_the_ledger():
    """A cantilever whose clamp moves up at a steady speed: the work the clamp does is what the rod gained
    and what its dashpot and the air took out."""
    rods = Cantilever(0.02, 21).build()
    sim = kl.Simulation(rods, air=kl.AirDrag())
    sim.hold(sim.nodes_of(0, [0, 1]), velocity_m_s=(0.0, 0.0, 0.5))
    sim.reset_ledger()
    sim.step(20000)
    ledger = sim.ledger()
    assert ledger.support_work > 0 and ledger.air > 0
    assert abs(ledger.residual) < 1e-3 * ledger.support_work


def test_the_authors_drag_converts_from_their_units_by_the_axial_wave_time_over_a_radius():
    """Their engine's units (jersey.c, main.c): a segment of one yarn radius r, a node of mass 1, k0 = EA = 1; a
    force -lambda v on a node is a rate lambda / (r sqrt(rho_L/EA)). The paper's Nylon: 1.94e7 lambda /s."""
    from knitlad.engine.dissipation import authors_contact_dashpot, authors_drag_per_s

    nylon = kl.Material()
    tau = 0.07e-3 * math.sqrt(15.8e-6 / (1.88e9 * math.pi * 0.14e-3**2 / 4))
    assert authors_drag_per_s(1e-4, nylon) == pytest.approx(1e-4 / tau, rel=1e-12)
    assert authors_drag_per_s(1e-4, nylon) == pytest.approx(1.94e3, rel=0.01)
    assert authors_contact_dashpot(nylon) == pytest.approx(math.sqrt(1.88e9 * math.pi * 0.14e-3**2 / 4 * 15.8e-6))
    with pytest.raises(ValueError, match="drag_lambda"):
        authors_drag_per_s(-1.0, nylon)


def test_a_spin_drag_decays_a_uniform_spin_at_its_rate_and_the_ledger_counts_it():
    """A free straight rod spinning as one body about its axis carries no twist strain: under a drag
    -gamma I omega on every edge's spin its spin decays as exp(-gamma t) (to Verlet's order), and the energy it
    loses is what the ledger's global drag took (the residual under 1e-3 of it, as the nodes' drag's)."""
    rods = Cantilever(0.02, 41).build(twist=True)
    rods = rods.replace_model(held=np.zeros_like(rods.model.held), theta_held=np.zeros_like(rods.model.theta_held))
    gamma = 2e3
    sim = kl.Simulation(rods, spin_drag_per_s=gamma)
    sim.state.omega[:] = 1e3 * kl.units.TIME  # 1000 rad/s
    sim.reset_ledger()
    steps = 2000
    sim.step(steps)
    t = steps * sim.dt_s
    assert gamma * t > 0.5  # a decay worth measuring
    # within what a first-order drag in the step would miss, gamma^2 dt t
    assert np.allclose(sim.state.omega / kl.units.TIME, 1e3 * math.exp(-gamma * t), rtol=gamma**2 * sim.dt_s * t)
    ledger = sim.ledger()
    assert ledger.global_drag == pytest.approx(ledger.start - ledger.kinetic, rel=1e-3, abs=0)
    assert abs(ledger.residual) < 1e-3 * ledger.turnover
