"""Contact kernels: narrow phase, broad phase, force distribution."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.contact import ContactModel, contact_time_step, make_contacts
from knitlad.engine.kernels.contact import HISTORY_COLUMNS, NORMAL_FORCE_SUM, TOUCHING, segment_closest_points
from knitlad.engine.kernels.dissipation import N_LEDGER
from knitlad.fabric.scenes.weave import plain_weave

D = kl.NYLON.diameter


def brute_closest(p0, d1, q0, d2, n=401):
    s = np.linspace(0, 1, n)
    P = p0 + s[:, None] * d1
    Q = q0 + s[:, None] * d2
    dist = np.linalg.norm(P[:, None, :] - Q[None, :, :], axis=2)
    return dist.min()


@pytest.mark.parametrize("seed", range(20))
def test_closest_points_match_a_brute_force_search(seed):
    rng = np.random.default_rng(seed)
    p0, d1, q0, d2 = rng.normal(size=(4, 3))
    if seed % 4 == 0:
        d2 = d1 * rng.uniform(-2, 2) + 1e-9 * rng.normal(size=3)  # near parallel
    s, t = segment_closest_points(*p0, *d1, *q0, *d2)
    dist = np.linalg.norm(p0 + s * d1 - q0 - t * d2)
    assert 0 <= s <= 1 and 0 <= t <= 1
    assert dist <= brute_closest(p0, d1, q0, d2) + 1e-9


def test_parallel_overlapping_segments_touch_at_the_middle_of_their_overlap():
    s, t = segment_closest_points(0, 0, 0, 1, 0, 0, 0.5, 1, 0, 1, 0, 0)  # overlap x in [0.5, 1]
    assert s == pytest.approx(0.75) and t == pytest.approx(0.25)


def dense_weave(n=4):
    return plain_weave(n, spacing=4 * D, nodes_per_spacing=6)


def contact_forces_of(rods, model):
    """Contact part of the nodal forces (Simulation grows the pair buffer as needed)."""
    with_contact = kl.Simulation(rods.copy(), contact=model)
    without = kl.Simulation(rods.copy())
    return with_contact.work.force - without.work.force, with_contact.contacts


def pressed_weave():
    """A weave whose crossings overlap: amplitude 0.4 d, so axes are 0.8 d apart."""
    return plain_weave(4, spacing=4 * D, nodes_per_spacing=6, amplitude=0.4 * D).build()


def test_contact_forces_obey_newtons_third_law_and_exert_no_torque():
    rods = pressed_weave()
    f, c = contact_forces_of(rods, ContactModel(stiffness=1e3))
    assert c.stats[TOUCHING] >= 16  # every one of the 16 crossings touches
    scale = np.abs(f).max()
    assert scale > 0
    np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-12 * scale * len(f))
    torque = np.cross(rods.state.x, f).sum(axis=0)
    assert np.abs(torque).max() < 1e-10 * scale * np.abs(rods.state.x).max() * len(f)


def brute_force_touching(rods, exclusion):
    """Touching edge pairs by an all-pairs search (the reference for the broad phase)."""
    from knitlad.engine.contact import edge_topology

    edge_yarn, edge_local, _, _ = edge_topology(rods.model)
    x = rods.state.x
    a, b = rods.model.edge_a, rods.model.edge_b
    r = 0.5 * (rods.model.radius[a] + rods.model.radius[b])
    found = set()
    for i in range(len(a)):
        for j in range(i + 1, len(a)):
            if edge_yarn[i] == edge_yarn[j] and abs(edge_local[i] - edge_local[j]) <= exclusion:
                continue
            s, t = segment_closest_points(*x[a[i]], *(x[b[i]] - x[a[i]]), *x[a[j]], *(x[b[j]] - x[a[j]]))
            dist = np.linalg.norm(x[a[i]] + s * (x[b[i]] - x[a[i]]) - x[a[j]] - t * (x[b[j]] - x[a[j]]))
            if dist < r[i] + r[j]:
                found.add((i, j))
    return found


def touching_in_broad_phase(rods):
    """The touching pairs among the broad phase's candidates, and the exclusion it used."""
    from knitlad.engine.kernels.contact import refresh_contacts, segment_distance

    c = make_contacts(rods, ContactModel(stiffness=1e3))
    assert refresh_contacts(rods.state.x, rods.model.edge_a, rods.model.edge_b, rods.model.edge_shift, c,
                            rods.state.v, 0.0)
    touching = {
        (int(i), int(j))
        for i, j in c.pairs[: c.n_pairs[0]]
        if segment_distance(rods.state.x, rods.model.edge_a, rods.model.edge_b, rods.model.edge_shift, i, j)[0] < c.edge_radius[i] + c.edge_radius[j]
    }
    return touching, int(c.exclusion[0])


def test_broad_phase_finds_exactly_the_pairs_of_an_all_pairs_search():
    rods = pressed_weave()
    touching, exclusion = touching_in_broad_phase(rods)
    assert touching == brute_force_touching(rods, exclusion)
    assert len(touching) > 0


def test_a_yarn_flung_far_away_coarsens_the_grid_and_no_touching_pair_is_missed():
    """The grid spans the bounding box: 10 m away, one yarn would make 1e10 cells of the reach."""
    from knitlad.engine.kernels.contact import MAX_CELLS_PER_EDGE

    rods = pressed_weave()
    first = slice(int(rods.model.yarn_start[0]), int(rods.model.yarn_start[1]))
    rods.state.x[first, 0] += 10.0 / kl.units.LENGTH
    rods.state.x[first, 2] += 10.0 / kl.units.LENGTH
    box = (rods.state.x.max(axis=0) - rods.state.x.min(axis=0)) * kl.units.LENGTH
    assert box.prod() / D**3 > MAX_CELLS_PER_EDGE * rods.model.edge_a.shape[0] * 1e3  # cells of d: far too many
    touching, exclusion = touching_in_broad_phase(rods)
    assert touching == brute_force_touching(rods, exclusion)
    assert len(touching) >= 12  # the 12 crossings of the 3 warps left in place


def test_a_non_finite_position_finds_no_pair_for_its_edges_and_crashes_nothing():
    from knitlad.engine.kernels.contact import refresh_contacts

    rods = pressed_weave()
    rods.state.x[3] = np.nan
    c = make_contacts(rods, ContactModel(stiffness=1e3))
    assert refresh_contacts(rods.state.x, rods.model.edge_a, rods.model.edge_b, rods.model.edge_shift, c,
                            rods.state.v, 0.0)
    bad = set(np.flatnonzero((rods.model.edge_a == 3) | (rods.model.edge_b == 3)).tolist())
    assert c.n_pairs[0] > 0
    assert not any(int(i) in bad or int(j) in bad for i, j in c.pairs[: c.n_pairs[0]])


@pytest.mark.parametrize("skin_d", [0.05, 0.5, 3.0])
def test_contact_count_and_forces_do_not_depend_on_the_cell_size(skin_d):
    """The cell size is longest edge + 2 r + skin: changing the skin changes the cells."""
    rods = pressed_weave()
    reference, c_ref = contact_forces_of(rods, ContactModel(stiffness=1e3, skin=1.0 * D))
    f, c = contact_forces_of(rods, ContactModel(stiffness=1e3, skin=skin_d * D))
    assert c.stats[TOUCHING] == c_ref.stats[TOUCHING]
    np.testing.assert_allclose(f, reference, rtol=0, atol=1e-12 * np.abs(reference).max())


def test_a_full_buffer_is_grown_and_the_run_goes_on():
    rods = pressed_weave()
    """One pair slot per edge holds fewer pairs than a pressed weave's candidates: the buffer must grow."""
    sim = kl.Simulation(rods, contact=ContactModel(stiffness=1e3, capacity_per_edge=1))
    first_capacity = max(16, len(rods.model.edge_yarn))
    assert sim.contacts.n_pairs[0] > first_capacity
    assert sim.contacts.pairs.shape[0] >= sim.contacts.n_pairs[0]
    sim.step(10)
    assert np.isfinite(sim.state.x).all()


def test_same_yarn_neighbours_are_excluded_but_distant_loops_of_one_yarn_touch():
    """A hairpin: one yarn folded back on itself touches itself away from the fold."""
    n = 40
    s = np.linspace(0, 1, n)
    arm = 10 * D
    pts = np.zeros((2 * n, 3))
    pts[:n, 0] = s * arm
    pts[n:, 0] = arm - s * arm
    pts[n:, 1] = 0.9 * D  # overlapping by 0.1 d
    pts[n:, 0] += 0.5 * arm / n  # no coincident points at the fold
    scene = kl.Scene()
    scene.add_yarn(pts)
    rods = scene.build()
    f, c = contact_forces_of(rods, ContactModel(stiffness=1e3))
    assert c.stats[TOUCHING] > 10  # the two arms touch along their length
    # straight neighbours never interact: no force on a lone straight yarn
    scene2 = kl.Scene()
    scene2.add_yarn(pts[:n])
    f2, c2 = contact_forces_of(scene2.build(), ContactModel(stiffness=1e3))
    assert c2.stats[TOUCHING] == 0 and np.abs(f2).max() < 1e-9


def test_bad_contact_parameters_are_refused():
    with pytest.raises(ValueError, match="stiffness"):
        ContactModel(stiffness=-1)
    with pytest.raises(ValueError, match="friction"):
        ContactModel(stiffness=1, mu=-0.1)
    sim = kl.Simulation(pressed_weave(), contact=ContactModel(stiffness=1e3))
    with pytest.raises(ValueError, match="friction"):
        sim.set_friction(float("nan"))


def crossing_at_a_node(counting: str, offset: float = 0.0):
    """A straight yarn along y pressed onto a rail along x right above one of its nodes
    (``offset``: along x, in edge lengths), with the equilibrium overlap of a single pair."""
    rail = np.zeros((11, 3))
    rail[:, 0] = np.linspace(-10 * D, 10 * D, 11)  # edges 2 d long (a knit's are 2-3 d), a node at x = 0
    y = np.linspace(-2 * D, 2 * D, 4)  # edges 1.33 d long, crossing mid-edge
    crossing = np.column_stack([np.full(4, offset * 2 * D), y, np.full(4, 0.95 * D)])
    scene = kl.Scene()
    scene.add_yarn(rail)
    scene.add_yarn(crossing)
    return contact_forces_of(scene.build(), ContactModel(stiffness=1e3, counting=counting))


def test_union_counts_a_crossing_at_a_node_once_all_pairs_once_per_edge_of_the_node():
    """Union: one pair whatever the crossing's place; all_pairs: the two rail edges that share
    the node each touch, so at the same overlap the normal force is twice union's there
    (mid-edge the two countings agree, force for force)."""
    _, c_union = crossing_at_a_node("union")
    _, c_all = crossing_at_a_node("all_pairs")
    assert c_union.stats[TOUCHING] == 1 and c_all.stats[TOUCHING] == 2
    assert c_all.stats[NORMAL_FORCE_SUM] == pytest.approx(2 * c_union.stats[NORMAL_FORCE_SUM], rel=1e-12)
    f_mid, c_mid = crossing_at_a_node("all_pairs", offset=0.5)
    f_mid_union, c_mid_union = crossing_at_a_node("union", offset=0.5)
    assert c_mid.stats[TOUCHING] == c_mid_union.stats[TOUCHING] == 1
    np.testing.assert_allclose(f_mid, f_mid_union, rtol=0, atol=1e-12 * np.abs(f_mid).max())


def arc(radius: float, n: int, half_angle: float, axis: int) -> np.ndarray:
    """n nodes on a circular arc in the plane of ``axis`` and z, its lowest point at the origin."""
    phi = np.linspace(-half_angle, half_angle, n)
    points = np.zeros((n, 3))
    points[:, axis] = radius * np.sin(phi)
    points[:, 2] = radius - radius * np.cos(phi)
    return points


def slide_through_a_trough(counting: str, substeps: int = 2000, law: str = "linear") -> tuple[float, float, float]:
    """A yarn bent down (a saddle's upper half) slid diagonally through a trough: a rail bent up, both of edges
    0.4 d on arcs of radius 1.5 d, frictionless and undamped, moved by hand. Returns the change of the contact
    energy, the work of the contact forces on the moving yarn (trapezoid over the substeps) and the energy the
    ledger booked to owner changes [J]."""
    from knitlad.engine import units
    from knitlad.engine.kernels.dissipation import OWNER_CHANGES

    rail = arc(1.5 * D, 19, 1.2, 0)
    above = arc(1.5 * D, 19, 1.2, 1)
    above[:, 2] = 0.9 * D - above[:, 2]
    above += np.array([-0.5, -0.37, 0.0]) * D
    scene = kl.Scene()
    scene.add_yarn(rail)
    scene.add_yarn(above)
    sim = kl.Simulation(scene.build(), contact=ContactModel(stiffness=1e3, counting=counting, mu=0.0,
                                                            damping_ratio=0.0, law=law, reference_overlap=0.05 * D))
    moving = np.arange(19, 38)
    step = np.array([1.0, 0.63, 0.0]) * D / substeps
    sim.compute_forces()
    sim.work.ledger[:] = 0.0
    e0 = sim.energies_J()["contact"]
    force = sim.forces_N()[moving].sum(axis=0) @ step
    work = 0.0
    for _ in range(substeps):
        sim.state.x[moving] += step / units.LENGTH
        sim.compute_forces()
        now = sim.forces_N()[moving].sum(axis=0) @ step
        work += 0.5 * (force + now)
        force = now
    booked = float(sim.work.ledger[:, OWNER_CHANGES].sum()) * units.ENERGY
    return sim.energies_J()["contact"] - e0, work, booked


@pytest.mark.parametrize("law", ["linear", "hertz"])
def test_the_union_rules_owner_changes_are_booked_and_close_the_contact_energy(law):
    """In a trough (a yarn between two edges of a bent rail, edges shorter than d) the union rule passes the
    contact from edge to edge, and the counted energy jumps where the closest point reaches a node. The jumps
    are booked (OWNER_CHANGES) at the mean of their two ends: the contact energy's change is then the work of
    its forces plus the jumps, to second order in the substep (all pairs: no jumps, a conservative potential),
    with either normal law (kernels/contact_law.py)."""
    change, work, booked = slide_through_a_trough("union", law=law)
    assert abs(change + work) > 0.1 * abs(change)  # the counted energy is not a potential alone ...
    assert abs(change + work - booked) < 1e-4 * abs(booked)  # ... the booked jumps are what is missing
    change, work, booked = slide_through_a_trough("all_pairs", law=law)
    assert booked == 0.0 and abs(change + work) < 1e-4 * abs(change)


def test_counting_every_pair_halves_the_stable_contact_step():
    """all_pairs may put four pairs' stiffness on one node (a crossing at a node of both
    yarns), so its contact time-step limit is half that of union counting."""
    from knitlad.engine.contact import contact_time_step

    rods = pressed_weave()
    union = contact_time_step(rods.model, ContactModel(stiffness=1e3))
    every = contact_time_step(rods.model, ContactModel(stiffness=1e3, counting="all_pairs"))
    assert every == pytest.approx(union / 2, rel=1e-12)
    with pytest.raises(ValueError, match="counting"):
        ContactModel(stiffness=1e3, counting="pairs")


def test_contact_forces_are_bit_for_bit_the_same_on_one_and_two_threads():
    """The pairs are evaluated in parallel blocks but added to the forces in pair order."""
    import numba

    from knitlad.engine import units
    from knitlad.engine.kernels.contact import MIN_PAIRS_PER_THREAD
    from knitlad.engine.simulation import numba_threads

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs two Numba threads")
    rng = np.random.default_rng(7)
    rods = plain_weave(20, spacing=4 * D, nodes_per_spacing=6, amplitude=0.45 * D).build()
    rods.state.v[:] = rng.normal(scale=2.0, size=rods.state.v.shape) / units.VELOCITY  # a few m/s: sliding contacts
    rods.state.v[rods.model.held] = 0.0
    finals = []
    for threads in (1, 2):
        with numba_threads(threads):
            sim = kl.Simulation(rods.copy(), contact=ContactModel(stiffness=1e3, mu=0.02))
            assert sim.contacts.threads[0] == threads
            sliding = 0
            for _ in range(30):
                sim.step(10)
                sliding = max(sliding, sim.contact_stats().sliding)
        if threads == 2:
            assert sim.contacts.n_pairs[0] >= 2 * MIN_PAIRS_PER_THREAD  # the parallel path ran
            assert sliding > 0
        finals.append(sim.state.x.copy())
    assert np.array_equal(finals[0], finals[1])


@pytest.mark.parametrize("spin", [False, True])
def test_the_contact_sum_rod_by_rod_is_the_serial_sum_over_the_pairs_to_the_bit(spin):
    """Each rod (a yarn of the state) adds its pairs' shares to its own nodes, on its own thread: every node
    must receive them in pair order, the order of one serial sum over the pairs (forces already on the nodes,
    so that another order would show in the bits), and the statistics must be those of all touching pairs."""
    from numba import njit

    from knitlad.engine import units
    from knitlad.engine.kernels import contact as kc
    from knitlad.engine.kernels.options import NUMBA_OPTS

    @njit(**dict(NUMBA_OPTS, cache=False))
    def serial_sum(pairs, n, res, edge_a, edge_b, spin, F, torque):
        for p in range(n):
            if res[p, kc.OVERLAP] <= 0.0:
                continue
            a0, a1 = edge_a[pairs[p, 0]], edge_b[pairs[p, 0]]
            b0, b1 = edge_a[pairs[p, 1]], edge_b[pairs[p, 1]]
            s, t = res[p, kc.S_PAIR], res[p, kc.T_PAIR]
            for d in range(3):
                f = res[p, kc.FORCE_X + d]
                F[a0, d] += (1 - s) * f
                F[a1, d] += s * f
                F[b0, d] -= (1 - t) * f
                F[b1, d] -= t * f
            if spin:
                torque[pairs[p, 0]] += res[p, kc.TORQUE_I]
                torque[pairs[p, 1]] += res[p, kc.TORQUE_J]

    # ten parallel yarns pressed side by side, stored so that neighbours fall in different halves of the
    # list: many nodes get shares from both blocks of pairs, whose order then shows in the bits
    scene = kl.Scene(kl.NYLON)
    s = np.linspace(0.0, 150 * D, 151)
    for k in (0, 5, 1, 6, 2, 7, 3, 8, 4, 9):
        scene.add_yarn(np.column_stack([s + 0.3 * D * (k % 2), np.full_like(s, 0.95 * D * k), 0 * s]))
    rods = scene.build()
    rng = np.random.default_rng(11)
    m, x = rods.model, rods.state.x
    v = rng.normal(scale=2.0, size=x.shape) / units.VELOCITY
    omega = rng.normal(size=m.edge_a.shape[0])
    c = make_contacts(rods, ContactModel(stiffness=1e3, mu=0.3, capacity_per_edge=8))
    assert kc.refresh_contacts(x, m.edge_a, m.edge_b, m.edge_shift, c, v, 0.0)
    base, base_torque = rng.normal(size=x.shape), rng.normal(size=m.edge_a.shape[0])
    for evaluation in range(2):  # the list's first evaluation, then one that skips pairs by their gaps
        force, torque = base.copy(), base_torque.copy()
        kc.contact_forces(x, v, omega, int(spin), m.mass, m.edge_a, m.edge_b, m.edge_shift, c, 1e-5, force, torque, v,
                          omega, False, np.zeros((4, N_LEDGER)))
        n = int(c.n_pairs[0])
        assert n >= 2 * kc.MIN_PAIRS_PER_THREAD  # the rods run in parallel where there are two threads
        expected, expected_torque = base.copy(), base_torque.copy()
        serial_sum(c.pairs, n, c.pair_results, m.edge_a, m.edge_b, spin, expected, expected_torque)
        assert np.array_equal(force, expected) and not np.array_equal(force, base)
        assert np.array_equal(torque, expected_torque)
        touching = c.pair_results[:n, kc.OVERLAP] > 0.0
        assert c.stats[kc.TOUCHING] == touching.sum() > 100
        assert c.stats[kc.SLIDING_PAIRS] == c.pair_results[:n, kc.SLIDING][touching].sum()
        assert c.stats[kc.MAX_OVERLAP] == c.pair_results[:n, kc.OVERLAP].max()
        assert c.stats[kc.NORMAL_FORCE_SUM] == pytest.approx(c.pair_results[:n, kc.NORMAL][touching].sum(),
                                                             rel=1e-12)


def test_the_sagitta_correction_is_the_mean_offset_of_an_arc_from_its_chord():
    """On a circle of radius R, the arc over a chord of length l lies l^2 s (1 - s) / (2 R) from it at s
    along the chord, l^2 / (12 R) on average (to O(l/R)^2): exactly what the correction takes off."""
    from knitlad.engine.contact import sagitta_corrected_radius

    R, l, r = 11.0, 2.9, 0.5  # in diameters: the default preset's R, the fast preset's segment
    x = (np.linspace(0.0, 1.0, 200001) - 0.5) * l
    offset = np.sqrt(R**2 - x**2) - np.sqrt(R**2 - (l / 2) ** 2)
    mean_offset = np.trapezoid(offset, x) / l
    taken = r - sagitta_corrected_radius(np.array([r]), np.array([l]), R)[0]
    assert taken == pytest.approx(mean_offset, rel=(l / R) ** 2)


def straight_yarn(scene, n: int, spacing: float, y: float = 0.0, x0: float = 0.0):
    points = np.zeros((n, 3))
    points[:, 0] = x0 + spacing * np.arange(n)
    points[:, 1] = y
    return scene.add_yarn(points)


def test_contacts_take_the_sagitta_off_each_edge_and_keep_their_skin_and_exclusion():
    scene = kl.Scene(kl.NYLON)
    straight_yarn(scene, 30, 0.4 * D)
    straight_yarn(scene, 30, 0.2 * D, y=0.9 * D)
    rods = scene.build()
    R = 11 * D
    plain = make_contacts(rods, ContactModel(stiffness=1.0))
    corrected = make_contacts(rods, ContactModel(stiffness=1.0, sagitta_radius=R))
    rest = rods.model.rest_length
    expected = plain.edge_radius - rest**2 / (12 * R / kl.units.LENGTH)
    np.testing.assert_allclose(corrected.edge_radius, expected, rtol=1e-12)
    assert corrected.params.skin == plain.params.skin
    np.testing.assert_array_equal(corrected.exclusion, plain.exclusion)
    with pytest.raises(ValueError, match="too long for the sagitta correction"):
        make_contacts(rods, ContactModel(stiffness=1.0, sagitta_radius=0.05 * D))


def test_the_two_ends_of_a_cut_do_not_push_each_other_apart():
    """Segments of d/2 (140 nodes per stitch): the capsules on either side of a cut edge overlap by d/2.
    The pieces stay one yarn for the contact (RodModel.yarn_parent), so the new ends are neighbours
    along it and do not touch; two yarns built end to end at the same gap do."""
    from knitlad.engine.simulation import Simulation
    from knitlad.engine.state import cut_edge

    scene = kl.Scene(kl.NYLON)
    straight_yarn(scene, 41, 0.5 * D)
    rods = cut_edge(scene.build(), 20)
    sim = Simulation(rods, contact=ContactModel.for_knit(kl.NYLON))
    sim.compute_forces()
    assert sim.contact_stats().touching == 0
    assert np.abs(sim.forces_N()).max() == 0.0
    apart = kl.Scene(kl.NYLON)
    straight_yarn(apart, 21, 0.5 * D)
    straight_yarn(apart, 20, 0.5 * D, x0=10.5 * D)
    sim = Simulation(apart.build(), contact=ContactModel.for_knit(kl.NYLON))
    sim.compute_forces()
    assert sim.contact_stats().touching == 1


def test_per_contact_read_out_carries_each_crossing_and_sums_to_the_totals():
    """Simulation.contact_pairs: one row per touching crossing of the pressed weave, normal forces
    summing to the kernel's total, no friction at rest, the point midway between the two axes."""
    sim = kl.Simulation(pressed_weave(), contact=ContactModel(stiffness=1e3))
    pairs, stats = sim.contact_pairs(), sim.contact_stats()
    assert len(pairs.edges) == stats.touching >= 16
    assert np.all(pairs.yarns[:, 0] != pairs.yarns[:, 1])  # crossings of warp and weft only
    assert np.linalg.norm(pairs.normal_N, axis=1).sum() == pytest.approx(stats.normal_force_sum_N, rel=1e-12)
    np.testing.assert_allclose(pairs.friction_N, 0.0, atol=1e-15)
    assert np.all(pairs.overlap_m == pytest.approx(0.2 * D, rel=0.05)) and not pairs.sliding.any()
    # the contact point sits at half the axes' distance, (d - overlap) / 2, from each yarn's centreline
    x = sim.positions_m()
    for k, (point, edges) in enumerate(zip(pairs.points_m, pairs.edges)):
        for e in edges:
            a, b = x[sim.model.edge_a[e]], x[sim.model.edge_b[e]]
            s = np.clip(np.dot(point - a, b - a) / np.dot(b - a, b - a), 0, 1)
            assert np.linalg.norm(point - a - s * (b - a)) == pytest.approx(0.5 * (D - pairs.overlap_m[k]), rel=1e-6)


def test_per_contact_friction_is_at_the_coulomb_limit_where_a_pair_slides():
    """A straight yarn dragged at 1 m/s across two others, all held rigid, pressed 0.2 d into them:
    the sliding rows carry mu |f_n| of friction, tangential to the normal; no row carries more."""
    mu = 0.4
    scene = kl.Scene(kl.NYLON)
    t = np.linspace(-10 * D, 10 * D, 21)
    dragged = scene.add_yarn(np.column_stack([t, np.zeros_like(t), np.full_like(t, 0.8 * D)]))
    scene.hold(dragged, range(t.size), velocity=(1.0, 0.0, 0.0))
    for x0 in (-3 * D, 3 * D):
        crossed = scene.add_yarn(np.column_stack([np.full_like(t, x0), t, np.zeros_like(t)]))
        scene.hold(crossed, range(t.size))
    sim = kl.Simulation(scene.build(), contact=ContactModel(stiffness=1e3, mu=mu), dt_s=1e-6)
    sim.step(100)  # 100 um of drag (all held: no stability limit), beyond the tangential spring's stick length
    pairs = sim.contact_pairs()
    fn, ft = np.linalg.norm(pairs.normal_N, axis=1), np.linalg.norm(pairs.friction_N, axis=1)
    assert pairs.sliding.any() and np.all(fn > 0)
    np.testing.assert_allclose(ft[pairs.sliding], mu * fn[pairs.sliding], rtol=1e-6)
    assert np.all(ft <= mu * fn * (1 + 1e-9))
    assert np.all(np.abs(np.sum(pairs.friction_N * pairs.normal_N, axis=1)) <= 1e-9 * fn * fn)
    assert np.all(pairs.friction_N[pairs.sliding, 0] < 0)  # friction on the dragged yarn opposes its motion


def test_skipping_pairs_whose_stored_gap_rules_them_out_changes_no_bit():
    """The narrow phase skips candidate pairs whose gap at the list's rebuild exceeds their edges'
    displacements since: a shaken, pressed weave with friction steps to the same bits as with every
    pair tested at every evaluation (the stored gaps forgotten before each step)."""
    from knitlad.engine.kernels.contact import GAPS_KNOWN

    def shaken(forget_gaps: bool) -> np.ndarray:
        rods = pressed_weave()
        rng = np.random.default_rng(3)
        rods.state.v[:] = rng.normal(scale=0.2, size=rods.state.v.shape)  # m/s: pairs close and open
        sim = kl.Simulation(rods, contact=ContactModel(stiffness=1e3, mu=0.4))
        known = 0
        for _ in range(400):
            if forget_gaps:
                sim.contacts.status[GAPS_KNOWN] = 0
            sim.step(1)
            known += int(sim.contacts.status[GAPS_KNOWN])
        assert known == 400  # the gaps were known after every evaluation (the skip was on when not forgotten)
        return sim.state.x.copy()

    np.testing.assert_array_equal(shaken(False), shaken(True))


def test_each_pair_of_materials_has_its_own_contact_stiffness():
    """Three yarns crossing at right angles, overlapping by 5 % d at rest: the normal force over the
    overlap is the pair's k_n (the steel-nylon entry), the default for nylon on nylon."""
    steel = kl.Material(diameter=D, line_density=1.2e-4, young_modulus=2.0e11)
    scene = kl.Scene(kl.NYLON)
    s = np.linspace(-4 * D, 4 * D, 9)
    gap = 0.95 * D
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))                          # nylon along x
    scene.add_yarn(np.column_stack([0 * s + 0.5 * D, s, 0 * s + gap]), material=steel)  # steel along y, above
    scene.add_yarn(np.column_stack([0 * s - 0.5 * D, s, 0 * s - gap]))           # nylon along y, below
    model = ContactModel(stiffness=1e3, pair_stiffness=[(kl.NYLON, steel, 7e3)])
    pairs = kl.Simulation(scene.build(), contact=model).contact_pairs()
    stiffness = {frozenset(map(int, yarns)): np.linalg.norm(normal) / overlap
                 for yarns, normal, overlap in zip(pairs.yarns, pairs.normal_N, pairs.overlap_m)}
    assert len(stiffness) == 2
    assert stiffness[frozenset((0, 1))] == pytest.approx(7e3, rel=1e-9)
    assert stiffness[frozenset((0, 2))] == pytest.approx(1e3, rel=1e-9)
    assert ContactModel(stiffness=1e3).pair_stiffness == ()
    with pytest.raises(ValueError, match="pair_stiffness"):
        ContactModel(stiffness=1e3, pair_stiffness=[(kl.NYLON, steel, -1.0)])
    with pytest.raises(ValueError, match="pair_stiffness"):
        ContactModel(stiffness=1e3, pair_stiffness=[(kl.NYLON, "steel", 1.0)])
    rods = scene.build()  # the stiffest pair sets the step
    assert contact_time_step(rods.model, model) == pytest.approx(
        contact_time_step(rods.model, ContactModel(stiffness=7e3)), rel=1e-12)
    # a material no yarn has (here hidden by a softened EA) is refused, not left at the default stiffness
    from knitlad.engine.state import with_axial_stiffness

    with pytest.raises(ValueError, match="pair_stiffness: no yarn of material"):
        kl.Simulation(with_axial_stiffness(rods, 0.5), contact=model)


def test_the_edges_largest_displacement_is_the_nodes_to_the_bit():
    """refresh_contacts tests the rebuild on the edges' displacements (one pass for it and the narrow phase's
    skipping): the largest over the edges is the largest over the nodes, bit for bit."""
    from knitlad.engine.kernels.contact import edge_displacements

    rods = pressed_weave()
    m, x_ref = rods.model, rods.state.x
    rng = np.random.default_rng(7)
    x = x_ref + rng.normal(scale=1e-3, size=x_ref.shape)
    out = np.zeros(m.edge_a.shape[0])
    largest = edge_displacements(x, x_ref, m.edge_a, m.edge_b, np.zeros(m.edge_a.shape[0]), out)
    d = x - x_ref
    assert largest == np.sqrt(np.max(d[:, 0] ** 2 + d[:, 1] ** 2 + d[:, 2] ** 2)) == out.max()
    ends = np.unique(np.concatenate([m.edge_a, m.edge_b]))
    assert ends.size == m.n_nodes  # every node ends an edge: the premise


def test_a_pair_that_parts_while_skipped_loses_its_tangential_spring():
    """A pair that touched at the last evaluation and that the stored gaps rule out now (it is not tested)
    must have its tangential spring cleared, as a pair found apart does, or it would come back with a stale
    friction force."""
    from knitlad.engine import units
    from knitlad.engine.kernels.contact import GAPS_KNOWN, OVERLAP, contact_forces, refresh_contacts

    rods = plain_weave(4, spacing=4 * D, nodes_per_spacing=6, amplitude=0.55 * D).build()  # axes 1.1 d apart
    m, x0 = rods.model, rods.state.x.copy()
    c = make_contacts(rods, ContactModel(stiffness=1e3, mu=0.4))
    force, torque, omega = np.zeros_like(x0), np.zeros(m.edge_a.shape[0]), np.zeros(m.edge_a.shape[0])
    first = slice(m.yarn_start[0], m.yarn_start[1])

    def evaluate(x, v):
        assert refresh_contacts(x, m.edge_a, m.edge_b, m.edge_shift, c, v, 0.0)
        force[:] = 0.0
        contact_forces(x, v, omega, 0, m.mass, m.edge_a, m.edge_b, m.edge_shift, c, 1e-5, force, torque, v, omega,
                       False, np.zeros((4, N_LEDGER)))
        n = int(c.n_pairs[0])
        return c.pair_results[:n, OVERLAP].copy(), np.abs(c.slip[:n]).sum(axis=1)

    still = np.zeros_like(x0)
    overlap, _ = evaluate(x0, still)  # the list's first evaluation: every pair apart, gaps stored
    assert c.status[GAPS_KNOWN] == 1 and not np.any(overlap > 0)
    pressed, sliding = x0.copy(), still.copy()
    pressed[first, 2] += 0.2 * D / units.LENGTH  # the first yarn pressed into half of its crossings (no rebuild)
    sliding[first, 0] = 0.1 / units.VELOCITY  # and drawn along them: the springs stretch
    overlap, spring = evaluate(pressed, sliding)
    assert np.any(overlap > 0) and np.all(spring[overlap > 0] > 0)
    overlap, spring = evaluate(x0, still)  # back where the gaps were stored: every pair skipped
    assert not np.any(overlap > 0) and not np.any(spring > 0)


@pytest.mark.parametrize("n_blocks", [1, 2, 3, 7])
def test_the_slip_history_carried_across_a_rebuild_is_the_same_in_any_number_of_blocks(n_blocks):
    """A pair in both lists keeps its history (slip, union verdict), a new pair starts from none (the merge in blocks, each starting
    at its first key by a binary search)."""
    from knitlad.engine.kernels.contact import carry_history

    rng = np.random.default_rng(n_blocks)
    old_keys = np.unique(rng.integers(0, 400, 150))
    new_keys = np.unique(np.concatenate([rng.choice(old_keys, 60, replace=False), rng.integers(0, 400, 80)]))
    old_slip = rng.normal(size=(old_keys.size + 5, HISTORY_COLUMNS))  # rows past n_old are not the list's
    new_slip = np.full((new_keys.size, HISTORY_COLUMNS), np.nan)
    carry_history(old_keys, old_slip, old_keys.size, new_keys, new_slip, new_keys.size, n_blocks)
    row_of = {int(k): i for i, k in enumerate(old_keys)}
    expected = np.array([old_slip[row_of[int(k)]] if int(k) in row_of else np.zeros(HISTORY_COLUMNS) for k in new_keys])
    assert np.array_equal(new_slip, expected)
    assert 0 < np.isin(new_keys, old_keys).sum() < new_keys.size  # both kinds of pair were there


def test_the_broad_phase_in_blocks_finds_the_serial_list_in_its_order():
    """Midpoints, cells, search and concatenation run on blocks of edges: the list is the one-block list, with
    fresh work arrays or with those of an earlier build (ListScratch)."""
    from knitlad.engine.kernels.contact import build_candidate_pairs, list_scratch

    rods = pressed_weave()
    c = make_contacts(rods, ContactModel(stiffness=1e3))
    m, x = rods.model, rods.state.x
    lists = []
    kept = list_scratch(m.edge_a.shape[0], 0)  # the work arrays of a rebuild, reused as refresh_contacts does
    for blocks, scratch in ((1, None), (2, None), (5, None), (2, kept), (1, kept)):
        pairs = np.full_like(c.pairs, -1)
        keys = np.full_like(c.keys, -1)
        n = build_candidate_pairs(x, m.edge_a, m.edge_b, m.edge_shift, c.edge_radius, c.edge_yarn, c.edge_local,
                                  c.yarn_edges, c.yarn_closed, c.exclusion, c.edge_image, 3 * D / kl.units.LENGTH,
                                  c.params.skin, pairs, keys, blocks, None, 0, scratch)
        assert 0 < n <= pairs.shape[0]
        lists.append((pairs[:n].copy(), keys[:n].copy()))
    for pairs, keys in lists[1:]:
        assert np.array_equal(pairs, lists[0][0]) and np.array_equal(keys, lists[0][1])
    assert np.all(np.diff(lists[0][1]) > 0)


def test_a_fast_yarn_gets_its_own_allowance_and_the_run_keeps_every_bit():
    """A yarn pulled through a pressed weave by its ends at 200 m/s (its crossings change all the time) with
    friction: the list that gives its fast edges an allowance of their own (ContactParams.lookahead_steps) is
    rebuilt far less often than the list of half a skin for all, and the two runs step to the same bits, which
    they could not if the first list ever missed a touching pair."""
    from knitlad.engine.kernels.contact import REBUILDS

    def pulled(lookahead: bool):
        rods = pressed_weave()
        first = slice(int(rods.model.yarn_start[0]), int(rods.model.yarn_start[1]))
        axis = rods.state.x[first][-1] - rods.state.x[first][0]
        velocity = 200.0 * axis / np.linalg.norm(axis)  # m/s
        rods.state.v[first] = velocity / kl.units.VELOCITY
        sim = kl.Simulation(rods, contact=ContactModel(stiffness=1e3, mu=0.4))
        sim.hold(sim.nodes_of(0, [0, -1]), velocity)
        c = sim.contacts
        # 40 steps: at the default 80 the pushed yarns turn fast too, over a quarter of this small weave's
        # edges, and the list falls back to half the skin for all (the next test)
        sim.contacts = c._replace(params=c.params._replace(lookahead_steps=40.0 if lookahead else 0.0))
        assert (sim.contacts.params.lookahead_steps > 0) == lookahead
        rebuilds, widest, counted = 0, 0.0, int(sim.contacts.status[REBUILDS])
        for _ in range(300):
            ref = sim.contacts.x_ref.copy()
            sim.step(1)
            rebuilds += not np.array_equal(ref, sim.contacts.x_ref)
            widest = max(widest, float(sim.contacts.edge_allowance.max() / (0.5 * sim.contacts.params.skin)))
        assert sim.contacts.status[REBUILDS] - counted == rebuilds  # the kernel's count of its rebuilds
        last = float(sim.contacts.edge_allowance.max() / (0.5 * sim.contacts.params.skin))
        return sim.state.x.copy(), rebuilds, widest, last

    x_aware, rebuilds_aware, widest, _ = pulled(True)
    x_uniform, rebuilds_uniform, _, last_uniform = pulled(False)
    np.testing.assert_array_equal(x_aware, x_uniform)
    # fast edges had more than half the skin with lookahead; without, every rebuild gives half the skin to all
    assert widest > 2.0 and last_uniform == 1.0
    assert rebuilds_aware < 0.5 * rebuilds_uniform


def test_a_fast_edge_lists_every_pair_within_the_sum_of_allowances():
    """The broad phase with allowances (one fast edge of 3 half-skins): its list is the list of half a skin for
    all plus exactly the fast edge's pairs whose gap lies between the skin and the sum of the two allowances."""
    from knitlad.engine.kernels.contact import build_candidate_pairs, segment_distance

    rods = pressed_weave()
    c = make_contacts(rods, ContactModel(stiffness=1e3))
    m, x, skin = rods.model, rods.state.x, c.params.skin
    fast = 20
    allowance = np.full(m.edge_a.shape[0], 0.5 * skin)
    allowance[fast] = 1.5 * skin

    def listed(allow, n_fast):
        pairs = np.zeros_like(c.pairs)
        keys = np.zeros_like(c.keys)
        n = build_candidate_pairs(x, m.edge_a, m.edge_b, m.edge_shift, c.edge_radius, c.edge_yarn, c.edge_local,
                                  c.yarn_edges, c.yarn_closed, c.exclusion, c.edge_image, 3 * D / kl.units.LENGTH,
                                  skin, pairs, keys, 2, allow, n_fast)
        assert np.all(np.diff(keys[:n]) > 0)  # sorted, no pair twice
        return {(int(i), int(j)) for i, j in pairs[:n]}

    plain = listed(allowance, 0)
    wide = listed(allowance, 1)
    extra = wide - plain
    assert plain <= wide and extra and all(fast in pair for pair in extra)
    for i, j in extra:
        dist = segment_distance(x, m.edge_a, m.edge_b, m.edge_shift, i, j)[0]
        assert c.edge_radius[i] + c.edge_radius[j] + skin <= dist < c.edge_radius[i] + c.edge_radius[j] + 2 * skin
    # and none left out: every partner of the fast edge within the sum of allowances is listed
    for j in range(m.edge_a.shape[0]):
        pair = (min(fast, j), max(fast, j))
        if j == fast or (c.edge_yarn[j] == c.edge_yarn[fast] and abs(c.edge_local[j] - c.edge_local[fast]) <= c.exclusion[0]):
            continue
        dist = segment_distance(x, m.edge_a, m.edge_b, m.edge_shift, *pair)[0]
        if dist < c.edge_radius[fast] + c.edge_radius[j] + 2 * skin:
            assert pair in wide


def test_many_fast_edges_list_exactly_the_pairs_within_their_allowances():
    """A third of the edges fast, with allowances of 1 to 6 half-skins (fast partners of fast edges meet in the
    sweep along x, slow ones in the cells): the list is exactly the pairs a search of every pair finds, those
    within the skin and those of a fast edge within the sum of the two allowances; sorted, each pair once."""
    from knitlad.engine.kernels.contact import build_candidate_pairs, excluded_along_yarn, segment_distance

    rods = pressed_weave()
    c = make_contacts(rods, ContactModel(stiffness=1e3), capacity=40_000)
    m, x, skin = rods.model, rods.state.x, c.params.skin
    ne = m.edge_a.shape[0]
    rng = np.random.default_rng(3)
    allowance = np.full(ne, 0.5 * skin)
    fast = rng.random(ne) < 1 / 3
    allowance[fast] = 0.5 * skin * rng.uniform(1.0, 6.0, fast.sum())
    pairs = np.zeros_like(c.pairs)
    keys = np.zeros_like(c.keys)
    n = build_candidate_pairs(x, m.edge_a, m.edge_b, m.edge_shift, c.edge_radius, c.edge_yarn, c.edge_local,
                              c.yarn_edges, c.yarn_closed, c.exclusion, c.edge_image, 3 * D / kl.units.LENGTH, skin,
                              pairs, keys, 2, allowance, int(fast.sum()))
    assert n <= pairs.shape[0] and np.all(np.diff(keys[:n]) > 0)
    listed = {(int(i), int(j)) for i, j in pairs[:n]}
    expected = set()
    for i in range(ne):
        for j in range(i + 1, ne):
            if (c.edge_image[i] and c.edge_image[j]) or excluded_along_yarn(
                    i, j, c.edge_yarn, c.edge_local, c.yarn_edges, c.yarn_closed, c.exclusion):
                continue
            dist = segment_distance(x, m.edge_a, m.edge_b, m.edge_shift, i, j)[0]
            radii = c.edge_radius[i] + c.edge_radius[j]
            if dist < radii + skin or ((fast[i] or fast[j]) and dist < radii + allowance[i] + allowance[j]):
                expected.add((i, j))
    assert listed == expected
    beyond_skin = [p for p in listed if segment_distance(x, m.edge_a, m.edge_b, m.edge_shift, *p)[0]
                   >= c.edge_radius[p[0]] + c.edge_radius[p[1]] + skin]
    assert sum(fast[i] and fast[j] for i, j in beyond_skin) > 0  # the sweep found pairs of two fast edges


def test_where_most_edges_move_fast_every_edge_keeps_half_the_skin():
    """The fast edges' pass is serial: with more than MAX_FAST_FRACTION of the edges fast (the whole weave
    flying), the rebuild falls back to half the skin for every edge; one fast yarn of eight keeps its own."""
    from knitlad.engine.kernels.contact import STALE, refresh_contacts

    rods = pressed_weave()
    m, x = rods.model, rods.state.x
    c = make_contacts(rods, ContactModel(stiffness=1e3), capacity=20_000)  # the widened list needs more room
    half = 0.5 * c.params.skin
    lookahead = 40 * 3e-5  # 40 steps of 3e-8 s, internal ms
    first = slice(int(m.yarn_start[0]), int(m.yarn_start[1]))
    for flying, widened in ((slice(None), False), (first, True)):
        v = np.zeros_like(x)
        v[flying] = 200.0  # mm/ms = m/s
        c.status[STALE] = 1
        assert refresh_contacts(x, m.edge_a, m.edge_b, m.edge_shift, c, v, lookahead)
        assert (c.edge_allowance.max() > half) == widened and c.edge_allowance.min() == half


@pytest.mark.parametrize("factor", [1.0, 2.5])
def test_a_yarn_of_its_own_friction_slides_at_its_factor_times_mu(factor):
    """A yarn dragged at 0.1 m/s across a held one it presses (both held, overlap 0.05 d), mu 0.2: once
    sliding, the friction force is factor x mu x the normal force when the dragged yarn has
    ``yarn_friction`` factor (ContactModel.yarn_friction: a coated course), mu x it otherwise."""
    s = np.linspace(-0.002, 0.002, 10)
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))
    scene.add_yarn(np.column_stack([0 * s, s, 0 * s + 0.95 * D]))
    scene.add_yarn(np.column_stack([s, 0 * s, 0 * s - 5 * D]))  # touching nothing: it must not change the classes' rows
    for yarn in range(3):
        scene.hold(yarn, list(range(10)))
    sim = kl.Simulation(scene.build(), contact=ContactModel(stiffness=1e3, mu=0.2, yarn_friction=((1, factor),)))
    sim.hold(sim.nodes_of(1), velocity_m_s=(0.1, 0.0, 0.0))
    sim.run(2e-5)
    pairs = sim.contact_pairs()
    assert len(pairs.edges) == 1 and pairs.sliding[0]
    ratio = np.linalg.norm(pairs.friction_N[0]) / np.linalg.norm(pairs.normal_N[0])
    assert ratio == pytest.approx(0.2 * factor, rel=1e-6)


def test_a_yarn_friction_entry_must_name_a_yarn_of_the_rods_and_a_factor_of_zero_or_more():
    with pytest.raises(ValueError, match="yarn_friction entries"):
        ContactModel(stiffness=1e3, yarn_friction=((0, -1.0),))
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([np.linspace(0, 0.002, 5), np.zeros(5), np.zeros(5)]))
    with pytest.raises(ValueError, match="no yarn 3"):
        kl.Simulation(scene.build(), contact=ContactModel(stiffness=1e3, yarn_friction=((3, 2.0),)))
