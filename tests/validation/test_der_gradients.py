"""Forces and torques equal minus the gradient of the energy (central differences)."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.contact import make_contacts
from knitlad.kernels.integrate import compute_forces, potential_energy
from knitlad.state import Workspace


def wiggly_rod(n: int = 9, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    h = 0.4e-3
    pts = np.zeros((n, 3))
    pts[:, 0] = np.arange(n) * h
    pts[:, 1:] = rng.normal(scale=0.25 * h, size=(n, 2))
    return pts


def energy(state: kl.RodState, twist: bool) -> float:
    s = state.copy()
    return float(sum(potential_energy(s, Workspace.for_state(s), make_contacts(s, None), twist)))


def check_gradient(state: kl.RodState, twist: bool, rel_tol: float) -> None:
    s = state.copy()
    w = Workspace.for_state(s)
    compute_forces(s, w, make_contacts(s, None), twist, 0.0, 1.0)
    eps = 1e-7  # mm
    fd = np.zeros_like(state.x)
    for i in range(state.x.shape[0]):
        for c in range(3):
            plus, minus = state.copy(), state.copy()
            plus.x[i, c] += eps
            minus.x[i, c] -= eps
            fd[i, c] = -(energy(plus, twist) - energy(minus, twist)) / (2 * eps)
    scale = np.max(np.abs(fd))
    assert np.max(np.abs(w.force - fd)) < rel_tol * scale, np.max(np.abs(w.force - fd)) / scale
    if twist:
        fd_t = np.zeros_like(state.theta)
        for k in range(state.theta.shape[0]):
            plus, minus = state.copy(), state.copy()
            plus.theta[k] += 1e-6
            minus.theta[k] -= 1e-6
            fd_t[k] = -(energy(plus, twist) - energy(minus, twist)) / 2e-6
        scale_t = np.max(np.abs(fd_t))
        assert np.max(np.abs(w.torque - fd_t)) < rel_tol * scale_t


def test_isotropic_bending_and_stretching_forces_are_minus_the_energy_gradient():
    pts = wiggly_rod()
    scene = kl.Scene()
    scene.add_yarn(pts)
    state = scene.build(twist=False, stretch_damping_ratio=0.0)
    state.x[:] *= 1.003  # some stretch too
    check_gradient(state, twist=False, rel_tol=1e-5)


@pytest.mark.parametrize("closed", [False, True])
def test_framed_bending_with_natural_curvature_and_twist_are_minus_the_energy_gradient(closed):
    pts = wiggly_rod(seed=1)
    scene = kl.Scene()
    scene.add_yarn(pts, natural_curvature="rest", closed=closed)
    state = scene.build(twist=True, stretch_damping_ratio=0.0)
    rng = np.random.default_rng(2)
    state.x[:] += rng.normal(scale=0.05e-3 / kl.units.LENGTH, size=state.x.shape)
    state.theta[:] = rng.normal(scale=0.3, size=state.theta.shape)
    # bring the frames to the perturbed shape first: the FD energies transport from here
    compute_forces(state, Workspace.for_state(state), make_contacts(state, None), True, 0.0, 1.0)
    check_gradient(state, twist=True, rel_tol=1e-5)
