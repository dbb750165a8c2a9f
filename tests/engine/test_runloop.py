"""knitlad/engine/runloop.py: the one run loop, its readings, observers and stop rules."""

from __future__ import annotations

from knitlad.engine.runloop import run_until


class Clock:
    """A stand-in for a simulation: each step advances its time by 1 s."""

    def __init__(self) -> None:
        self.time_s = 0.0

    def step(self, n: int) -> None:
        self.time_s += n


def test_observers_see_each_reading_with_the_run_before_the_rules_check_it():
    events = []

    class Seen:
        def __init__(self, name):
            self.name = name

        def observe(self, t, run, reading):
            events.append((self.name, t, run, reading))

    class StopAtThree:
        def check(self, t, reading):
            events.append(("rule", t, None, reading))
            return "three" if reading == 3 else None

    run = object()
    t, rule, reason = run_until(Clock(), 2, lambda t: int(t) // 2, [StopAtThree()], [Seen("a"), Seen("b")], run)
    assert (t, reason) == (6.0, "three")
    assert [e[0] for e in events] == ["a", "b", "rule"] * 3
    assert all(e[2] is run for e in events if e[0] != "rule")
    assert [e[3] for e in events if e[0] == "a"] == [1, 2, 3]
