"""Rod core against analytic rod mechanics (statics, dynamics, convergence)."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.fabric.scenes.rod import Cantilever
from tests.validation.references import elastica_tip

B = kl.NYLON.bending_stiffness


def relaxed_tip(cantilever: Cantilever, force: float) -> np.ndarray:
    sim = kl.Simulation(cantilever.build(tip_force=(0.0, -force, 0.0)))
    result = sim.relax(force_tol_N=force * 1e-6, max_steps=3_000_000)
    assert result["converged"], result
    return sim.positions_m()[-1]


def test_small_deflection_cantilever_matches_FL3_over_3B():
    """Euler-Bernoulli: delta = F L^3 / (3 B); 41 nodes, error < 0.1 %."""
    c = Cantilever(length=0.02, n_nodes=41)
    force = 1e-3 * B / c.length**2
    tip = relaxed_tip(c, force)
    err = abs(-tip[1] / c.small_deflection(force) - 1.0)
    assert err < 1e-3, f"relative error {err:.2e}"


def test_cantilever_deflection_converges_at_second_order_in_segment_length():
    """Halving the segment length divides the deflection error by ~4 (O(h^2))."""
    errors = []
    for n in (11, 21, 41):
        c = Cantilever(length=0.02, n_nodes=n)
        force = 1e-3 * B / c.length**2
        tip = relaxed_tip(c, force)
        errors.append(abs(-tip[1] / c.small_deflection(force) - 1.0))
    h = np.array([Cantilever(0.02, n).segment for n in (11, 21, 41)])
    order = np.polyfit(np.log(h), np.log(errors), 1)[0]
    assert 1.8 < order < 2.2, f"observed order {order:.2f}, errors {errors}"


def test_large_deflection_matches_the_elastica():
    """P L^2 / B = 3: tip at (0.7456, -0.6033) L from the shooting solution; error < 0.2 % of L."""
    c = Cantilever(length=0.02, n_nodes=61)
    alpha = 3.0
    tip = relaxed_tip(c, alpha * B / c.length**2) / c.length
    x_ref, y_ref = elastica_tip(alpha)
    assert abs(tip[0] - x_ref) < 2e-3 and abs(tip[1] - y_ref) < 2e-3, (tip, (x_ref, y_ref))


def test_reaction_forces_balance_the_load():
    """The supports carry the tip load: sum of reactions = -applied force (to 1e-9)."""
    c = Cantilever(length=0.02, n_nodes=21)
    force = 0.5 * B / c.length**2
    sim = kl.Simulation(c.build(tip_force=(0.0, -force, 0.0)))
    sim.relax(force_tol_N=force * 1e-8, max_steps=3_000_000)
    reaction = sim.reaction_forces_N().sum(axis=0)
    np.testing.assert_allclose(reaction, [0.0, force, 0.0], atol=force * 1e-6)


@functools.lru_cache(maxsize=None)
def _loaded(length: float, n_nodes: int, damping: float):
    """The cantilever in its shape under a small tip load F = 1e-3 B/L^2: Euler-Bernoulli's y(x) = -F x^2 (3L - x)
    / 6B from the clamp, the free nodes a rest length apart along it (a static solve to the discrete shape took
    28 s; the two differ by O(h^2), which the tests below do not see)."""
    c = Cantilever(length=length, n_nodes=n_nodes)
    force = 1e-3 * B / length**2
    rods = c.build(tip_force=(0.0, -force, 0.0), stretch_damping_ratio=damping)
    h = c.segment
    x = np.linspace(0.5 * h, 2.0 * length, 200_001)
    y = -force * x**2 * (3.0 * length - x) / (6.0 * B)
    y -= y[0]  # node 1, held on the axis, starts the curve
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    along = (np.arange(1, n_nodes) - 1) * h
    rods.state.x[1:, 0] = np.interp(along, arc, x) / kl.units.LENGTH
    rods.state.x[1:, 1] = np.interp(along, arc, y) / kl.units.LENGTH
    return rods


def oscillate(c: Cantilever, dt_s: float | None, periods: float, damping: float = 0.0, implicit_axial: bool = False):
    """Release the cantilever from its statically loaded shape; tip y(t) and energies."""
    rods = _loaded(c.length, c.n_nodes, damping).copy()
    rods = rods.replace_model(f_ext=0.0 * rods.model.f_ext)
    sim = kl.Simulation(rods, dt_s=dt_s, implicit_axial=implicit_axial)
    period = 2 * math.pi / c.first_frequency()
    times, tips, totals = [], [], []

    def record(s: kl.Simulation) -> None:
        times.append(s.time_s)
        tips.append(s.state.x[-1, 1])
        totals.append(s.energies_J()["total"])

    record(sim)
    sim.run(periods * period, observe=record, observe_every_s=period / 200)
    return np.array(times), np.array(tips), np.array(totals), sim


def test_first_bending_frequency_of_the_cantilever():
    """omega_1 = 1.8751^2 sqrt(B / (rho_L L^4)); 41 nodes, error < 0.5 %."""
    c = Cantilever(length=0.02, n_nodes=41)
    t, y, _, _ = oscillate(c, None, periods=3.0)
    # upward zero crossings of the tip, linearly interpolated
    idx = np.where((y[:-1] < 0) & (y[1:] >= 0))[0]
    crossings = t[idx] - y[idx] * (t[idx + 1] - t[idx]) / (y[idx + 1] - y[idx])
    assert len(crossings) >= 2
    omega = 2 * math.pi / np.mean(np.diff(crossings))
    err = abs(omega / c.first_frequency() - 1.0)
    assert err < 5e-3, f"relative frequency error {err:.2e}"


def test_energy_is_conserved_without_damping_and_the_error_is_second_order_in_dt():
    """Velocity Verlet: bounded energy error, O(dt^2): halving dt divides it by ~4."""
    c = Cantilever(length=0.02, n_nodes=21)
    probe = kl.Simulation(c.build())
    drifts = []
    for factor in (0.5, 0.25):
        dt = factor * probe.limits.combined * kl.units.TIME
        _, _, total, _ = oscillate(c, dt, periods=2.0)
        scale = total[0]  # the elastic energy of the released shape
        drifts.append(np.max(np.abs(total - total[0])) / scale)
    assert drifts[0] < 1e-3, drifts
    ratio = drifts[0] / drifts[1]
    assert 3.0 < ratio < 5.0, f"energy error ratio {ratio:.2f} for dt halved (expect 4)"


def axial_energy_history(damping: float, periods: float = 5.0, dt_over_limit: float | None = None) -> np.ndarray:
    """A free rod stretched uniformly by 1e-4 and released: total energy per sample. ``dt_over_limit``:
    the axial springs implicit, stepped at that multiple of their explicit stability limit."""
    n = 21
    pts = np.zeros((n, 3))
    pts[:, 0] = np.linspace(0.0, 0.01, n)
    scene = kl.Scene()
    scene.add_yarn(pts)
    rods = scene.build(stretch_damping_ratio=damping)
    rods.state.x[:, 0] *= 1.0 + 1e-4
    if dt_over_limit is None:
        sim = kl.Simulation(rods)
    else:
        dt = dt_over_limit * kl.Simulation(rods.copy()).limits.stretching * kl.units.TIME
        sim = kl.Simulation(rods, dt_s=dt, implicit_axial=True)
    period = 2 * 0.01 / kl.NYLON.axial_wave_speed  # fundamental free-free axial mode
    totals = [sim.energies_J()["total"]]
    sim.run(periods * period, observe=lambda s: totals.append(s.energies_J()["total"]), observe_every_s=period / 50)
    return np.array(totals)


def test_axial_dashpot_dissipates_axial_vibration_and_never_adds_energy():
    undamped = axial_energy_history(0.0)
    damped = axial_energy_history(0.5)
    # a uniform release excites axial modes up to the stability limit, where Verlet's
    # (bounded, non-secular) energy error is a few percent at the default dt
    assert np.max(np.abs(undamped / undamped[0] - 1.0)) < 5e-2
    assert damped[-1] < 0.1 * damped[0]
    assert np.all(np.diff(damped) <= 1e-3 * damped[0])


def test_axial_dashpot_leaves_bending_vibration_undamped():
    """Kelvin-Voigt damping acts on the stretch rate only, not on bending."""
    c = Cantilever(length=0.02, n_nodes=21)
    _, _, total, _ = oscillate(c, None, periods=2.0, damping=1.0)
    assert abs(total[-1] / total[0] - 1.0) < 1e-3


def test_implicit_axial_springs_keep_the_first_bending_frequency_at_a_step_set_by_bending():
    """The bending waves, which carry a ladder, are those of the explicit springs: omega_1 within
    0.5 %, at 0.7 x the bending limit, which is over 5 x the axial springs' explicit limit."""
    c = Cantilever(length=0.02, n_nodes=41)
    explicit = kl.Simulation(c.build()).limits
    t, y, total, sim = oscillate(c, None, periods=3.0, implicit_axial=True)
    assert sim.dt > 5 * explicit.stretching and math.isinf(sim.limits.stretching)
    idx = np.where((y[:-1] < 0) & (y[1:] >= 0))[0]
    crossings = t[idx] - y[idx] * (t[idx + 1] - t[idx]) / (y[idx + 1] - y[idx])
    omega = 2 * math.pi / np.mean(np.diff(crossings))
    assert abs(omega / c.first_frequency() - 1.0) < 5e-3
    assert abs(total[-1] / total[0] - 1.0) < 1e-3  # bending barely feeds the damped axial modes


def test_implicit_axial_springs_stretch_a_pulled_yarn_by_FL_over_EA():
    """Statics are the explicit springs': a yarn held at one end and pulled by F at the other,
    brought to rest by drag at 0.7 x the bending limit, extends by F L / EA (to 1e-6) and its
    support carries F (to 1e-9)."""
    n, length, force = 41, 0.05, 1e-2
    pts = np.zeros((n, 3))
    pts[:, 0] = np.linspace(0.0, length, n)
    scene = kl.Scene()
    y = scene.add_yarn(pts)
    scene.hold(y, [0])
    scene.apply_force(y, -1, (force, 0.0, 0.0))
    rods = scene.build()
    explicit = kl.Simulation(rods.copy()).limits
    sim = kl.Simulation(rods, implicit_axial=True, drag_per_s=2e3)
    assert sim.dt > 5 * explicit.combined
    sim.run(0.02)
    ea = kl.NYLON.young_modulus * math.pi * kl.NYLON.diameter**2 / 4
    extension = sim.positions_m()[-1, 0] - length
    assert abs(extension / (force * length / ea) - 1.0) < 1e-6
    np.testing.assert_allclose(sim.reaction_forces_N().sum(axis=0), [-force, 0.0, 0.0], atol=force * 1e-9)


@pytest.mark.parametrize("implicit_axial", [False, True])
def test_a_yarn_whose_end_slides_on_a_rail_extends_by_FL_over_EA_and_the_rail_carries_the_load_across_it(
        implicit_axial):
    """A yarn held at one end, its other end on a rail along the yarn (a clip sliding along a bar), pulled by
    F along the rail and by P across it: at rest (drag) it extends by F L / EA (to 1e-6), and the reactions
    are those of statics: the support carries -F along, the rail -P across (to 1e-9), with explicit or
    implicit axial springs."""
    n, length, force, across = 41, 0.05, 1e-2, 3e-3
    pts = np.zeros((n, 3))
    pts[:, 0] = np.linspace(0.0, length, n)
    scene = kl.Scene()
    y = scene.add_yarn(pts)
    scene.hold(y, [0])
    scene.slide(y, [n - 1], (1.0, 0.0, 0.0))
    scene.apply_force(y, -1, (force, 0.0, across))
    sim = kl.Simulation(scene.build(), implicit_axial=implicit_axial, drag_per_s=2e3)
    sim.run(0.02)
    ea = kl.NYLON.young_modulus * math.pi * kl.NYLON.diameter**2 / 4
    assert abs((sim.positions_m()[-1, 0] - length) / (force * length / ea) - 1.0) < 1e-6
    assert abs(sim.positions_m()[-1, 2]) < 1e-12  # on its rail
    reactions = sim.reaction_forces_N()
    np.testing.assert_allclose(reactions[0], [-force, 0.0, 0.0], atol=force * 1e-9)
    np.testing.assert_allclose(reactions[-1], [0.0, 0.0, -across], atol=force * 1e-9)


def yarn_on_a_clipped_rail(pull: float, press: float, mu: float, implicit_axial: bool = False) -> kl.Simulation:
    """A straight yarn along x, every node in a clip on a rail along x with Coulomb coefficient ``mu``, pulled
    along the rail and pressed across it by ``pull`` and ``press`` [m/s^2] times its mass: every node feels the
    same acceleration, so the yarn moves as one block on a rough plane (its springs stay at rest)."""
    n = 11
    pts = np.zeros((n, 3))
    pts[:, 0] = np.linspace(0.0, 0.01, n)
    scene = kl.Scene()
    y = scene.add_yarn(pts)
    scene.slide(y, range(n), (1.0, 0.0, 0.0), friction=mu)
    mass = scene.build().model.mass * kl.units.MASS
    for i in range(n):  # pressed obliquely: the normal reaction is the whole force across the rail
        scene.apply_force(y, i, mass[i] * np.array([pull, 0.6 * press, -0.8 * press]))
    return kl.Simulation(scene.build(), implicit_axial=implicit_axial)


@pytest.mark.parametrize("implicit_axial", [False, True], ids=["explicit", "implicit axial"])
def test_a_clip_holds_below_mu_N_and_slides_above_with_the_coulomb_deceleration(implicit_axial):
    """Coulomb friction of a rail (``Scene.slide(friction=mu)``): pulled at 0.8 mu N the yarn stays at rest to
    round-off and its clips carry the pull; pulled at 1.6 mu N it slides with a = (pull - mu press), its
    displacement 1/2 a t^2 to 1e-9 (Verlet is exact under constant force), and the ledger's friction is mu N
    times the distance and the ledger closes, both to half a step's friction loss, mu N u dt / 2 = friction dt/t
    (the ledger counts each evaluation's loss over a whole kick; a run ends on half a kick)."""
    mu, press = 0.5, 100.0
    held = yarn_on_a_clipped_rail(0.8 * mu * press, press, mu, implicit_axial)
    x0 = held.positions_m().copy()
    held.step(2000)
    assert np.abs(held.positions_m() - x0).max() < 1e-15
    assert held.ledger().friction == 0.0
    total_mass = held.model.mass.sum() * kl.units.MASS
    assert held.reaction_forces_N()[:, 0].sum() == pytest.approx(-0.8 * mu * press * total_mass, rel=1e-12)

    sliding = yarn_on_a_clipped_rail(1.6 * mu * press, press, mu, implicit_axial)
    sliding.reset_ledger()
    sliding.step(2000)
    distance = sliding.positions_m()[:, 0] - x0[:, 0]
    expected = 0.5 * 0.6 * mu * press * sliding.time_s**2
    np.testing.assert_allclose(distance, expected, rtol=1e-9)
    ledger = sliding.ledger()
    half_step_loss = ledger.friction * sliding.dt_s / sliding.time_s
    assert abs(ledger.friction - mu * press * total_mass * expected) < 1.01 * half_step_loss
    assert abs(ledger.residual) < 1.01 * half_step_loss


def test_a_clip_stops_a_sliding_yarn_at_u0_squared_over_2_mu_g_and_keeps_it_there():
    """Launched along its rail at u0 with no pull, the yarn decelerates at mu g and stops at u0^2/(2 mu g)
    (to one step's travel), then stays stopped: the clip sticks, with no creep and no reversal."""
    mu, press, u0 = 0.5, 100.0, 0.05
    sim = yarn_on_a_clipped_rail(0.0, press, mu)
    sim.state.v[:, 0] = u0 / kl.units.VELOCITY
    sim.compute_forces()
    x0 = sim.positions_m()[:, 0].copy()
    stop_s = u0 / (mu * press)
    sim.run(1.5 * stop_s)
    travel = sim.positions_m()[:, 0] - x0
    assert np.abs(travel - u0**2 / (2 * mu * press)).max() < u0 * sim.dt_s
    stopped = sim.positions_m().copy()
    sim.run(0.5 * stop_s)
    assert np.abs(sim.positions_m() - stopped).max() < 1e-15


def test_implicit_axial_springs_damp_axial_vibration_and_never_add_energy():
    """Stepped at 4 x their explicit limit without any dashpot, the released axial vibration
    decays (backward Euler in the springs) and the energy never rises (to 1e-9)."""
    totals = axial_energy_history(0.0, dt_over_limit=4.0)
    assert totals[-1] < 0.1 * totals[0]
    assert np.all(np.diff(totals) <= 1e-9 * totals[0])


def damped_spring_error(dt_over_period: float, predicted: bool, zeta: float = 0.3) -> float:
    """One free node on a held one, joined by an axial spring and its dashpot, released from 1e-4 of
    stretch: the largest error of its position over two periods against the damped oscillator."""
    scene = kl.Scene()
    y = scene.add_yarn(np.array([[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0]]))
    scene.hold(y, [0])
    rods = scene.build(stretch_damping_ratio=zeta)
    m = rods.model
    k, c, mass = m.EA[0] / m.rest_length[0], m.stretch_damping[0], m.mass[1]
    omega, z = math.sqrt(k / mass), c / (2 * math.sqrt(k * mass))
    omega_d = omega * math.sqrt(1 - z * z)
    x0 = rods.state.x[1, 0]
    delta = 1e-4 * m.rest_length[0]
    rods.state.x[1, 0] += delta
    period = 2 * math.pi / omega * kl.units.TIME  # s
    sim = kl.Simulation(rods, dt_s=dt_over_period * period, predicted_dashpots=predicted)
    errors = []

    def compare(s: kl.Simulation) -> None:
        t = s.time
        exact = delta * math.exp(-z * omega * t) * (math.cos(omega_d * t) + z / math.sqrt(1 - z * z) * math.sin(omega_d * t))
        errors.append(abs(s.state.x[1, 0] - x0 - exact) / delta)

    sim.run(2 * period, observe=compare, observe_every_s=sim.dt_s)
    return max(errors)


def test_dashpots_on_predicted_velocities_are_second_order_in_dt_and_half_step_ones_first():
    """A damped oscillator (zeta 0.3): halving dt divides the error by ~4 with predicted velocities
    (DASHPOTS_PREDICTED), by ~2 with the half-step ones, which are also the larger."""
    half_step = [damped_spring_error(f, predicted=False) for f in (0.02, 0.01)]
    predicted = [damped_spring_error(f, predicted=True) for f in (0.02, 0.01)]
    assert 1.6 < half_step[0] / half_step[1] < 2.5, half_step
    assert 3.5 < predicted[0] / predicted[1] < 4.5, predicted
    assert predicted[1] < 0.2 * half_step[1]
