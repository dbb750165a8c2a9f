"""The one run loop of every experiment: advance by an interval, read, observe, stop at the first rule that fires.

An experiment gives :func:`run_until` its ``observe(t) -> reading`` (the reading is what its observers are shown
and its rules check), its observers, each with ``observe(t, run, reading)`` (``run``: the running experiment,
whose ``sim`` is the simulation; one signature for every experiment), and its stop rules, each with
``check(t, reading) -> str | None`` (the reason it fires, or None). What a reading holds is the experiment's: the laddering's undone cells
(:func:`knitlad.experiments.laddering.propagate`), whether a single loop is still held (:class:`knitlad.fabric.observers.LetGo`,
:mod:`knitlad.experiments.loop_model`, :mod:`knitlad.experiments.periodic_loop`). ``t`` is the time since the loop began [s].
"""

from __future__ import annotations

from typing import Any, Callable, Protocol, Sequence


class StopRule(Protocol):
    def check(self, t: float, reading: Any) -> str | None: ...


class Observer(Protocol):
    def observe(self, t: float, run: Any, reading: Any) -> None: ...


def run_until(sim, steps_per_reading: int, observe: Callable[[float], Any], stop_rules: Sequence[StopRule],
              observers: Sequence[Observer] = (), run: Any = None) -> tuple[float, StopRule, str]:
    """Step ``sim`` ``steps_per_reading`` at a time; after each, ``reading = observe(t)``, every observer in
    order sees ``(t, run, reading)`` and every rule in order checks the reading. Returns (t, the rule that
    fired, its reason). Give a time limit among the rules."""
    t_start = sim.time_s
    while True:
        sim.step(steps_per_reading)
        t = sim.time_s - t_start
        reading = observe(t)
        for observer in observers:
            observer.observe(t, run, reading)
        for rule in stop_rules:
            reason = rule.check(t, reading)
            if reason:
                return t, rule, reason
