"""The engine refuses input that is not finite, or calls that would not end, before any kernel runs.

Round 3 of the reliability probes (2026-12-05): with contact on, an infinite force, velocity, displacement
or state ended in a segfault in the contact's grid (exit 139); a settle of infinite time, a ramp at 1e-15 m/s
or over a kilometre hung; ``step(nan)`` said "cannot convert float NaN to integer"; an infinite tangential
stiffness ratio raised ZeroDivisionError; NaN obstacle points and damping ratios were accepted and reported
later as a blow-up; ``guard_every=-5`` reported "blow-up by step -14415".
"""

import math

import numpy as np
import pytest

import knitlad as kl


def crossing_yarns() -> kl.Scene:
    """Two short yarns crossing in contact, the first held at its ends."""
    s = np.linspace(-0.002, 0.002, 9)
    scene = kl.Scene()
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))
    scene.add_yarn(np.column_stack([0 * s, s, 0 * s + 1.3e-4]))
    scene.hold(0, [0, -1])
    return scene


def contact_simulation(scene=None) -> kl.Simulation:
    return kl.Simulation((scene or crossing_yarns()).build(), contact=kl.ContactModel(stiffness=100.0, mu=0.3))


@pytest.mark.parametrize("bad", [math.inf, -math.inf, math.nan, 1e300])
def test_a_scene_refuses_an_infinite_force_or_velocity_naming_it(bad):
    scene = crossing_yarns()
    if bad == 1e300:  # finite: accepted by the scene, refused as a blow-up by the guard, never a crash
        scene.apply_force(1, 4, (bad, 0.0, 0.0))
        sim = contact_simulation(scene)
        with pytest.raises(kl.SimulationBlowUp):
            sim.step(10)
        return
    with pytest.raises(ValueError, match="^force: must be finite"):
        scene.apply_force(1, 4, (bad, 0.0, 0.0))
    with pytest.raises(ValueError, match="^velocity: must be finite"):
        scene.hold(1, [0], velocity=(bad, 0.0, 0.0))


@pytest.mark.parametrize("call, name", [
    (lambda sim: sim.hold(sim.nodes_of(1, [0]), velocity_m_s=(math.inf, 0, 0)), "velocity_m_s"),
    (lambda sim: sim.move_held(sim.nodes_of(0, [0]), by_m=(math.inf, 0, 0)), "by_m"),
    (lambda sim: sim.move_held(sim.nodes_of(0, [0]), to_m=(0, math.nan, 0)), "to_m"),
    (lambda sim: sim.set_external_forces((0, 0, math.inf)), "forces_N"),
])
def test_the_simulation_refuses_an_infinite_input_naming_it_before_anything_runs(call, name):
    sim = contact_simulation()
    x0 = sim.state.x.copy()
    with pytest.raises(ValueError, match=f"^{name}: must be finite"):
        call(sim)
    assert np.array_equal(sim.state.x, x0)
    sim.step(5)  # still usable


@pytest.mark.parametrize("field", ["x", "v"])
def test_an_infinite_state_is_refused_by_step_and_relax_not_crashed_on(field):
    for bad in (math.inf, math.nan):
        sim = contact_simulation()
        getattr(sim.state, field)[7, 1] = bad
        with pytest.raises(ValueError, match=f"state.{field} .*NaN or infinity at node 7; nothing was run"):
            sim.step(1)
        with pytest.raises(ValueError, match=f"state.{field}"):
            sim.relax()
        assert sim.steps == 0


@pytest.mark.parametrize("call, name", [
    (lambda sim: sim.step(math.nan), "n_steps"),
    (lambda sim: sim.step(-1), "n_steps"),
    (lambda sim: sim.step(1e9), "n_steps"),
    (lambda sim: sim.run(math.nan), "duration_s"),
    (lambda sim: sim.run(math.inf), "duration_s"),
    (lambda sim: sim.settle(force_tol_N=1e-300, max_time_s=math.inf, damping_per_s=1e3), "max_time_s"),
    (lambda sim: sim.ramp_held(sim.nodes_of(0, [0]), by_m=(1e-3, 0, 0), speed_m_s=1e-15, damping_per_s=1e3),
     "by_m / speed_m_s"),
    (lambda sim: sim.ramp_held(sim.nodes_of(0, [0]), by_m=(1e3, 0, 0), speed_m_s=0.25, damping_per_s=1e3),
     "by_m / speed_m_s"),
    (lambda sim: sim.relax(max_steps=math.nan), "max_steps"),
])
def test_a_call_that_would_not_end_or_counts_nan_steps_is_refused_at_once(call, name):
    sim = contact_simulation()
    with pytest.raises(ValueError, match=f"^{name}: "):
        call(sim)
    assert sim.steps == 0


def test_models_refuse_values_that_would_break_later_naming_them():
    with pytest.raises(ValueError, match="tangential_stiffness_ratio"):
        kl.ContactModel(stiffness=100.0, tangential_stiffness_ratio=math.inf)
    with pytest.raises(ValueError, match="damping_ratio"):
        kl.ContactModel(stiffness=100.0, damping_ratio=math.nan)
    with pytest.raises(ValueError, match="point_m"):
        kl.Plane(stiffness=100.0, point_m=(0.0, math.nan, 0.0))
    with pytest.raises(ValueError, match="point_m"):
        kl.Cylinder(stiffness=100.0, point_m=(math.inf, 0.0, 0.0))
    with pytest.raises(ValueError, match="damping_ratio"):
        kl.Plane(stiffness=100.0, damping_ratio=math.nan)
    with pytest.raises(ValueError, match="stretch_damping_ratio"):
        crossing_yarns().build(stretch_damping_ratio=math.nan)
    with pytest.raises(ValueError, match="guard_every"):
        kl.Simulation(crossing_yarns().build(), guard_every=-5)


def test_a_removed_setting_still_works_at_its_old_default_with_a_warning_and_refuses_any_other_value():
    """friction_every (the held-friction study, removed in 0.15.0): 1 changed nothing and still works, with a
    DeprecationWarning; 3 would have changed the run, so it is refused, naming the setting."""
    with pytest.warns(DeprecationWarning, match="friction_every"):
        kl.ContactModel(stiffness=100.0, friction_every=1)
    with pytest.warns(DeprecationWarning, match="friction_every"):
        assert kl.CutConfig(fx=3.0, friction_every=1) == kl.CutConfig(fx=3.0)
    with pytest.raises(ValueError, match="friction_every"):
        kl.ContactModel(stiffness=100.0, friction_every=3)
    with pytest.raises(ValueError, match="friction_every"):
        kl.CutConfig(fx=3.0, friction_every=3)


def test_a_contact_count_below_one_and_an_infinite_settling_drag_are_refused_naming_them():
    """Round 4: contacts_per_node=-1 gave "math domain error"; settle(damping_per_s=inf) "check_every_s must be
    positive, got None"."""
    for name in ("contacts_per_node", "capacity_per_edge"):
        for bad in (-1, 0, 1.5):
            with pytest.raises(ValueError, match=name):
                kl.ContactModel(stiffness=100.0, **{name: bad})
    scene = kl.Scene()
    yarn = scene.add_yarn(np.column_stack([np.linspace(0.0, 1e-3, 5), np.zeros(5), np.zeros(5)]))
    scene.hold(yarn, [0])
    sim = kl.Simulation(scene.build())
    with pytest.raises(ValueError, match="damping_per_s must be finite"):
        sim.settle(1e-9, 1e-3, damping_per_s=math.inf)
    with pytest.raises(ValueError, match="force_tol_N must be positive"):
        sim.settle(-1.0, 1e-3, damping_per_s=1e3)
