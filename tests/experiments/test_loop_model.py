"""knitlad/experiments/loop_model.py: the single loop takes observers with the run loop's one signature."""

from __future__ import annotations

from knitlad.experiments.config import LoopConfig
from knitlad.experiments.loop_model import LoopReading, LoopRun
from knitlad.fabric.observers import TrajectoryRecorder


def test_an_observer_of_the_ladder_observes_a_single_loop_the_same_way():
    """observe(t, run, reading): the loop's run and its LoopReading; the trajectory recorder of one's own scenes
    records a frame at every reading."""
    seen = []

    class Seen:
        def observe(self, t, run, reading):
            seen.append((t, run, reading))

    run = LoopRun(LoopConfig(fx=4, mu=0.4).settings())
    recorder = TrajectoryRecorder()
    result = run.run(observers=[Seen(), recorder])
    assert result.released and len(seen) > 3
    assert all(r is run and isinstance(reading, LoopReading) for _, r, reading in seen)
    times = [t for t, _, _ in seen]
    assert times == sorted(times) and times[-1] >= result.tau_s
    assert len(recorder.positions) == len(seen) and recorder.positions[0].shape == (run.sim.model.n_nodes, 3)
