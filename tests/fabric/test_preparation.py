"""Preparing a knit (knitlad.fabric.preparation): where it is built, the tiled and affine stretches, force
control, the edges."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from knitlad.engine import units as kl_units
from knitlad.engine.simulation import Simulation
from knitlad.experiments.config import CutConfig
from knitlad.experiments.laddering import cut
from knitlad.fabric.preparation import KNIT_NOISE, KnitBox, build_width, stretch, stretch_contact
from knitlad.fabric.scenes.knit import BUILD_LX
from knitlad.fabric.stretching import OutOfReach, stretch_to
from knitlad.engine.units import NYLON


def config(**kw) -> CutConfig:
    """The coarse model these tests run (the fast preset: capsules of the yarn's radius, explicit axial springs)."""
    return CutConfig(**{"preset": "fast", **kw})


@pytest.mark.slow
def test_tall_cells_are_built_narrower_so_that_the_loops_interlock():
    """At l_y/l0 = 0.302, Crane loops built at 0.30 l0 overlap the next course by 0.12 d only and the
    knit comes apart; at the stitch's f_x = 0 width they overlap by more than 2 d."""
    assert build_width(0.25, NYLON) == BUILD_LX
    lx = build_width(0.302, NYLON)
    assert 0.24 < lx < 0.29
    box = KnitBox(config(n_x=4, n_y=6, lx=0.35, ly=0.302).stretch_settings())
    l0, d = NYLON.stitch_length, NYLON.diameter
    overlap = 2 * box.knit.H - 0.302 * l0
    assert overlap > 2 * d


@pytest.mark.parametrize("start", ["tiled", "affine"])
@pytest.mark.slow
def test_force_control_reaches_its_target_in_a_tall_knit(start):
    knit = stretch(config(n_x=6, n_y=8, fx=4.0, ly=0.302, resolution=16, stretch_start=start).stretch_settings())
    assert knit.fx_within_tolerance
    assert knit.fx_ini == pytest.approx(4.0, rel=0.02)


def test_the_tiled_stretch_relaxes_only_what_the_edges_change():
    """Force control from the periodised stitch: the knit reaches f_x 8 within the tolerance in
    fewer FIRE steps than one affine increment takes (the tiled knit is already at equilibrium
    but near its edges), and the stretch of a knit with tails, which the stitch has no copy of,
    stays affine."""
    cfg = config(n_x=8, n_y=8, fx=8.0)
    knit = stretch(cfg.stretch_settings())
    assert knit.fx_within_tolerance and knit.fx_ini == pytest.approx(8.0, rel=0.02)
    assert knit.relax_steps < cfg.steps_per_increment
    assert knit.box_lx == pytest.approx(knit.lx_over_l0, rel=0.002)
    tail = stretch(config(n_x=4, n_y=4, lx=0.33, edge="tail", resolution=16).stretch_settings())
    assert tail.relax_steps > 0 and tail.tension_history.shape[0] > 2


def _relax_in_rounds(box: KnitBox, rounds: int) -> tuple[list[float], dict]:
    """The protocol's FIRE rounds at a fixed box; f_x after each, and the last round's report."""
    readings, info = [], {}
    for _ in range(rounds):
        info = box.relax()
        readings.append(box.tension())
        if info["converged"]:
            break
    return readings, info


@pytest.mark.slow
def test_at_mu_0_a_knit_with_clamped_course_ends_reaches_equilibrium_at_a_fixed_box():
    """Course ends clamped at the edge sinkers (position and tangent, the mirror symmetry of the
    periodic stitch there): FIRE reaches its force tolerance (1e-3 f0), so f_x has settled. Ends held at the tip of
    straight tails instead leave the edge stitches free to trade yarn, and the knit creeps: 8 x 10
    at l_x/l0 = 0.355 wandered between f_x 1.21 and 1.46 over 30 rounds, residual ~0.4 f0."""
    clamped = KnitBox(config(n_x=8, n_y=10, lx=0.355, edge="clamped").stretch_settings())
    stretch_to(clamped, 0.355, 0.25, clamped.s.stretch_increment)
    readings, info = _relax_in_rounds(clamped, 40)
    assert info["converged"], f"residual {info['max_force_N'] / NYLON.f0:.3g} f0 after {len(readings)} rounds"

    tail = KnitBox(config(n_x=8, n_y=10, lx=0.355, edge="tail").stretch_settings())
    stretch_to(tail, 0.355, 0.25, tail.s.stretch_increment)
    _, info = _relax_in_rounds(tail, len(readings) + 10)
    assert info["max_force_N"] > 10 * 1e-3 * NYLON.f0


def test_an_unknown_edge_is_refused_before_anything_runs():
    with pytest.raises(ValueError, match="edge"):
        config(n_x=4, n_y=4, lx=0.35, edge="loose")


@pytest.mark.slow
def test_force_control_says_when_the_knit_as_built_is_already_past_the_target():
    """With tails, the 8 x 10 knit built at l_x/l0 = 0.30 carries f_x ~ 0.4: a target of 0.05
    cannot be reached by stretching, and force control says so (position control is advised)."""
    with pytest.raises(OutOfReach, match="use position control"):
        stretch(config(n_x=8, n_y=10, fx=0.05, edge="tail").stretch_settings())


@pytest.mark.parametrize("K", [0.0, 0.5])
def test_a_memory_band_remembers_its_own_curvature_and_the_rest_of_the_knit_its_own(K):
    """A curvature band (run-stop band of a yarn that remembers its knitted shape): its courses remember
    K_band, the others the knit's K, each a mean of (kappa_bar/kappa0)^2 over the course's hinges
    (knitlad.fabric.shape_memory); a knit of straight yarn (K = 0) has neither natural curvature nor
    natural twist outside the band; the tiled stretch still reaches its target tension."""
    from knitlad.fabric.shape_memory import mean_squared_curvature, voronoi_lengths

    cfg = config(n_x=4, n_y=6, fx=4.0, resolution=16, natural_curvature=K, band="curvature", band_row=4,
                 band_courses=1, band_curvature=2.0)
    knit = stretch(cfg.stretch_settings())
    model = knit.knit.rods.model
    hinge_yarn = model.edge_yarn[model.hinge_e1]
    lengths = voronoi_lengths(knit.knit.rods)
    for row, y in enumerate(knit.knit.courses):
        h = hinge_yarn == y
        remembered = mean_squared_curvature(model.kappa_bar[h], lengths[h], knit.settings.material)
        assert remembered == pytest.approx(2.0 if row == 4 else K, rel=0.02, abs=1e-12), row
        if row != 4 and K == 0:
            assert not model.twist_bar[h].any()
    assert knit.knit.rods.twist and knit.fx_within_tolerance
    assert knit.fx_ini == pytest.approx(4.0, rel=cfg.fx_tolerance)


def test_sliding_bars_let_the_edge_courses_slide_along_x_and_carry_their_share_of_the_load():
    """bars="sliding" (the experiment's clips): a bar's two end nodes held at each end, every other node on a
    rail along x. Stretched to f_x 4 at mu 0, the knit reaches its target, and the supports and rails together
    balance it: the sum of every reaction vanishes to 2e-3 of the pull F_y across the courses (measured
    7e-4; without the rails' share the sum is 0.2 F_y). Laddered with implicit axial springs, the bars' rail nodes keep their y and z
    to round-off while they slide along x."""
    cfg = config(n_x=6, n_y=6, fx=4.0, resolution=16, bars="sliding")
    knit = stretch(cfg.stretch_settings())
    assert knit.fx_within_tolerance
    rails = knit.knit.rods.model.rail_node
    starts = knit.knit.rods.model.yarn_start
    assert rails.size == sum(starts[b + 1] - starts[b] - 4 for b in knit.knit.bars)
    sim = Simulation(knit.knit.rods.copy(), contact=stretch_contact(knit.settings))
    reactions = sim.reaction_forces_N()
    supports = np.union1d(np.flatnonzero(sim.model.held), rails)
    y = sim.state.x[supports, 1]
    above = y > 0.5 * (y.min() + y.max())
    pull_y = 0.5 * (reactions[supports[above], 1].sum() - reactions[supports[~above], 1].sum())
    assert pull_y > 0 and np.abs(reactions.sum(axis=0)).max() < 2e-3 * pull_y
    run = cut(knit, config(n_x=6, n_y=6, fx=4.0, resolution=16, bars="sliding", implicit_axial=True,
                           twist=False).dynamics_settings())
    before = run.sim.state.x[rails].copy()
    run.sim.step(3000)
    after = run.sim.state.x[rails]
    assert np.abs(after[:, 1:] - before[:, 1:]).max() < 1e-9 * np.abs(before).max()
    assert np.abs(after[:, 0] - before[:, 0]).max() > 1e-4 * knit.settings.material.diameter / kl_units.LENGTH


def test_the_continuous_edge_reaches_its_target_and_its_clips_hold_the_pull_while_they_slide_along_y():
    """edge="continuous" (one yarn turning in clips, the experiment's edge) with sliding bars, tiled from the
    periodised stitch and stretched to f_x 4 at mu 0: the knit reaches its target, no edge is strained 1 %, and the pull the right side's
    clips and yarn end carry balances the left side's to 2 % (measured 0.7 %, the relaxation's residual), and
    each clip carries two courses' pull. Laddered, the clips keep
    their x and z to round-off while they slide along y."""
    cfg = config(n_x=6, n_y=6, fx=4.0, resolution=16, edge="continuous", bars="sliding")
    knit = stretch(cfg.stretch_settings())
    assert knit.fx_within_tolerance
    k, model = knit.knit, knit.knit.rods.model
    clips = model.rail_node[np.abs(model.rail_axis[:, 1]) == 1.0]
    assert clips.size == 5
    # tiled course by course (the odd ones backwards) and the turning loops laid between: no edge pulled apart
    x, a, b = k.rods.state.x, model.edge_a, model.edge_b
    assert np.abs(np.linalg.norm(x[b] - x[a], axis=1) / model.rest_length - 1.0).max() < 1e-2
    reactions = Simulation(k.rods.copy(), contact=stretch_contact(knit.settings)).reaction_forces_N()
    right = (reactions[k.right_end, 0] * k.right_share).sum()
    left = (reactions[k.left_end, 0] * k.left_share).sum()
    assert right > 0 and abs(right + left) < 0.02 * right
    # a clip holds two courses: on average 2 f_x f0 (measured 0.1 % off; one by one 13 % at most)
    assert np.abs(reactions[clips, 0]).mean() == pytest.approx(2 * knit.fx_ini * knit.settings.material.f0, rel=0.05)
    run = cut(knit, config(n_x=6, n_y=6, fx=4.0, resolution=16, edge="continuous", bars="sliding").dynamics_settings())
    before = run.sim.state.x[clips].copy()
    run.sim.step(3000)
    after = run.sim.state.x[clips]
    assert np.abs(after[:, [0, 2]] - before[:, [0, 2]]).max() < 1e-9 * np.abs(before).max()
    assert np.abs(after[:, 1] - before[:, 1]).max() > 1e-4 * knit.settings.material.diameter / kl_units.LENGTH


def test_the_clips_friction_comes_on_at_the_cut_and_keeps_every_reaction_in_its_coulomb_cone():
    """clip_friction (the continuous edge's clips and the sliding bars' on their bars): the stretch runs them
    frictionless, the cut switches them on with mu; while the ladder runs, every rail's reaction along its bar
    stays within mu times its reaction across (to 1e-9), and some clip reaches that bound (it slides)."""
    mu = 0.3
    cfg = config(n_x=6, n_y=6, fx=4.0, resolution=16, edge="continuous", bars="sliding", clip_friction=mu)
    knit = stretch(cfg.stretch_settings())
    assert not np.any(knit.knit.rods.model.rail_friction)
    run = cut(knit, cfg.dynamics_settings())
    model = run.sim.model
    assert np.all(model.rail_friction == mu) and model.rail_friction.size == model.rail_node.size > 0
    ratios = []
    for _ in range(30):
        run.sim.step(100)
        r = run.sim.reaction_forces_N()[model.rail_node]
        along = np.einsum("ij,ij->i", r, model.rail_axis)
        across = np.linalg.norm(r - along[:, None] * model.rail_axis, axis=1)
        assert np.all(np.abs(along) <= mu * across * (1 + 1e-9) + 1e-15)
        ratios.append(np.max(np.abs(along) / np.maximum(across, 1e-300)))
    assert max(ratios) == pytest.approx(mu, rel=1e-6)


def test_clip_friction_needs_clips():
    with pytest.raises(ValueError, match="clip_friction: this knit has no clips"):
        config(fx=4.0, clip_friction=0.3)
    assert config(fx=4.0, bars="sliding", clip_friction=0.3).dynamics_settings().clip_friction == 0.3


def test_two_knit_seeds_give_two_knits_of_the_same_stretch_and_the_same_seed_the_same_knit():
    """An ensemble's members differ in their stretched knits: each free node displaced across its yarn, KNIT_NOISE d
    rms from its seed (segments keep their length to second order); the held nodes stay; the same seed is the
    same knit to the bit."""
    base = CutConfig(n_x=4, n_y=4, preset="fast", resolution=16, lx=0.36).stretch_settings()
    plain = stretch(base)
    knits = [stretch(dataclasses.replace(base, knit_seed=seed)) for seed in (0, 1, 1)]
    moved = [k.knit.rods.state.x - plain.knit.rods.state.x for k in knits]
    d = base.material.diameter / kl_units.LENGTH
    held = plain.knit.rods.model.held
    for m in moved:
        rms = np.sqrt(np.mean(m[~held] ** 2) * 3)
        assert 0.5 * KNIT_NOISE * d < rms < 1.5 * KNIT_NOISE * d and not m[held].any()
    assert not np.array_equal(moved[0], moved[1]) and np.array_equal(moved[1], moved[2])
    assert knits[0].fx_ini != knits[1].fx_ini and abs(knits[0].fx_ini / plain.fx_ini - 1) < 0.02
