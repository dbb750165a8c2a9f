"""The laddering protocol: its stages after the stretch (knitlad.fabric.preparation), and the choices that measurements made."""

from __future__ import annotations

import numpy as np
import pytest

from knitlad.engine import units
from knitlad.experiments.config import CutConfig
from knitlad.experiments.laddering import analyse, cut, propagate
from knitlad.fabric.preparation import KnitBox, stretch
from knitlad.engine.timestep import DEFAULT_SAFETY
from knitlad.engine.units import NYLON


def config(**kw) -> CutConfig:
    """The coarse model these tests run (the fast preset: capsules of the yarn's radius, explicit axial springs)."""
    return CutConfig(**{"preset": "fast", **kw})


def test_dashpot_and_drag_settings_reach_the_knit_and_the_laddering_dynamics():
    """The dissipation of the dynamics after the cut is set from the dynamics' settings alone (the
    damping study and scripts/energy_drift.py at commit 56421cd switch it off this way)."""
    cfg = config(n_x=4, n_y=4, resolution=16, lx=0.30, contact_damping_ratio=0.0, stretch_damping_ratio=0.0,
                 drag_per_s=3e3)
    box = KnitBox(cfg.stretch_settings())
    # the mu = 0 stretch (FIRE) keeps its own dashpots and no drag: they only shape its path
    assert box.knit.rods.model.stretch_damping.min() > 0 and box.sim.contact_model.damping_ratio == 0.3
    assert box.sim.drag == 0.0
    knit = stretch(cfg.stretch_settings())
    run = cut(knit, cfg.dynamics_settings())
    assert not run.sim.model.stretch_damping.any()
    assert run.sim.contact_model.damping_ratio == 0.0 and run.sim.contact_model.tangential_damping_ratio == 0.0
    assert run.sim.drag == pytest.approx(3e3 * units.TIME)
    assert knit.knit.rods.model.stretch_damping.min() > 0  # the stretched knit is untouched


def test_the_stretched_knit_does_not_depend_on_the_laddering_time_step():
    """dt_safety sets the step of the dynamics after the cut only: a stretch at another step
    would end in another relaxed state, and the ladder from it differs by the knit's scatter
    (16 x 16 at f_x = 3.9: v_lad 0.27 against 0.49), which would pass for an effect of dt."""
    knits, steps = [], []
    for dt in (0.35, 0.175):
        cfg = config(n_x=4, n_y=4, resolution=16, lx=0.34, dt_safety=dt)
        knit = stretch(cfg.stretch_settings())
        run = cut(knit, cfg.dynamics_settings())
        knits.append(knit)
        steps.append(run.sim.dt / run.sim.limits.combined)
    assert np.array_equal(knits[0].knit.rods.state.x, knits[1].knit.rods.state.x)
    assert knits[0].fx_ini == knits[1].fx_ini
    assert steps == pytest.approx([0.35, 0.175], rel=1e-9)


@pytest.mark.parametrize("name", ["contact_damping_ratio", "stretch_damping_ratio", "drag_per_s"])
def test_a_negative_dissipation_setting_is_refused_before_anything_runs(name):
    with pytest.raises(ValueError, match=name):
        config(fx=4.0, **{name: -0.1})


def test_an_unknown_contact_counting_is_refused_before_anything_runs():
    with pytest.raises(ValueError, match="contact_counting"):
        config(fx=4.0, contact_counting="every")


def test_one_stretched_knit_cut_twice_ladders_like_two_fresh_runs():
    """Studies of the laddering dynamics compare settings from one stretched knit: cutting it
    leaves it untouched, and each cut gives the very ladder a fresh run with those settings gives
    (the stretch is deterministic and does not read them)."""
    base = dict(n_x=4, n_y=4, resolution=16, lx=0.34, max_time_ms=0.2)
    knit = stretch(config(**base).stretch_settings())
    x_before = knit.knit.rods.state.x.copy()
    other = config(**base, mu=0.0, drag_per_s=1e3)
    first = analyse(propagate(cut(knit, other.dynamics_settings())))
    assert np.array_equal(knit.knit.rods.state.x, x_before)  # the knit is untouched
    again = analyse(propagate(cut(knit, other.dynamics_settings())))
    fresh = analyse(propagate(cut(stretch(other.stretch_settings()), other.dynamics_settings())))
    assert first.settings.dynamics.mu == 0.0
    assert first.fx_series == again.fx_series == fresh.fx_series
    assert [np.array_equal(a, b) for a, b in zip(first.frames, fresh.frames)] == [True] * len(fresh.frames)


def test_a_stretched_knit_written_and_read_back_ladders_the_same(tmp_path):
    """A stretched knit is a value that can be stored: the one read back ladders bit for bit
    as the one in memory."""
    from knitlad.io.hdf5 import read_stretched_knit, write_stretched_knit

    cfg = config(n_x=4, n_y=4, resolution=16, lx=0.34, max_time_ms=0.1)
    knit = stretch(cfg.stretch_settings())
    read = read_stretched_knit(write_stretched_knit(tmp_path / "stretched.h5", knit))
    assert read.settings == knit.settings and read.fx_ini == knit.fx_ini and read.dt_s == knit.dt_s
    a = analyse(propagate(cut(knit, cfg.dynamics_settings())))
    b = analyse(propagate(cut(read, cfg.dynamics_settings())))
    assert a.fx_series == b.fx_series and np.array_equal(a.frames[-1], b.frames[-1])


def test_observers_and_stop_rules_are_handed_to_the_run_loop():
    """propagate calls the observers it is given with (t, run, the cells' reading) and stops by the rules."""
    from knitlad.fabric.observers import TimeLimit

    cfg = config(n_x=4, n_y=4, resolution=16, lx=0.34)
    seen = []

    class Counter:
        def observe(self, t, run, reading):
            seen.append((t, reading.undone.shape, reading.ever.shape, reading.overlap.shape))

    trace = propagate(cut(stretch(cfg.stretch_settings()), cfg.dynamics_settings()), observers=[Counter()],
                      stop_rules=[TimeLimit(50e-6)])
    assert trace.stop_reason == "max_time_s reached" and not trace.reached_edge
    assert len(seen) == len(trace.times_s) == 3 and seen[0][1:] == ((4, 4),) * 3


def test_with_twist_the_laddering_yarns_spin_at_the_twist_free_step_held_stable():
    """twist=True: twist switched on at the cut (friction couple on). The step is dt_safety x the
    sliding's limit, as without twist; the faster spin mode is held to DEFAULT_SAFETY of its limit."""
    base = dict(n_x=4, n_y=4, resolution=16, lx=0.34, max_time_ms=0.1)
    knit = stretch(config(**base).stretch_settings())
    plain = cut(knit, config(**base).dynamics_settings())
    propagate(plain)
    twisted = cut(knit, config(**base, twist=True).dynamics_settings())
    propagate(twisted)
    assert twisted.sim.twist and not plain.sim.twist
    spin = np.abs(twisted.sim.state.omega).max() / units.TIME  # rad/s
    assert spin > 1e3  # friction has turned the yarns (surface speeds of 0.1 m/s and more)
    assert twisted.sim.limits.contact < plain.sim.limits.contact  # the turning adds to the contact stiffness
    assert twisted.sim.dt == pytest.approx(plain.sim.dt, rel=1e-12)
    assert twisted.sim.dt < DEFAULT_SAFETY * twisted.sim.limits.combined
    assert np.isfinite(twisted.sim.state.x).all()
    # a step factor that would take the spin mode past DEFAULT_SAFETY of its limit is held there
    bold = cut(knit, config(**base, twist=True, dt_safety=1.0).dynamics_settings())
    assert bold.sim.dt == pytest.approx(DEFAULT_SAFETY * bold.sim.limits.combined, rel=1e-12)


def test_a_heavier_spin_softens_only_the_friction_couples_share_of_the_contact_limit():
    """twist_inertia_factor K: I -> K I on every edge, so the spin term of the contact limit,
    omega^2 = 2 z (k_n + k_t)/m + 2 z k_t r^2/I, falls as 1/K and the rest is unchanged."""
    base = dict(n_x=4, n_y=4, resolution=16, lx=0.34)
    knit = stretch(config(**base).stretch_settings())
    plain, spin1, spin4 = (cut(knit, config(**base, **kw).dynamics_settings())
                           for kw in ({}, {"twist": True}, {"twist": True, "twist_inertia_factor": 4.0}))
    np.testing.assert_allclose(spin4.sim.model.twist_inertia, 4.0 * spin1.sim.model.twist_inertia, rtol=1e-15)
    omega2 = [dt ** -2.0 for dt in (plain.sim.limits.contact, spin1.sim.limits.contact, spin4.sim.limits.contact)]
    assert omega2[1] > omega2[0] * 1.1  # the couple's share is not negligible
    assert omega2[2] == pytest.approx(omega2[0] + (omega2[1] - omega2[0]) / 4.0, rel=1e-12)


def test_cut_edge_cuts_every_array_along_its_axis():
    """cut_edge removes one entry of every edge array and the hinges of that edge, whatever the
    fields: each field of the model and the state declares its axis once (MODEL_AXES, STATE_AXES)."""
    from knitlad.engine.state import EDGE, HINGE, MODEL_AXES, STATE_AXES, RodModel, RodState, cut_edge

    assert set(MODEL_AXES) == set(RodModel._fields) and set(STATE_AXES) == set(RodState._fields)
    knit = stretch(config(n_x=4, n_y=4, resolution=16, lx=0.32).stretch_settings())
    rods = knit.knit.rods
    edge = int(rods.model.yarn_start[2]) + 5
    after = cut_edge(rods, edge)
    for part, axes in ((rods.model, MODEL_AXES), (rods.state, STATE_AXES)):
        new = after.model if part is rods.model else after.state
        for name, axis in axes.items():
            drop = {EDGE: 1, HINGE: 2}.get(axis, 0)
            grows = name in ("yarn_start", "yarn_parent")  # one yarn more
            assert getattr(new, name).shape[0] == getattr(part, name).shape[0] - drop + grows, name
    assert after.model.n_yarns == rods.model.n_yarns + 1
    y = int(rods.model.node_yarn[rods.model.edge_a[edge]])
    assert after.model.yarn_parent[y + 1] == after.model.yarn_parent[y] == rods.model.yarn_parent[y]


def test_the_cut_leaves_every_course_and_cell_where_it_was():
    """Cutting a course makes two yarns of it, so the yarn indices of the courses above shift by
    one; the laddered cells are read by the nodes of each course, which do not move: right after
    the cut, before any step, the map is the one of the uncut knit and the courses are whole."""
    cfg = config(n_x=6, n_y=8, resolution=16, lx=0.36, steps_per_increment=200)
    knit = stretch(cfg.stretch_settings())
    run = cut(knit, cfg.dynamics_settings())
    x = run.sim.state.x
    assert np.array_equal(x, knit.knit.rods.state.x)
    rows = knit.gauge.rows(x)
    assert [len(r) for r in rows] == [len(knit.knit.rods.state.x[s]) for s in knit.knit.row_nodes()]
    assert run.sim.model.n_yarns == knit.knit.rods.model.n_yarns + 1
    heights = [r[:, 1].mean() for r in rows]
    assert np.all(np.diff(heights) > 0.5 * knit.box_ly * NYLON.stitch_length / units.LENGTH)
    assert np.array_equal(run.laddered(), run.baseline)


def test_a_ladder_relaxes_the_courses_it_crosses_and_leaves_the_others_taut():
    """Per-course f_x after the cut (6 x 8, l_x 0.38, fast preset, 1 ms): at every observation their mean
    is the knit's f_x (to round-off); at the stop the courses with an undone cell carry less than half
    the tension of the others (measured 1.71 against 5.16), so the mean f_x^fin mixes the two."""
    r = analyse(propagate(cut(stretch(config(n_x=6, n_y=8, lx=0.38, preset="fast").stretch_settings()),
                              config(n_x=6, n_y=8, lx=0.38, preset="fast", max_time_ms=1.0).dynamics_settings())))
    np.testing.assert_allclose(np.asarray(r.fx_course_series).mean(axis=1), r.fx_series, atol=1e-12)
    assert 0 < r.final_laddered.any(axis=1).sum() < 8
    assert r.fx_fin_crossed < 0.5 * r.fx_fin_intact
    assert min(r.fx_fin_crossed, r.fx_fin_intact) < r.fx_fin < max(r.fx_fin_crossed, r.fx_fin_intact)


def test_every_nan_of_a_ladders_summary_has_its_reason_beside_it():
    """README example 2 printed `0.8 nan 0.875 2.888`: the run hit max_time_s with the front at 1 stitch, and
    nothing said so. Every NaN of the summary now has its reason in ``nan_reasons``."""
    import math

    from knitlad.experiments.config import CutConfig
    from knitlad.experiments.laddering import run_ladder

    cfg = CutConfig(n_x=6, n_y=8, lx=0.40, preset="fast", resolution=16, max_time_ms=0.05)
    result = run_ladder(cfg.settings())
    summary = result.summary()
    nan = {k for k, v in summary.items() if isinstance(v, float) and math.isnan(v)}
    assert "v_lad_over_cb" in nan
    reasons = result.nan_reasons()
    assert set(reasons) == nan and all(f"{k}: " in summary["nan_reasons"] for k in nan)
    assert "the front ran" in reasons["v_lad_over_cb"] and "max_time_s reached" in reasons["v_lad_over_cb"]


def test_a_run_stop_band_gives_its_courses_contacts_the_bands_friction_and_the_rest_the_fabrics():
    """band_row/band_courses/band_friction_factor reach the laddering's contact: every contact touching a band
    course (its yarn as built, above the cut) has factor x mu, every other contact mu; the stretch (mu = 0)
    is the plain knit's."""
    from knitlad.engine.kernels.contact_law import FRICTION_FACTOR

    cfg = config(n_x=6, n_y=8, resolution=16, fx=4.0, band_row=5, band_courses=2, band_friction_factor=2.5)
    knit = stretch(cfg.stretch_settings())
    run = cut(knit, cfg.dynamics_settings())
    c, m = run.sim.contacts, run.sim.model
    factor = c.pair_law[c.edge_class, c.edge_class, FRICTION_FACTOR]  # each edge's own factor
    band = np.isin(m.yarn_parent[m.edge_yarn], [knit.knit.courses[5], knit.knit.courses[6]])
    assert band.any() and np.all(factor[band] == 2.5) and np.all(factor[~band] == 1.0)
    assert c.pair_law[c.edge_class[band][0], c.edge_class[~band][0], FRICTION_FACTOR] == 2.5
    with pytest.raises(ValueError, match="band_row"):
        config(n_x=6, n_y=8, fx=4.0, band_row=3, band_courses=2)  # holds the cut course 4


def test_each_choice_of_the_authors_preset_reaches_the_kernels():
    """The preset crassous2023 (knitlad.fabric.presets, each choice cited to the authors' engine) reaches the
    simulation that runs the ladder: 140 nodes per stitch and capsules of the yarn's radius in the knit, twist with
    twice a cylinder's spin inertia, the drag of lambda on the nodes and at the same rate on the spin, every touching
    pair counted, a normal contact dashpot of sqrt(EA rho_L) and none along the surface, the axial dashpot at
    2.8 sqrt(EA rho_L). Run here at 16 nodes per stitch for its cost: every other choice is the preset's."""
    from knitlad.engine.dissipation import authors_drag_per_s

    full = CutConfig(fx=4.0, n_x=4, n_y=4, preset="crassous2023")
    assert full.stretch_settings().resolution == 140 and full.stretch_settings().sagitta_radius == 0.0
    cfg = full.replace(resolution=16)
    run = cut(stretch(cfg.stretch_settings()), cfg.dynamics_settings())
    sim, m, mat = run.sim, run.sim.model, cfg.material()
    gamma = authors_drag_per_s(cfg.drag_lambda, mat)
    assert sim.twist and sim.drag == pytest.approx(gamma * units.TIME) and sim.spin_drag == sim.drag > 0
    assert sim.damping.spin_drag == sim.spin_drag  # what the kernels take
    rho, EA, d = mat.line_density, mat.stretching_stiffness, mat.diameter
    inside = ~m.held[m.edge_a] & ~m.held[m.edge_b]
    length = m.rest_length[inside] * units.LENGTH
    spin = m.twist_inertia[inside] * units.MASS * units.LENGTH**2
    assert spin == pytest.approx(2.0 * rho * length * d**2 / 8, rel=1e-9)
    axial = m.stretch_damping[inside] * units.FORCE * units.TIME / units.LENGTH
    assert np.median(axial) == pytest.approx(2.8 * np.sqrt(EA * rho), rel=0.02)
    c = sim.contacts
    assert not c.union and c.params.damping_t == 0.0
    node = np.median(m.mass[~m.held]) * units.MASS
    c_n = 2 * c.params.damping_n * np.sqrt(sim.contact_model.stiffness * node / 2)
    assert c_n == pytest.approx(np.sqrt(EA * rho), rel=1e-9)
    assert np.allclose(c.edge_radius * units.LENGTH, d / 2)


def test_a_drag_per_second_given_with_the_authors_preset_replaces_its_lambda():
    cfg = CutConfig(fx=4.0, preset="crassous2023", drag_per_s=5e3)
    assert cfg.drag_lambda is None and cfg.dynamics_settings().drag_per_s == 5e3
    with pytest.raises(ValueError, match="drag_lambda"):
        CutConfig(fx=4.0, drag_lambda=1e-4, drag_per_s=10.0)
    with pytest.raises(ValueError, match="spin_drag"):
        CutConfig(fx=4.0, spin_drag=True)
