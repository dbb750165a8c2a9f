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
