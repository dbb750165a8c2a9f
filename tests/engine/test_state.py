import numpy as np
import pytest

import knitlad as kl


def line(n, length=0.01):
    pts = np.zeros((n, 3))
    pts[:, 0] = np.linspace(0, length, n)
    return pts


def test_many_yarns_share_one_state_with_offsets():
    scene = kl.Scene()
    scene.add_yarn(line(5))
    scene.add_yarn(line(7) + [0, 1e-3, 0], closed=True)
    s = scene.build().model
    assert s.yarn_start.tolist() == [0, 5, 12]
    assert s.edge_a.shape[0] == 4 + 7  # open: k-1 edges, closed: k
    assert s.hinge_e0.shape[0] == 3 + 7
    assert s.yarn_of(8) == (1, 3)
    # lumped masses add up to rho_L times the yarn length
    total_length = s.rest_length.sum() * kl.units.LENGTH
    assert s.mass.sum() * kl.units.MASS == pytest.approx(kl.NYLON.line_density * total_length)


def test_periodised_yarn_closes_with_its_shift():
    scene = kl.Scene()
    pts = line(4, length=0.003)
    scene.add_yarn(pts, closed=True, period=(0.004, 0, 0))
    s = scene.build().model
    np.testing.assert_allclose(s.rest_length * kl.units.LENGTH, 1e-3)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(points=np.zeros((1, 3))), "shape"),
        (dict(points=np.zeros((3, 3))), "coincide"),
        (dict(points=line(3) * np.nan), "NaN"),
        (dict(points=line(3), natural_curvature="bent"), "natural_curvature"),
        (dict(points=line(3), period=(1, 0, 0)), "closed"),
    ],
)
def test_bad_yarns_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        kl.Scene().add_yarn(**kwargs)


def test_natural_curvature_needs_twist():
    scene = kl.Scene()
    scene.add_yarn(line(4) + np.array([[0, 0, 0], [0, 1e-4, 0], [0, 0, 0], [0, 1e-4, 0]]), natural_curvature="rest")
    with pytest.raises(ValueError, match="twist"):
        scene.build(twist=False)


def test_the_framed_mode_is_said_never_read_from_the_arrays():
    """A yarn built with its curved rest shape is framed (the kernels' framed DER); one straight at rest is
    not, even with twist; a natural curvature handed over without the mode is refused, not guessed."""
    bent = line(5) + np.array([[0, 0, 0], [0, 1e-4, 0], [0, 0, 0], [0, 1e-4, 0], [0, 0, 0]])
    scene = kl.Scene()
    scene.add_yarn(bent, natural_curvature="rest")
    rods = scene.build()
    assert rods.twist and rods.framed and np.any(rods.model.kappa_bar)
    assert kl.Simulation(rods).twist_mode == kl.engine.kernels.integrate.TWIST_FRAMED
    straight = kl.Scene()
    straight.add_yarn(bent)
    plain = straight.build(twist=True)
    assert plain.twist and not plain.framed
    assert kl.Simulation(plain).twist_mode == kl.engine.kernels.integrate.TWIST_STRAIGHT
    unsaid = plain.replace_model(kappa_bar=rods.model.kappa_bar)
    with pytest.raises(ValueError, match="framed"):
        kl.Simulation(unsaid)
    assert kl.Simulation(plain.replace_model(kappa_bar=rods.model.kappa_bar, framed=True)).twist_mode == \
        kl.engine.kernels.integrate.TWIST_FRAMED
    with pytest.raises(ValueError, match="need twist"):
        kl.Rods(rods.model, rods.state, twist=False, framed=True)


def test_hold_out_of_range_is_refused():
    scene = kl.Scene()
    y = scene.add_yarn(line(4))
    with pytest.raises(IndexError):
        scene.hold(y, [4])


def test_a_node_on_a_rail_moves_only_along_it():
    """Scene.slide: a rod end pulled obliquely slides along its rail (x) and keeps y and z."""
    import knitlad as kl

    n = 11
    pts = np.zeros((n, 3))
    pts[:, 0] = np.linspace(0.0, 0.01, n)
    scene = kl.Scene(kl.NYLON)
    y = scene.add_yarn(pts)
    scene.hold(y, [0])
    scene.slide(y, [n - 1], (1.0, 0.0, 0.0))
    scene.apply_force(y, n - 1, (1e-3, 1e-3, -1e-3))
    sim = kl.Simulation(scene.build())
    sim.run(2e-4)
    tip = sim.positions_m()[-1]
    assert tip[0] > 0.01  # pulled out along the rail (the rod stretches)
    assert abs(tip[1]) < 1e-15 and abs(tip[2]) < 1e-15
    with pytest.raises(ValueError, match="axis"):
        scene.slide(y, [1], (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="friction"):
        scene.slide(y, [1], (1.0, 0.0, 0.0), friction=-0.1)


def test_a_softer_yarn_keeps_its_tensions_and_takes_a_longer_step():
    """with_axial_stiffness: EA' = EA/4 with the rest lengths reset, so every force of a stretched,
    bent rod is unchanged to round-off, and the stretching limit of the step doubles (1/sqrt(factor))."""
    from knitlad.engine.state import with_axial_stiffness
    from knitlad.engine.timestep import critical_time_steps

    n = 21
    s = np.linspace(0.0, 1.0, n)
    pts = np.stack([0.02 * s, 0.002 * np.sin(np.pi * s), np.zeros(n)], axis=1)
    scene = kl.Scene(kl.NYLON)
    y = scene.add_yarn(pts)
    scene.hold(y, [0, n - 1])
    rods = scene.build()
    rods.state.x[:, 0] *= 1.002  # stretched by 0.2 %: every edge under tension
    before = kl.Simulation(rods.copy())
    soft = with_axial_stiffness(rods, 0.25)
    after = kl.Simulation(soft)
    assert np.allclose(after.work.force, before.work.force, rtol=1e-9, atol=1e-12 * np.abs(before.work.force).max())
    assert np.allclose(soft.model.EA, 0.25 * rods.model.EA)
    ratio = critical_time_steps(soft.model, False).stretching / critical_time_steps(rods.model, False).stretching
    assert ratio == pytest.approx(2.0, rel=0.01)
    with pytest.raises(ValueError, match="factor"):
        with_axial_stiffness(rods, 1.5)


def test_frame_anchors_are_the_yarn_starts_and_the_cut_ends_and_need_hinges_in_order():
    """The edges whose reference frame the frame-free twist carries: each yarn's first edge and an edge
    no hinge ends on; the rebuild of the others needs the hinges stored along the yarn (refused if not)."""
    from knitlad.engine.state import cut_edge, frame_anchors

    scene = kl.Scene()
    scene.add_yarn(line(9) + np.array([[0, 1e-4 * (i % 2), 0] for i in range(9)]))  # a zigzag
    scene.add_yarn(np.column_stack([np.cos(np.arange(6)), np.sin(np.arange(6)), np.zeros(6)]) * 1e-3, closed=True)
    rods = cut_edge(scene.build(twist=True), 3)  # the open yarn's edges 0-2 and 3-6, the ring's 7-12
    assert np.flatnonzero(frame_anchors(rods.model)).tolist() == [0, 3, 7]
    m = rods.model
    with pytest.raises(ValueError, match="not stored in order"):
        frame_anchors(m._replace(hinge_e0=m.hinge_e0[::-1].copy(), hinge_e1=m.hinge_e1[::-1].copy()))


def test_a_yarn_straight_at_rest_can_start_crooked_without_twist():
    """add_yarn(rest, start=...): a 20 mm column straight at rest, started as a half sine of amplitude a.
    Its rest length is the straight one, its bending energy the continuum's B a^2 pi^4 / (4 L^3) (1 % at
    100 edges), and released with free ends it relaxes back to a straight rod of length L."""
    import knitlad as kl

    L, n, a = 0.02, 101, 2e-4
    s = np.linspace(0.0, L, n)
    rest = np.column_stack([s, 0 * s, 0 * s])
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(rest, start=np.column_stack([s, a * np.sin(np.pi * s / L), 0 * s]))
    rods = scene.build()
    assert not rods.twist
    assert rods.model.rest_length.sum() * kl.units.LENGTH == pytest.approx(L, rel=1e-12)
    sim = kl.Simulation(rods)
    bending = kl.NYLON.bending_stiffness * a**2 * np.pi**4 / (4 * L**3)
    assert sim.energies_J()["bending"] == pytest.approx(bending, rel=0.01)
    assert sim.relax(force_tol_N=1e-10)["converged"]
    x = sim.positions_m()
    off_line = np.linalg.svd(x - x.mean(axis=0), compute_uv=False)[1] / np.sqrt(n)
    assert off_line < 1e-4 * a and np.linalg.norm(x[-1] - x[0]) == pytest.approx(L, rel=1e-6)


def test_a_start_shape_must_match_the_rest_shape():
    import knitlad as kl

    with pytest.raises(ValueError, match="start must have the shape of points"):
        kl.Scene(kl.NYLON).add_yarn(np.zeros((3, 3)) + np.arange(3)[:, None], start=np.zeros((4, 3)))
