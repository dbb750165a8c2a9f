"""Normal contact laws (knitlad/engine/kernels/contact_law.py): each law against its closed form, through the
yarn-yarn contact and the obstacles."""

from __future__ import annotations

import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.contact import ContactModel, contact_time_step
from knitlad.engine.kernels.contact_law import (
    LAWS,
    STEP_OVERLAP_OVER_REFERENCE,
    largest_slope_factor,
    normal_spring,
    normal_spring_energy,
)

D = kl.NYLON.diameter
K = 1e3  # N/m
REFERENCE = 0.05 * D  # m


def spring(law: str, delta: float) -> float:
    return normal_spring(LAWS[law][0], K, REFERENCE, delta)


def energy(law: str, delta: float) -> float:
    return normal_spring_energy(LAWS[law][0], K, REFERENCE, delta)


def law_overlap(law: str, force: float) -> float:
    """The overlap at which the law carries ``force`` [N] (its closed form, inverted by hand)."""
    return force / K if law == "linear" else REFERENCE * (force / (K * REFERENCE)) ** (2 / 3)


@pytest.mark.parametrize("law", list(LAWS))
def test_every_law_carries_the_working_force_at_the_reference_overlap_and_is_its_energys_slope(law):
    """f(delta_ref) = k delta_ref for every law (the knit's contact keeps its working point), U(0) = 0, and
    f = dU/d(delta) (central differences, to 1e-6): the law is a potential."""
    assert spring(law, REFERENCE) == pytest.approx(K * REFERENCE, rel=1e-14)
    assert energy(law, 0.0) == 0.0
    for delta in np.array([0.1, 0.7, 1.0, 2.5, 4.0]) * REFERENCE:
        h = 1e-4 * delta
        slope = (energy(law, delta + h) - energy(law, delta - h)) / (2 * h)
        assert slope == pytest.approx(spring(law, delta), rel=1e-6)


def test_hertz_grows_as_the_three_halves_power_of_the_overlap_the_penalty_linearly():
    """Log-log slope of f(delta) over two decades: 3/2 for crossed elastic cylinders (Johnson 1985), 1 for the
    penalty."""
    deltas = np.array([0.1, 10.0]) * REFERENCE
    for law, exponent in (("hertz", 1.5), ("linear", 1.0)):
        forces = [spring(law, d) for d in deltas]
        assert math.log(forces[1] / forces[0]) / math.log(deltas[1] / deltas[0]) == pytest.approx(exponent, rel=1e-12)


@pytest.mark.parametrize("law", list(LAWS))
def test_the_time_steps_slope_bounds_the_law_up_to_the_overlap_it_allows(law):
    """The slope the time step is set by (LAWS) is the law's steepest df/d(delta) up to
    STEP_OVERLAP_OVER_REFERENCE delta_ref, within 0.1 %; a stiffer law gets the shorter contact step."""
    deltas = np.linspace(1e-3, STEP_OVERLAP_OVER_REFERENCE, 4001) * REFERENCE
    forces = np.array([spring(law, d) for d in deltas])
    steepest = float(np.max(np.diff(forces) / np.diff(deltas))) / K
    assert steepest <= largest_slope_factor(law) * (1 + 1e-12)
    assert steepest == pytest.approx(largest_slope_factor(law), rel=1e-3)
    rods = crossing(0.0).build()
    linear = contact_time_step(rods.model, ContactModel(stiffness=K))
    this = contact_time_step(rods.model, ContactModel(stiffness=K, law=law, reference_overlap=REFERENCE))
    ratio = 0.5  # k_t / k_n
    assert this == pytest.approx(linear * math.sqrt((1 + ratio) / (largest_slope_factor(law) + ratio)), rel=1e-12)


def crossing(overlap_m: float) -> kl.Scene:
    """Two straight yarns crossing at right angles mid-edge (10 nodes over 4 mm each), ``overlap_m`` into each
    other, every node held."""
    s = np.linspace(-0.002, 0.002, 10)
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))
    scene.add_yarn(np.column_stack([0 * s, s, 0 * s + D - overlap_m]))
    scene.hold(0, list(range(10)))
    scene.hold(1, list(range(10)))
    return scene


@pytest.mark.parametrize("law", list(LAWS))
def test_two_crossing_yarns_push_each_other_with_the_laws_force_and_store_its_energy(law):
    """At overlaps of 0.5, 1 and 3 delta_ref the pair's normal force is f(delta) and the stored contact energy
    U(delta), through the contact kernel (ContactModel.law)."""
    for factor in (0.5, 1.0, 3.0):
        sim = kl.Simulation(crossing(factor * REFERENCE).build(),
                            contact=ContactModel(stiffness=K, law=law, reference_overlap=REFERENCE))
        sim.compute_forces()
        pairs = sim.contact_pairs()
        assert len(pairs.edges) == 1
        delta = float(pairs.overlap_m[0])
        assert delta == pytest.approx(factor * REFERENCE, rel=1e-9)
        assert float(np.linalg.norm(pairs.normal_N[0])) == pytest.approx(spring(law, delta), rel=1e-9)
        assert sim.energies_J()["contact"] == pytest.approx(energy(law, delta), rel=1e-9)


@pytest.mark.parametrize("law", list(LAWS))
def test_a_yarn_pressed_on_a_plane_settles_at_the_laws_overlap(law):
    """A straight yarn lying on a plane, each node pushed down by 8 k delta_ref: relaxed, every node overlaps
    the plane by the law's overlap for that force (8 delta_ref for the penalty, 4 delta_ref for Hertz), to 1e-6."""
    force = 8.0 * K * REFERENCE
    s = np.linspace(0.0, 0.005, 11)
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([s, 0 * s, np.full_like(s, 0.5 * D)]))
    plane = kl.Plane(stiffness=K, law=law, reference_overlap=REFERENCE)
    sim = kl.Simulation(scene.build(), obstacles=[plane])
    loads = np.zeros((s.size, 3))
    loads[:, 2] = -force
    sim.set_external_forces(loads)
    sim.relax(force_tol_N=1e-9 * force)
    overlaps = 0.5 * D - sim.positions_m()[:, 2]
    np.testing.assert_allclose(overlaps, law_overlap(law, force), rtol=1e-6)


def test_a_law_that_does_not_exist_or_lacks_its_reference_overlap_is_refused_naming_it():
    with pytest.raises(ValueError, match="contact law must be one of linear, hertz, got 'hooke'"):
        ContactModel(stiffness=K, law="hooke")
    with pytest.raises(ValueError, match="hertz contact law needs reference_overlap"):
        ContactModel(stiffness=K, law="hertz")
    with pytest.raises(ValueError, match="reference_overlap must be > 0"):
        kl.Plane(stiffness=K, law="hertz", reference_overlap=-1.0)
    with pytest.raises(ValueError, match="contact_law"):
        kl.CutConfig(n_x=6, n_y=6, fx=4.0, contact_law="hooke")
    assert ContactModel.for_force(1.0, D, overlap_fraction=0.05, law="hertz").reference_overlap == pytest.approx(REFERENCE)
