"""The stop rules and recorders of knitlad.fabric.observers."""

from __future__ import annotations

import numpy as np
import pytest

from knitlad.fabric.observers import TOP_ROWS_HELD, Arrested, CellReading, EdgeReached


def reading(undone: np.ndarray, ever: np.ndarray | None = None) -> CellReading:
    """A reading of ``undone`` cells now (and ``ever``, by default the same)."""
    return CellReading(undone.copy(), undone.copy() if ever is None else ever, np.zeros(undone.shape))


def test_the_top_edge_is_the_row_below_the_held_course():
    """Rows of cells run from course 0 to the top free course; the cell of the top free course
    lies under the held top course and cannot ladder, so the row below it is the top edge."""
    undone = np.zeros((16, 16), dtype=bool)
    rule = EdgeReached()
    undone[5:15 - TOP_ROWS_HELD, 7] = True
    assert rule.check(0.0, reading(undone)) is None
    undone[15 - TOP_ROWS_HELD, 7] = True
    assert rule.check(0.0, reading(undone)) == "ladder reached an edge course"
    bottom = np.zeros((16, 16), dtype=bool)
    bottom[0, 3] = True
    assert rule.check(0.0, reading(bottom)) is not None


def test_arrest_is_declared_after_the_window_without_change():
    rule = Arrested(arrest_s=1e-3)
    undone = np.zeros((4, 4), dtype=bool)
    assert rule.check(0.0, reading(undone)) is None
    undone[1, 1] = True
    assert rule.check(0.5e-3, reading(undone)) is None
    assert rule.check(1.4e-3, reading(undone)) is None
    assert rule.check(1.5e-3, reading(undone)) is not None


def test_a_cell_that_knits_itself_again_or_crosses_the_threshold_again_keeps_the_run_going():
    """The arrest is judged on the photograph: a cell hooked again changes it as a new one does (the count
    read 14, 16, 14, 12 over a run's last 0.3 ms while every latched cell stayed set)."""
    rule = Arrested(arrest_s=1e-3, pause_factor=0.0)
    undone, ever = np.zeros((4, 4), dtype=bool), np.zeros((4, 4), dtype=bool)
    undone[1, 1] = ever[1, 1] = True
    assert rule.check(0.0, reading(undone, ever)) is None
    undone[1, 1] = False  # hooked again: the latched map is unchanged, the photograph is not
    assert rule.check(0.9e-3, reading(undone, ever)) is None
    assert rule.check(1.5e-3, reading(undone, ever)) is None  # 0.6 ms since the change
    undone[1, 1], undone[2, 2] = True, True  # ... and a swap of two cells, at the same count
    undone[1, 1] = False
    assert rule.check(1.8e-3, reading(undone, ever)) is None
    assert rule.check(2.9e-3, reading(undone, ever)) is not None


def test_a_pair_that_separated_is_not_read_as_sliding():
    """Stale sliding flags of separated pairs marked 29 % of the nodes as sliding where 13 % were (16 x 16)."""
    from types import SimpleNamespace

    import numpy as np

    from knitlad.engine.kernels.contact import OVERLAP, PAIR_RESULTS, SLIDING as SLIDING_COLUMN
    from knitlad.fabric.observers import FREE, SLIDING, TOUCHING, node_contact_state

    results = np.zeros((3, PAIR_RESULTS))
    results[0, OVERLAP], results[0, SLIDING_COLUMN] = 1e-3, 1.0  # touching and sliding
    results[1, OVERLAP], results[1, SLIDING_COLUMN] = 0.0, 1.0  # separated, a stale flag
    results[2, OVERLAP] = 1e-3  # touching, sticking
    contacts = SimpleNamespace(n_pairs=np.array([3]), pair_results=results,
                               pairs=np.array([[0, 1], [2, 3], [4, 5]]))
    model = SimpleNamespace(n_nodes=12, edge_a=np.arange(0, 12, 2), edge_b=np.arange(1, 12, 2))
    state = node_contact_state(SimpleNamespace(contacts=contacts, model=model))
    assert list(state[[0, 2, 4, 6, 8, 10]]) == [SLIDING, SLIDING, FREE, FREE, TOUCHING, TOUCHING]


def test_the_progress_of_a_ladder_is_how_far_its_front_has_gone():
    """The stage bar measured simulated time against max_time_ms and froze at a few per cent, since
    ladders stop at an edge course long before."""
    import numpy as np

    from knitlad.fabric.observers import FrontRecorder

    n_y, cut = 10, 5
    fronts = FrontRecorder((2, 3), cut)
    undone = np.zeros((n_y, 6), dtype=bool)
    fronts.observe(0.0, None, reading(undone))
    assert fronts.reach(n_y) == 0.0
    undone[cut:cut + 3, 3] = True  # three cells up the column beside the cut
    fronts.observe(1e-4, None, reading(undone))
    assert 0.4 < fronts.reach(n_y) < 1.0
    undone[cut:, 3] = True  # up to the last free course: the ladder is at the edge
    fronts.observe(2e-4, None, reading(undone))
    assert fronts.reach(n_y) == 1.0


def test_a_scene_of_one_s_own_writes_a_trajectory_that_reads_back_with_units_and_an_xdmf(tmp_path):
    """The rod demo's cantilever let go: frames as recorded, units, checksums, the fields and the XDMF."""
    import h5py

    import knitlad as kl
    from knitlad.io.hdf5 import verify_datasets

    s = np.linspace(0.0, 0.02, 21)
    scene = kl.Scene(kl.NYLON)
    rod = scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]), start=np.column_stack([s, 1e-3 * (s / 0.02) ** 2, 0 * s]))
    scene.hold(rod, [0, 1])
    sim = kl.Simulation(scene.build())
    recorder = kl.TrajectoryRecorder()
    sim.run(2e-3, observe=recorder, observe_every_s=5e-4)
    path = kl.write_trajectory(tmp_path / "mine.h5", recorder)
    verify_datasets(path)
    with h5py.File(path) as f:
        n = len(recorder.times)
        assert n >= 4 and f["frames/positions"].shape == (n, 21, 3) and f["frames/positions"].attrs["unit"] == "m"
        np.testing.assert_allclose(f["frames/positions"][-1], sim.positions_m(), atol=1e-9)
        assert f["frames/time"][-1] == pytest.approx(sim.time_s) and np.all(np.diff(f["frames/time"][()]) > 0)
        assert f["fields/curvature"].shape == (n, 21) and f.attrs["scale_B_N_m2"] == kl.NYLON.bending_stiffness
    assert "/frames/positions" in (tmp_path / "mine.xdmf").read_text()
    with pytest.raises(ValueError, match="no frame recorded"):
        kl.write_trajectory(tmp_path / "none.h5", kl.TrajectoryRecorder())


def test_a_stick_slip_front_is_not_taken_as_arrested_during_its_pauses():
    """A front undoing a cell every 1.5 ms, then after a pause of 4 ms (longer than the 2 ms window, shorter
    than three of its pauses so far), runs on; once still for three times its longest pause it is arrested."""
    rule = Arrested(arrest_s=2e-3)
    undone = np.zeros((8, 4), dtype=bool)
    changes = [1.0e-3, 2.5e-3, 4.0e-3, 5.5e-3, 9.5e-3, 11.0e-3]
    fired = None
    for t in np.round(np.arange(0.0, 40e-3, 1e-4), 7):
        undone.flat[:sum(c <= t + 1e-9 for c in changes)] = True
        if (reason := rule.check(t, reading(undone))) is not None:
            fired = (t, reason)
            break
    assert rule.longest_pause == pytest.approx(4e-3)
    assert fired is not None and fired[0] == pytest.approx(11e-3 + 3 * 4e-3, abs=1.5e-4)
    assert "12.0 ms" in fired[1]
