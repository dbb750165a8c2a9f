import math
import time

import numba
import numpy as np
import pytest

import knitlad as kl
from knitlad.fabric.scenes.rod import Cantilever


def test_time_step_limit_matches_the_textbook_stretching_bound():
    """Uniform rod: dt_crit = (l / c_E)(sqrt(1+zeta^2) - zeta) for stretching."""
    c = Cantilever(0.02, 41)
    sim = kl.Simulation(c.build(stretch_damping_ratio=0.0))
    expected = c.segment / kl.NYLON.axial_wave_speed / kl.units.TIME
    assert sim.limits.stretching == pytest.approx(expected, rel=1e-6)
    bend = c.segment**2 / 2 * math.sqrt(kl.NYLON.line_density / kl.NYLON.bending_stiffness) / kl.units.TIME
    assert sim.limits.bending == pytest.approx(bend, rel=1e-6)


def test_unstable_time_step_is_refused_before_anything_runs():
    state = Cantilever(0.02, 21).build()
    probe = kl.Simulation(state.copy())
    limit = probe.limits.combined * kl.units.TIME
    with pytest.raises(kl.UnstableTimeStep, match="stability limit"):
        kl.Simulation(state, dt_s=1.01 * limit)
    kl.Simulation(state, dt_s=0.99 * limit)  # accepted


def test_a_step_just_below_the_limit_is_stable_and_conserves_energy():
    """The Gershgorin bound is safe: 0.99 dt_crit runs 2000 steps with bounded energy."""
    c = Cantilever(0.02, 21)
    state = c.build(tip_force=(0, -1e-6, 0), stretch_damping_ratio=0.0)
    kl.Simulation(state).relax(force_tol_N=1e-12)
    state = state.replace_model(f_ext=0 * state.model.f_ext)
    sim = kl.Simulation(state, dt_s=0.99 * kl.Simulation(state.copy()).limits.combined * kl.units.TIME)
    e0 = sim.energies_J()["total"]
    sim.step(2000)
    assert abs(sim.energies_J()["total"] / e0 - 1) < 0.05


def test_blow_up_names_the_step_yarn_and_node():
    scene = kl.Scene()
    pts = np.zeros((10, 3))
    pts[:, 0] = np.linspace(0, 0.005, 10)
    scene.add_yarn(pts)
    scene.add_yarn(pts + [0, 0.002, 0])
    sim = kl.Simulation(scene.build(), guard_every=1)
    # a stiffness gone NaN is not refused up front (only states and loads are): it blows up in the first step,
    # at the nodes of that edge of yarn 1 (nodes 13 and 14, its local nodes 3 and 4)
    edge = 12
    assert sim.model.edge_a[edge] == 13
    sim.model.EA[edge] = np.nan
    with pytest.raises(kl.SimulationBlowUp, match=r"step 1 .*yarn 1, node [1-5];"):
        sim.step(50)


def test_runaway_speed_is_caught():
    sim = kl.Simulation(Cantilever(0.02, 11).build(), guard_every=1)
    sim.state.v[5, 0] = 10 * sim.max_speed
    with pytest.raises(kl.SimulationBlowUp, match="axial wave speed"):
        sim.step(1)


def test_held_nodes_follow_their_prescribed_motion():
    scene = kl.Scene()
    pts = np.zeros((6, 3))
    pts[:, 0] = np.linspace(0, 0.005, 6)
    y = scene.add_yarn(pts)
    scene.hold(y, [0], velocity=(0.0, 0.0, 0.0))
    scene.hold(y, [5], velocity=(0.01, 0.0, 0.0))
    sim = kl.Simulation(scene.build(), drag_per_s=1e3)
    sim.run(1e-3)
    assert sim.positions_m()[5, 0] == pytest.approx(0.005 + 0.01 * sim.time_s, rel=1e-9)
    # held still and relaxed: the supports pull outward with the tension EA * strain
    sim.replace_model(v_prescribed=0.0 * sim.model.v_prescribed)
    sim.relax(force_tol_N=1e-10)
    strain = (sim.positions_m()[5, 0] - sim.positions_m()[0, 0]) / 0.005 - 1.0
    r = sim.reaction_forces_N()
    assert r[5, 0] == pytest.approx(kl.NYLON.stretching_stiffness * strain, rel=1e-6)
    assert r[0, 0] == pytest.approx(-r[5, 0], rel=1e-9)


def test_a_global_drag_decays_a_free_rods_momentum_exponentially():
    """-gamma m v on every node: a rod coasting with no other force keeps its shape and its
    speed falls as exp(-gamma t) (to the integrator's O(gamma dt) accuracy); a negative rate is refused."""
    sim = kl.Simulation(_free_rod(), drag_per_s=2e3)
    sim.state.v[:, 1] = 1.0  # internal units (mm/ms = m/s); a rigid translation: no elastic force
    sim.run(0.5e-3)
    assert sim.state.v[:, 1] == pytest.approx(np.exp(-2e3 * sim.time_s), rel=1e-3)
    with pytest.raises(ValueError, match="drag"):
        sim.set_drag(-1.0)


def _free_rod():
    scene = kl.Scene()
    pts = np.zeros((11, 3))
    pts[:, 0] = np.linspace(0, 0.02, 11)
    scene.add_yarn(pts)
    return scene.build()


def test_the_twist_path_is_framed_only_where_the_yarn_has_natural_curvature():
    """Twist through material frames for natural curvature (or when asked), else the frame-free path."""
    from knitlad.engine.kernels.integrate import TWIST_FRAMED, TWIST_OFF, TWIST_STRAIGHT

    s = np.linspace(0.0, 3e-3, 13)
    arc = np.column_stack([s, 0.2 * s**2 / 3e-3, 0 * s])

    def sim(twist, natural_curvature="straight", **kw):
        scene = kl.Scene()
        scene.add_yarn(arc, natural_curvature=natural_curvature)
        return kl.Simulation(scene.build(twist=twist), **kw)

    assert sim(False).twist_mode == TWIST_OFF
    assert sim(True).twist_mode == TWIST_STRAIGHT
    assert sim(True, framed_twist=True).twist_mode == TWIST_FRAMED
    assert sim(True, natural_curvature="rest").twist_mode == TWIST_FRAMED


@pytest.mark.parametrize("predicted", [False, True])
def test_the_damped_limit_factor_is_the_integrators_stability_limit(predicted):
    """A mass on a spring and dashpot (zeta 0.3), stepped by the kernels at 2 % below and above
    2 f(zeta) / omega (:func:`knitlad.engine.timestep.damped_limit_factor`): bounded below, growing above."""
    from knitlad.engine.kernels.integrate import DASHPOTS_HALF_STEP, DASHPOTS_PREDICTED, compute_forces, verlet_steps
    from knitlad.engine.obstacles import obstacle_state
    from knitlad.engine.timestep import damped_limit_factor

    mode = DASHPOTS_PREDICTED if predicted else DASHPOTS_HALF_STEP
    amplitudes = []
    for factor in (0.98, 1.02):
        scene = kl.Scene()
        y = scene.add_yarn(np.array([[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0]]))
        scene.hold(y, [0])
        rods = scene.build(stretch_damping_ratio=0.3)
        m, s = rods.model, rods.state
        k, c, mass = m.EA[0] / m.rest_length[0], m.stretch_damping[0], m.mass[1]
        zeta = c / (2 * math.sqrt(k * mass))
        dt = factor * 2 * damped_limit_factor(zeta, predicted) / math.sqrt(k / mass)
        x0 = s.x[1, 0]
        s.x[1, 0] += 1e-6
        sim = kl.Simulation(rods)  # its workspace and buffers; the steps below bypass its limit
        sim.work.v_damp[:] = s.v
        none = obstacle_state([], m.n_nodes)
        compute_forces(m, s, sim.work, sim.contacts, 0, False, sim.damping, dt, 0, mode, none)
        verlet_steps(m, s, sim.work, sim.contacts, dt, 3000, 0, False, sim.damping, 0, mode, none)
        amplitudes.append(abs(s.x[1, 0] - x0) / 1e-6)
    assert amplitudes[0] < 1.0 and amplitudes[1] > 1e3, amplitudes


def test_a_twisting_yarn_straight_at_rest_hands_back_complete_frames():
    """TWIST_STRAIGHT carries only the anchors' reference frames each step and rebuilds the others when
    a kernel returns: after steps of a springing helix, an open yarn cut in two and a ring, every frame is
    unit, normal to its tangent, and agrees with the reference twist (update_reference_twist, which
    adds the angle between the transported frame turned by the twist and the stored one, adds nothing)."""
    from knitlad.engine.kernels.frames import update_reference_twist
    from knitlad.engine.kernels.integrate import TWIST_STRAIGHT
    from knitlad.engine.state import cut_edge

    s = np.linspace(0.0, 4.0 * np.pi, 41)
    helix = 1e-3 * np.column_stack([np.cos(s), np.sin(s), 0.3 * s])
    scene = kl.Scene()
    scene.add_yarn(helix)
    scene.add_yarn(2e-3 * np.column_stack([np.cos(s[:-1] / 2), np.sin(s[:-1] / 2), 0 * s[:-1]]) + [0, 0, 5e-3],
                   closed=True)
    rods = cut_edge(scene.build(twist=True), 19)
    rods.state.omega[:] = np.random.default_rng(3).normal(scale=1.0, size=rods.state.omega.shape)
    sim = kl.Simulation(rods)
    assert sim.twist_mode == TWIST_STRAIGHT
    tangent0 = sim.state.tangent.copy()
    sim.step(2000)
    m, st = sim.model, sim.state
    e = (st.x[m.edge_b] + m.edge_shift) - st.x[m.edge_a]
    np.testing.assert_allclose(st.tangent, e / np.linalg.norm(e, axis=1)[:, None], atol=1e-14)
    assert np.degrees(np.arccos(np.sum(tangent0 * st.tangent, axis=1).min())) > 5  # the yarns have moved
    np.testing.assert_allclose(np.linalg.norm(st.ref_u, axis=1), 1.0, atol=1e-14)
    assert np.abs(np.sum(st.ref_u * st.tangent, axis=1)).max() < 1e-14
    twist = st.ref_twist.copy()
    update_reference_twist(st.tangent, st.ref_u, m.hinge_e0, m.hinge_e1, twist)
    assert np.abs(st.ref_twist).max() > 1e-3
    np.testing.assert_allclose(twist, st.ref_twist, rtol=0, atol=1e-12)


def _bar(n: int = 11, length: float = 0.01):
    s = np.linspace(0.0, length, n)
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))
    return kl.Simulation(scene.build(), drag_per_s=0.0)


def test_displacement_control_moves_held_ends_between_relaxations_and_reads_ea_strain():
    """A 10 mm bar held at both ends, its end moved 1 um at a time: after each relaxation the support
    reaction is EA dL / L (springs in series are linear), and the free nodes sit evenly."""
    sim = _bar()
    ends = np.concatenate([sim.nodes_of(0, [0]), sim.nodes_of(0, [-1])])
    sim.hold(ends)
    ea = kl.NYLON.stretching_stiffness
    for k in range(1, 4):
        sim.move_held(ends[1], by_m=(1e-6, 0.0, 0.0))
        assert sim.relax(force_tol_N=1e-12)["converged"]
        assert sim.reaction_forces_N()[ends[0], 0] == pytest.approx(-ea * k * 1e-6 / 0.01, rel=1e-6)
        np.testing.assert_allclose(np.diff(sim.positions_m()[:, 0]), (0.01 + k * 1e-6) / 10, rtol=1e-9)
    sim.move_held(ends[1], to_m=(0.01, 0.0, 0.0))  # back to the rest length
    assert sim.relax(force_tol_N=1e-12)["converged"]
    assert abs(sim.reaction_forces_N()[ends[0], 0]) < 1e-9


def test_held_nodes_change_velocity_and_are_released_mid_run():
    sim = _bar()
    end = sim.nodes_of(0, [-1])
    sim.hold(end, velocity_m_s=(0.0, 0.0, 0.0))
    sim.step(100)
    x0, t0 = sim.positions_m()[end[0]].copy(), sim.time_s
    sim.hold(end, velocity_m_s=(0.0, 0.0, 2e-3))  # a new velocity for a held node
    sim.step(200)
    assert sim.positions_m()[end[0], 2] - x0[2] == pytest.approx(2e-3 * (sim.time_s - t0), rel=1e-9)
    sim.release(end)
    assert not sim.model.held[end].any()
    z = sim.positions_m()[end[0], 2]
    sim.step(200)
    assert sim.positions_m()[end[0], 2] != pytest.approx(z + 2e-3 * 200 * sim.dt_s, rel=1e-3)  # no longer prescribed
    with pytest.raises(ValueError, match="held nodes only"):
        sim.move_held(end, by_m=(0, 0, 1e-6))
    with pytest.raises(IndexError, match="out of range"):
        sim.nodes_of(0, [11])


def _governed(g, chunks: int, seconds_per_step, idle=None, others=None) -> list[int]:
    """Threads the governor chose for each chunk of 500 steps, the machine's speed given per count (and the
    idle cores and the cores other processes used, as /proc/stat would say)."""
    seen = []
    for k in range(chunks):
        threads = g.plan(2)
        seen.append(threads)
        g.record(threads, 500, 500 * seconds_per_step(k, threads))
        if idle is not None:
            g.idle_cores = idle
        if others is not None:
            g.other_cores = others
    return seen


def test_the_thread_governor_keeps_the_faster_count_and_tries_two_only_where_a_core_is_free():
    from knitlad.engine.simulation import ThreadGovernor

    def governor():
        g = ThreadGovernor()
        g.cpus = ()  # no /proc/stat reading: the test sets the idle cores
        return g

    assert governor().plan(1) == 1  # one thread allowed: nothing to choose
    # a loaded machine with no idle core: two threads are never tried
    assert set(_governed(governor(), 100, lambda k, n: 1e-3 if n == 2 else 1e-4, idle=0.1)) == {1}
    # idle unknown, two threads ten times slower: tried once after the first chunk, then rarely
    seen = _governed(governor(), 40, lambda k, n: 1e-3 if n == 2 else 1e-4)
    assert seen[:3] == [1, 2, 1] and seen.count(2) == 1
    # a quiet machine, two threads twice as fast: taken after one chunk and kept, probed ever more rarely
    g = governor()
    seen = _governed(g, 2000, lambda k, n: 2.5e-4 if n == 2 else 5e-4, idle=1.0)
    assert seen[:3] == [1, 2, 2] and g.current == 2 and g.interval == ThreadGovernor.LAST_INTERVAL
    # then another process takes a core: two threads become ten times slower, one thread is back next chunk
    seen = _governed(g, 3, lambda k, n: 2.5e-3 if n == 2 else 5e-4, idle=0.0)
    assert seen == [2, 1, 1] and g.current == 1


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two Numba threads (NUMBA_NUM_THREADS >= 2)")
def test_switching_thread_counts_mid_run_changes_no_bit():
    """The governor may change the count every chunk: the positions are those of a one-thread run."""
    counts = []
    from knitlad.engine.contact import ContactModel
    from knitlad.fabric.scenes.weave import plain_weave
    from knitlad.engine.simulation import numba_threads

    def run(threads: int, probe_often: bool):
        rods = plain_weave(4, spacing=4 * kl.NYLON.diameter, nodes_per_spacing=6,
                           amplitude=0.4 * kl.NYLON.diameter).build()
        sim = kl.Simulation(rods, contact=ContactModel(stiffness=1e3, mu=0.4), guard_every=50)
        if probe_often:
            sim.threads.FIRST_INTERVAL = sim.threads.until_probe = sim.threads.LAST_INTERVAL = 1
            sim.threads.cpus = ()  # tries two threads whatever the machine's load
        with numba_threads(threads):
            sim.step(600)
        counts.extend(sim.threads.seconds_per_step)
        return sim.state.x.copy()

    np.testing.assert_array_equal(run(2, probe_often=True), run(1, probe_often=False))
    assert set(counts) == {1, 2}  # both counts ran


def test_the_governor_skips_its_probes_of_one_thread_while_no_other_process_runs():
    """Two threads twice as fast: with the other processes below a quarter of a core, one thread is never
    tried after the choice; with another process on a core, it is probed as before, and taken when faster;
    a light load that slows nothing brings the probe back at once."""
    from knitlad.engine.simulation import ThreadGovernor

    def governor():
        g = ThreadGovernor()
        g.cpus = ()
        return g

    quiet = _governed(governor(), 200, lambda k, n: 2.5e-4 if n == 2 else 5e-4, idle=1.0, others=0.05)
    assert quiet[:2] == [1, 2] and quiet[2:].count(1) == 0
    # a small scene, where one thread is the faster on a quiet machine: kept, two tried ever more rarely
    small = _governed(governor(), 200, lambda k, n: 8e-4 if n == 2 else 5e-4, idle=1.0, others=0.05)
    assert small[:3] == [1, 2, 1] and 2 <= small.count(2) <= 6
    busy = _governed(governor(), 200, lambda k, n: 2.5e-4 if n == 2 else 5e-4, idle=1.0, others=0.6)
    assert busy[:4] == [1, 2, 2, 1] and 2 <= busy.count(1) <= 6  # probed, ever more rarely
    # another process starts: the run on two threads slows ten times, and one thread takes over
    g = governor()
    _governed(g, 300, lambda k, n: 2.5e-4 if n == 2 else 5e-4, idle=1.0, others=0.05)
    seen = _governed(g, 3, lambda k, n: 2.5e-3 if n == 2 else 5e-4, idle=0.0, others=1.0)
    assert seen == [2, 1, 1] and g.current == 1
    # the same where the slow chunk went unread (the 2 x rule alone): the last quiet reading does not count
    g = governor()
    _governed(g, 300, lambda k, n: 2.5e-4 if n == 2 else 5e-4, idle=1.0, others=0.05)
    assert _governed(g, 3, lambda k, n: 2.5e-3 if n == 2 else 5e-4, idle=0.0) == [2, 1, 1]
    # after 300 quiet chunks, a process that takes a third of a core and slows nothing: probed next chunk
    g = governor()
    _governed(g, 300, lambda k, n: 2.5e-4 if n == 2 else 5e-4, idle=1.0, others=0.05)
    g.other_cores = 0.35
    assert _governed(g, 2, lambda k, n: 2.5e-4 if n == 2 else 5e-4, idle=0.6, others=0.35) == [1, 2]


def test_the_governor_reads_the_other_processes_load_from_the_processors_and_its_own_cpu_time(monkeypatch):
    """A chunk before a probe reads the processors' idle ticks and this process's CPU time: the others' load is
    what is neither idle nor this process's own. Checked on fed readings (the machine's own load, whatever
    else runs, must not decide the test), then once on this machine's /proc/stat, where it is a number of cores
    between none and all."""
    import knitlad.engine.simulation as simulation
    from knitlad.engine.simulation import ThreadGovernor, idle_cpu_ticks

    for idle_ticks, others in ((100, 0.0), (0, 1.0), (50, 0.5)):  # of 200 ticks on 2 processors in 1 s
        readings = iter([(0, 0), (idle_ticks, 200)])
        monkeypatch.setattr(simulation, "idle_cpu_ticks", lambda cpus: next(readings))
        clock = iter([10.0, 11.0])  # this process used one core over the chunk
        monkeypatch.setattr(simulation.time, "process_time", lambda: next(clock))
        g = ThreadGovernor()
        g.cpus, g.until_probe = (0, 1), 1
        g.plan(2)
        g.record(g.current, 500, 1.0)
        assert g.other_cores == pytest.approx(others)
    monkeypatch.undo()
    g = ThreadGovernor()
    if len(g.cpus) < 2 or idle_cpu_ticks(g.cpus) is None:
        pytest.skip("one processor, or no /proc/stat here")
    g.until_probe = 1
    g.plan(2)
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < 0.5:
        pass
    g.record(g.current, 500, time.perf_counter() - t0)
    assert g.other_cores is not None and -0.5 < g.other_cores <= len(g.cpus)


def test_a_relaxation_takes_the_chunks_choice_or_one_thread_when_the_load_says_the_cores_are_taken(monkeypatch):
    import os

    from knitlad.engine.simulation import ThreadGovernor

    g = ThreadGovernor()
    g.cpus = (0, 1)
    monkeypatch.setattr(os, "getloadavg", lambda: (1.1, 1.0, 1.0))  # this process alone
    assert g.for_one_call(2) == 2 and g.for_one_call(1) == 1
    monkeypatch.setattr(os, "getloadavg", lambda: (2.2, 2.0, 2.0))  # and another one
    assert g.for_one_call(2) == 1
    g.seconds_per_step, g.current = {1: 1e-4, 2: 5e-5}, 2  # the chunks measured: their choice rules
    assert g.for_one_call(2) == 2


def test_a_closing_edge_moved_by_a_new_period_finds_the_yarn_it_now_crosses():
    """A periodised yarn's period grows (replace_model(edge_shift=...)) until its closing edge crosses
    another yarn two diameters past its old end: the candidate list, which counts node moves only, is
    rebuilt, and the crossing touches."""
    d = kl.NYLON.diameter
    s = np.arange(10) * d
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]), closed=True, period=(10 * d, 0.0, 0.0))
    y = np.linspace(-3 * d, 3 * d, 7)
    scene.add_yarn(np.column_stack([0 * y + 12 * d, y, 0 * y + 0.9 * d]))  # a yarn crossing the ring's period
    sim = kl.Simulation(scene.build(), contact=kl.ContactModel(stiffness=1e3))
    sim.hold(np.arange(sim.model.n_nodes))  # the period alone moves the closing edge
    sim.step()
    assert sim.contact_stats().touching == 0
    shift = sim.model.edge_shift.copy()
    for grown in (11, 12, 13, 14):  # a box stretched in steps
        shift[9, 0] = grown * d / 1e-3  # internal units: mm
        sim.replace_model(edge_shift=shift)
        sim.step()
    assert sim.contact_stats().touching >= 1
