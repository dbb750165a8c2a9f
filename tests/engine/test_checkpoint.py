"""A simulation's checkpoint (knitlad/engine/checkpoint.py): restored into a simulation built the same way, the run
continues to the bit, friction history, viscoelastic branches, obstacles and ledger included."""

from __future__ import annotations

import numpy as np
import pytest

import knitlad as kl
from knitlad.io.hdf5 import read_arrays, write_arrays


def _crossed_yarns_pressed(points: int = 33) -> kl.Simulation:
    """Two crossed yarns, one pulled sideways by its held ends, under a plate coming down, with friction,
    the yarn's damping and a drag: every kind of history a run keeps."""
    scene = kl.Scene(kl.NYLON)
    s = np.linspace(-4e-3, 4e-3, points)
    a = scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]))
    b = scene.add_yarn(np.column_stack([0 * s, s, 0 * s + 0.14e-3]))
    scene.hold(a, [0, points - 1])
    scene.hold(b, [0, points - 1], velocity=(0.2, 0.0, 0.0))
    plate = kl.Plane(stiffness=50.0, mu=0.3, point_m=(0, 0, 0.215e-3), normal=(0, 0, -1), velocity_m_s=(0, 0, -0.1))
    return kl.Simulation(scene.build(), contact=kl.ContactModel.for_knit(kl.NYLON, mu=0.4), obstacles=[plate],
                         material_damping=kl.MaterialDamping(0.03), drag_per_s=200.0)


def test_a_run_restored_from_its_checkpoint_file_continues_to_the_bit(tmp_path):
    whole = _crossed_yarns_pressed()
    whole.step(3000)
    whole.release(whole.nodes_of(1, [0]))  # the model changes mid-run too
    whole.step(3000)
    assert whole.contact_stats().touching > 0 and whole.contact_stats().sliding > 0  # friction history to carry

    first = _crossed_yarns_pressed()
    first.step(3000)
    first.release(first.nodes_of(1, [0]))
    path = write_arrays(tmp_path / "checkpoint.h5", first.checkpoint())
    arrays, _ = read_arrays(path)
    second = _crossed_yarns_pressed()
    second.restore(arrays)
    second.step(3000)
    assert np.array_equal(second.state.x, whole.state.x) and np.array_equal(second.state.v, whole.state.v)
    assert second.time_s == whole.time_s and second.steps == whole.steps
    # the state to the bit; the ledger's sums to rounding: they add per-block slices, and the blocks follow the
    # threads the step planner picks from its timings (a cold compile times differently), so their grouping may differ
    assert second.ledger().as_dict() == pytest.approx(whole.ledger().as_dict(), rel=1e-12, abs=1e-30)
    assert np.array_equal(second.obstacle_reactions_N(), whole.obstacle_reactions_N())


def test_a_checkpoint_of_another_scene_is_refused_naming_the_array():
    first = _crossed_yarns_pressed(points=33)
    other = _crossed_yarns_pressed(points=41)
    with pytest.raises(ValueError, match="state/x has shape"):
        other.restore(first.checkpoint())
