"""Each script of examples/ against the known result it shows."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import knitlad as kl

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def example(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


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


@pytest.mark.parametrize("name", ["euler_buckling", "coulomb_slide"])
def test_examples_are_short_and_use_only_the_public_api(name):
    text = (EXAMPLES / f"{name}.py").read_text()
    assert len(text.splitlines()) <= 40
    assert "from knitlad." not in text and "import knitlad." not in text
