"""Forces and torques equal minus the gradient of the energy (central differences)."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine.contact import make_contacts
from knitlad.engine.kernels.dissipation import no_damping
from knitlad.engine.kernels.integrate import (AXIAL_EXPLICIT, DASHPOTS_HALF_STEP, TWIST_FRAMED, TWIST_OFF, TWIST_STRAIGHT,
                                              compute_forces, potential_energy)
from knitlad.engine.obstacles import obstacle_state
from knitlad.engine.state import Workspace


def wiggly_rod(n: int = 9, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    h = 0.4e-3
    pts = np.zeros((n, 3))
    pts[:, 0] = np.arange(n) * h
    pts[:, 1:] = rng.normal(scale=0.25 * h, size=(n, 2))
    return pts


def energy(rods: kl.Rods, twist: int) -> float:
    r = rods.copy()
    return float(sum(potential_energy(r.model, r.state, Workspace.for_model(r.model), make_contacts(r, None), twist,
                                      False)))


def forces(rods: kl.Rods, twist: int) -> Workspace:
    """Forces and torques of ``rods`` (no contact) into a new workspace."""
    w = Workspace.for_model(rods.model)
    compute_forces(rods.model, rods.state, w, make_contacts(rods, None), twist, False, no_damping(), 1.0,
                   AXIAL_EXPLICIT, DASHPOTS_HALF_STEP, obstacle_state([], rods.model.n_nodes))
    return w


def check_gradient(rods: kl.Rods, twist: int, rel_tol: float) -> None:
    w = forces(rods.copy(), twist)
    eps = 1e-7  # mm
    fd = np.zeros_like(rods.state.x)
    for i in range(rods.state.x.shape[0]):
        for c in range(3):
            plus, minus = rods.copy(), rods.copy()
            plus.state.x[i, c] += eps
            minus.state.x[i, c] -= eps
            fd[i, c] = -(energy(plus, twist) - energy(minus, twist)) / (2 * eps)
    scale = np.max(np.abs(fd))
    assert np.max(np.abs(w.force - fd)) < rel_tol * scale, np.max(np.abs(w.force - fd)) / scale
    if twist:
        fd_t = np.zeros_like(rods.state.theta)
        for k in range(rods.state.theta.shape[0]):
            plus, minus = rods.copy(), rods.copy()
            plus.state.theta[k] += 1e-6
            minus.state.theta[k] -= 1e-6
            fd_t[k] = -(energy(plus, twist) - energy(minus, twist)) / 2e-6
        scale_t = np.max(np.abs(fd_t))
        assert np.max(np.abs(w.torque - fd_t)) < rel_tol * scale_t


def test_isotropic_bending_and_stretching_forces_are_minus_the_energy_gradient():
    pts = wiggly_rod()
    scene = kl.Scene()
    scene.add_yarn(pts)
    rods = scene.build(twist=False, stretch_damping_ratio=0.0)
    rods.state.x[:] *= 1.003  # some stretch too
    check_gradient(rods, twist=TWIST_OFF, rel_tol=1e-5)


@pytest.mark.parametrize("closed", [False, True])
def test_framed_bending_with_natural_curvature_and_twist_are_minus_the_energy_gradient(closed):
    pts = wiggly_rod(seed=1)
    scene = kl.Scene()
    scene.add_yarn(pts, natural_curvature="rest", closed=closed)
    rods = scene.build(twist=True, stretch_damping_ratio=0.0)
    rng = np.random.default_rng(2)
    rods.state.x[:] += rng.normal(scale=0.05e-3 / kl.units.LENGTH, size=rods.state.x.shape)
    rods.state.theta[:] = rng.normal(scale=0.3, size=rods.state.theta.shape)
    # bring the frames to the perturbed shape first: the FD energies transport from here
    forces(rods, TWIST_FRAMED)
    check_gradient(rods, twist=TWIST_FRAMED, rel_tol=1e-5)


@pytest.mark.parametrize("closed", [False, True])
def test_isotropic_bending_and_twisting_without_frames_are_minus_the_energy_gradient(closed):
    """TWIST_STRAIGHT: the reference twist by holonomy, so its gradient is that of the frames' (DER08 sec. 7)."""
    pts = wiggly_rod(seed=3)
    scene = kl.Scene()
    scene.add_yarn(pts, closed=closed)
    rods = scene.build(twist=True, stretch_damping_ratio=0.0)
    rng = np.random.default_rng(4)
    rods.state.x[:] += rng.normal(scale=0.05e-3 / kl.units.LENGTH, size=rods.state.x.shape)
    rods.state.theta[:] = rng.normal(scale=1.0, size=rods.state.theta.shape)
    forces(rods, TWIST_STRAIGHT)
    r = rods.copy()
    _, bending, twisting, _, _ = potential_energy(r.model, r.state, Workspace.for_model(r.model), make_contacts(r, None),
                                                  TWIST_STRAIGHT, False)
    assert twisting > 0.05 * bending  # the twist is loaded, not a bystander
    check_gradient(rods, twist=TWIST_STRAIGHT, rel_tol=1e-5)
