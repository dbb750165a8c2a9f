"""Each script of examples/ against the known result it shows."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from tests.script_loading import ROOT, load_script

EXAMPLES = ROOT / "examples"


def example(name: str):
    return load_script("examples", name)


def test_the_column_buckles_at_euler_s_load_and_follows_the_elastica_past_it():
    """Pinned ends: P = P_E (1 + Delta / 2L) to first order in the end shortening Delta (the elastica),
    P_E = pi^2 B / L^2; 40 segments put the discrete load 0.05 % under the continuum's."""
    forces = example("euler_buckling").buckle(increments=5)
    euler = np.pi**2 * kl.NYLON.bending_stiffness / 0.02**2
    shortening = 0.01 * np.arange(1, 6) / 5
    np.testing.assert_allclose(forces / euler, 1 + shortening / 2, rtol=1e-3)


def test_each_sliding_contact_carries_mu_times_its_normal_force():
    fn, ft, pairs = example("coulomb_slide").drag(mu=0.4)
    assert pairs.sliding.all() and len(fn) >= 2
    np.testing.assert_allclose(ft / fn, 0.4, rtol=1e-6)
    assert np.all(pairs.friction_N[:, 0] < 0)  # against the drag along +x


def test_a_squeezed_ring_follows_the_thin_ring_closed_form_as_the_squeeze_vanishes():
    """delta = (pi/4 - 2/pi) F R^3 / B for point loads on a thin inextensible ring, to first order in
    delta/R: at delta = 0.01 R and 0.02 R the force falls short of it by 0.9 and 1.6 % (a softening first
    order in delta), and the straight line through the two meets it at delta = 0 within 0.5 %."""
    (f1, d1, c1), (f2, d2, c2) = example("ring_between_plates").squeeze(steps=(0.01, 0.02))
    e1, e2 = f1 / c1 - 1, f2 / c2 - 1
    assert -0.03 < e1 < 0 and 1.5 < e2 / e1 < 2.5  # first order in delta
    assert abs(e1 - (e2 - e1) / (d2 - d1) * d1) < 0.005


@pytest.mark.slow
def test_a_yarn_pulled_over_a_cylinder_follows_the_capstan_equation():
    """Steady sliding over half a turn: pull = load e^(mu pi). Frictionless the pull is the load (0.1 %);
    at mu = 0.3 the capstan law within 4 % (measured -2.1 %: the yarn's bending stiffness lifts it off
    the cylinder before the tangent points, a wrap of 3.07 rad for pi)."""
    capstan = example("capstan").capstan
    pull, load, _ = capstan(mu=0.0)
    assert pull == pytest.approx(load, rel=0.01)
    pull, load, law = capstan(mu=0.3)
    assert pull == pytest.approx(law, rel=0.04) and pull > 2.4 * load


@pytest.mark.slow
def test_a_node_pressed_on_a_plane_sticks_below_mu_n_and_slides_above_it_at_the_coulomb_rate():
    """A straight yarn lying on a plane (stiffness 100 N/m, mu = 0.4), each node pressed by N and pulled
    along x by T: at T = 0.5 mu N it holds (drift below the tangential spring's stretch T/k_t); at
    T = 2 mu N the whole yarn accelerates at (T - mu N)/m per node, the momentum balance of Coulomb
    sliding, within 1 %."""
    s = np.linspace(0, 0.01, 21)
    d, N, mu = kl.NYLON.diameter, 1e-5, 0.4
    for T, sliding in ((0.5 * mu * N, False), (2 * mu * N, True)):
        scene = kl.Scene(kl.NYLON)
        scene.add_yarn(np.column_stack([s, 0 * s, np.full_like(s, 0.5 * d - N / 100.0)]))
        sim = kl.Simulation(scene.build(), obstacles=[kl.Plane(stiffness=100.0, mu=mu)])
        sim.set_external_forces((T, 0.0, -N))
        sim.run(2e-3)
        drift = sim.positions_m()[:, 0] - s
        if sliding:
            mass = sim.model.mass.sum() * kl.units.MASS
            v = np.mean(sim.state.v[:, 0]) * kl.units.VELOCITY
            assert v == pytest.approx(len(s) * (T - mu * N) / mass * sim.time_s, rel=0.01)
            assert (sim.obstacle_contacts()[:, 0] == 2).all()
        else:
            assert np.abs(drift).max() < 2 * T / (0.5 * 100.0)
    assert sim.obstacle_reactions_N()[0, 2] == pytest.approx(-len(s) * N, rel=1e-3)


def test_a_yarn_dropped_on_a_cylinder_rests_on_it_as_two_cantilevers_carrying_its_weight():
    """After the fall and a relaxation the cylinder carries the weight (to the relaxation's tolerance,
    1e-3), and each end sags below the middle by w a^4 / (8 B) within 1 % (measured +0.2 %)."""
    weight, on_cylinder, sag, cantilever = example("yarn_on_cylinder").drop()
    assert on_cylinder[1] == pytest.approx(-weight, rel=1e-3) and abs(on_cylinder[0]) < 1e-3 * weight
    np.testing.assert_allclose(sag, cantilever, rtol=0.01)


@pytest.mark.slow
def test_pulling_a_course_out_of_a_knit_stores_the_work_without_friction_and_dissipates_with_it():
    """Frictionless statics: the pull's work (trapezoid rule over 10 steps of 0.02 mm) equals the stored
    energy gained within 1 % (measured 0.1 %). At mu = 0.4, every step settled (to 1e-6 N), the work
    exceeds the energy stored: the rest was dissipated by sliding (measured 7.6 % of the work)."""
    pull = example("pull_out").pull
    x, f, e = pull(mu=0.0)
    assert np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x)) == pytest.approx(e[-1] - e[0], rel=0.01) and e[-1] > e[0]
    x, f, e = pull(mu=0.4)
    assert np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x)) > e[-1] - e[0] > 0


def test_two_plied_yarns_press_on_each_other_with_the_line_force_of_a_helical_rod():
    """p = kappa (T + B tau^2) within 1 % at two pulls and two pitches; the bending term is of the
    tension's size (B tau^2 / T from 0.5 to 1.2), so dropping it would miss by a third or more."""
    for kwargs in ({}, {"pull": 0.02}, {"pitch": 3e-3}):
        p, kirchhoff, bending = example("plied_pair").ply(**kwargs)
        assert p == pytest.approx(kirchhoff, rel=0.01)
        assert bending > 0.4


@pytest.mark.parametrize("name", ["euler_buckling", "coulomb_slide", "ring_between_plates", "capstan",
                                  "yarn_on_cylinder", "pull_out", "plied_pair"])
def test_examples_are_short_and_use_only_the_public_api(name):
    text = (EXAMPLES / f"{name}.py").read_text()
    assert len(text.splitlines()) <= 40
    assert "from knitlad." not in text and "import knitlad." not in text


def test_the_hosiery_yarn_sets_its_own_scales_and_its_ladder_reports_them():
    """A 20 den nylon monofilament (2.22 tex at 1.14 g/cm^3: d = 49.8 um) at 2.5 mm per stitch: f0 = B kappa0^2
    with B = E pi d^4/64 and kappa0 = 2 pi/l0 (the paper's definitions), 1/4.1 of the paper's Nylon's; the worn
    stretch l_x = 10 mm/10.5 and l_y = 10 mm/16; the ladder's pull in N is f_x n_y f0 of this yarn."""
    hosiery = example("hosiery")
    cfg = hosiery.worn_stocking(6, max_time_ms=0.5)
    m = cfg.material()
    b = 1.88e9 * np.pi * 0.0498e-3**4 / 64
    assert m.line_density == pytest.approx(2.22e-6, rel=0.01)
    assert m.f0 == pytest.approx(b * (2 * np.pi / 2.5e-3) ** 2, rel=1e-12)
    assert (cfg.lx, cfg.ly) == pytest.approx((10 / 10.5 / 2.5, 10 / 16 / 2.5))
    s = hosiery.ladder(6, max_time_ms=0.5)
    assert s["force_ini_N"] == pytest.approx(s["fx_ini"] * 6 * m.f0, rel=1e-9)
    assert s["lx_mm"] == pytest.approx(2.5 * s["lx_over_l0"])
