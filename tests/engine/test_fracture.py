"""A yarn that breaks (knitlad.engine.fracture): at its breaking force, during a run, with the history kept."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.fracture import breakable_edges

PULL_M_S = 1.0  # slow against the axial waves (1350 m/s): the tension is uniform to 0.1 %


def pulled_yarn(n: int = 21, length_m: float = 0.01):
    """A straight Nylon yarn held at node 0, its last node pulled along x at PULL_M_S."""
    scene = kl.Scene(kl.NYLON)
    points = np.zeros((n, 3))
    points[:, 0] = np.linspace(0.0, length_m, n)
    y = scene.add_yarn(points)
    scene.hold(y, [0])
    scene.hold(y, [n - 1], velocity=(PULL_M_S, 0.0, 0.0))
    return kl.Simulation(scene.build())


WEAK = 10  # the segment given a weak point: 1 % below the Nylon's breaking force


def weak_point(sim):
    strength = np.full(sim.model.edge_a.shape[0], kl.NYLON.breaking_force)
    strength[WEAK] *= 0.99
    return strength


@pytest.mark.slow
def test_a_yarn_pulled_steadily_breaks_at_its_breaking_force():
    """The Nylon (7.9 N, 27 % strain at EA = 28.9 N) with a weak point 1 % below it breaks there when its
    tension reaches that: the recorded tension within 0.5 %, the pull then at (F_b/EA) L within 1 %; one
    segment is cut, the yarn is two, and the piece held at node 0 lets go of its tension."""
    sim = pulled_yarn()
    strength = 0.99 * kl.NYLON.breaking_force
    sim.set_breaking_force(weak_point(sim))
    ea = kl.NYLON.stretching_stiffness
    expected_s = strength / ea * 0.01 / PULL_M_S  # the pull at which the uniform tension reaches F_b
    sim.run(0.95 * expected_s)
    assert sim.breaks == () and sim.tensions_N().max() < strength
    assert abs(sim.reaction_forces_N()[0, 0]) == pytest.approx(0.95 * strength, rel=0.02)
    sim.run(0.1 * expected_s)
    assert len(sim.breaks) == 1
    b = sim.breaks[0]
    assert b.tension_N == pytest.approx(strength, rel=5e-3) and b.tension_N >= strength
    assert b.time_s == pytest.approx(expected_s, rel=0.01)
    assert sim.model.n_yarns == 2 and b.edge == WEAK and b.node == WEAK
    sim.run(0.5e-3)  # the cut end recoils; the piece held at node 0 carries (almost) nothing
    assert abs(sim.reaction_forces_N()[0, 0]) < 0.05 * strength


@pytest.mark.slow
def test_the_ledger_books_the_energy_a_break_cuts_away():
    """The broken segment's spring held T^2 l/(2 EA): the ledger's ``fracture``, within 2 %; with it the
    balance of the whole pull (the work of the moving end) closes within 1 %."""
    sim = pulled_yarn()
    sim.set_breaking_force(weak_point(sim))
    sim.run(3e-3)
    ledger = sim.ledger()
    (b,) = sim.breaks
    segment_m = 0.01 / 20
    assert ledger.fracture == pytest.approx(b.tension_N**2 * segment_m / (2 * kl.NYLON.stretching_stiffness), rel=0.02)
    assert abs(ledger.residual) < 0.01 * ledger.turnover


def test_a_break_keeps_the_friction_history_of_every_other_contact():
    """Cut mid-run in a woven patch at mu 0.4: every touching pair of other segments keeps its tangential
    spring (to 1e-4 of the largest: the forces of the cut model are evaluated at once, which advances each
    spring by one step's slip), the pairs of the cut segment go, and the run goes on."""
    from knitlad.engine.contact import ContactModel
    from knitlad.fabric.scenes.weave import plain_weave

    rods = plain_weave(4, spacing=4 * kl.NYLON.diameter, nodes_per_spacing=6, amplitude=0.4 * kl.NYLON.diameter).build()
    sim = kl.Simulation(rods, contact=ContactModel(stiffness=1e3, mu=0.4), drag_per_s=1e3)
    sim.state.v[:, 2] = 0.01 * np.sin(np.arange(sim.model.n_nodes))  # jiggle: the springs take up slip
    sim.step(300)
    n = int(sim.contacts.n_pairs[0])
    before = {tuple(p): s.copy() for p, s in zip(sim.contacts.pairs[:n], sim.contacts.slip[:n])}
    edge = int(np.flatnonzero(breakable_edges(sim.model))[len(before) % 7 + 3])
    touching_cut = sum(edge in p for p in before)
    sim.cut_edges([edge])
    n = int(sim.contacts.n_pairs[0])
    after = {tuple(p): s for p, s in zip(sim.contacts.pairs[:n], sim.contacts.slip[:n])}
    renumber = lambda k: k - (k > edge)  # noqa: E731
    kept = {(renumber(a), renumber(b)): s for (a, b), s in before.items() if edge not in (a, b)}
    assert len(after) == len(before) - touching_cut
    largest = max(np.abs(s).max() for s in kept.values())
    assert largest > 0
    for pair, slip in kept.items():
        np.testing.assert_allclose(after[pair], slip, atol=1e-4 * largest)
    assert sim.model.n_yarns == rods.model.n_yarns + 1
    sim.step(100)
    assert np.all(np.isfinite(sim.state.x))


def test_a_stretched_knit_holds_its_yarn_whole():
    """The laddering's tensions are some tens of f0 (a few 0.1 N), the Nylon breaks at 530 f0: a cut knit
    ladders with the breaking force on and no segment breaks, its most loaded one far below it."""
    from knitlad.experiments.config import CutConfig
    from knitlad.experiments.laddering import cut
    from knitlad.fabric.preparation import stretch

    cfg = CutConfig(n_x=6, n_y=8, preset="fast", lx=0.38, max_time_ms=0.3)
    run = cut(stretch(cfg.stretch_settings()), cfg.dynamics_settings())
    run.sim.set_breaking_force(kl.NYLON.breaking_force, check_every=10)
    run.sim.run(0.3e-3)
    assert run.sim.breaks == ()
    assert run.sim.tensions_N().max() < 0.1 * kl.NYLON.breaking_force


@pytest.mark.slow
def test_a_uniform_yarn_under_uniform_tension_fragments():
    """Without a weak point every segment reaches the limit together: several break within a few steps, each
    at its limit, none at the held ends' segments (a piece of one node is no rod)."""
    sim = pulled_yarn()
    sim.set_breaking_force(kl.NYLON.breaking_force)
    sim.run(3e-3)
    assert len(sim.breaks) > 1 and max(b.step for b in sim.breaks) - min(b.step for b in sim.breaks) < 50
    assert all(b.tension_N >= kl.NYLON.breaking_force for b in sim.breaks)
    assert all(1 <= b.node <= 18 for b in sim.breaks)


def test_a_breaking_force_must_be_positive():
    sim = pulled_yarn()
    with pytest.raises(ValueError, match="one value or one per segment"):
        sim.set_breaking_force(np.ones(3))
    with pytest.raises(ValueError, match="breaking force must be > 0"):
        sim.set_breaking_force(-1.0)
    with pytest.raises(ValueError, match="check_every"):
        sim.set_breaking_force(1.0, check_every=0)
    with pytest.raises(ValueError, match="Material.breaking_force"):
        kl.Material(breaking_force=0.0)


def test_a_segment_between_two_held_nodes_is_the_supports_and_does_not_break():
    """Two held nodes moved apart stretch the segment between them past the breaking force (their length is
    the supports'): it is not breakable and the run cuts nothing there; the free segments stay breakable."""
    n = 11
    scene = kl.Scene(kl.NYLON)
    points = np.zeros((n, 3))
    points[:, 0] = np.linspace(0.0, 0.01, n)
    y = scene.add_yarn(points)
    scene.hold(y, [0, 1, 2])
    sim = kl.Simulation(scene.build())
    breakable = breakable_edges(sim.model)
    assert not breakable[:2].any() and breakable[2:n - 2].all()  # edges 0-1, 1-2 held at both ends
    sim.state.x[1, 0] *= 1.5  # the support stretches edge 0 by 50 % (14 N in the Nylon)
    sim.set_breaking_force(kl.NYLON.breaking_force)
    sim.run(1e-6)
    assert sim.breaks == ()
