"""knitlad.fabric.stretching against a box whose mechanics are known: a linear knit that creeps to equilibrium."""

from __future__ import annotations

import pytest

from knitlad.fabric.stretching import OutOfReach, force_control, relax_to_steady_tension, stretch_to


class CreepingBox:
    """f_x = k (l_x - free) at equilibrium; each relaxation round closes a fraction ``rate`` of the gap
    (the creep of a real knit after an increment: exponential in rounds)."""

    def __init__(self, k=100.0, free=0.30, rate=0.3, lx=0.30, ly=0.25):
        self.k, self.free, self.rate = k, free, rate
        self.lx, self.ly = lx, ly
        self.fx = self.equilibrium()
        self.deformed, self.rounds = [], 0

    def equilibrium(self) -> float:
        return self.k * (self.lx - self.free)

    def deform(self, lx, ly):
        jump = self.k * (lx - self.lx)
        self.lx, self.ly = lx, ly
        self.fx += 0.5 * jump  # right after an increment the reading lags the relaxed tension
        self.deformed.append((lx, ly))

    def relax(self):
        self.rounds += 1
        self.fx += self.rate * (self.equilibrium() - self.fx)
        return {"converged": True}

    def tension(self):
        return self.fx


def test_stretch_to_takes_increments_no_larger_than_asked_and_ends_on_the_target():
    box, seen = CreepingBox(), []
    stretch_to(box, 0.37, 0.28, 0.01, progress=seen.append)
    assert len(box.deformed) == 7  # max(0.07, 0.03) / 0.01
    assert box.deformed[-1] == pytest.approx((0.37, 0.28))
    steps = [b[0] - a[0] for a, b in zip([(0.30, 0.25)] + box.deformed, box.deformed)]
    assert max(steps) <= 0.01 + 1e-12 and seen[-1] == 1.0 and box.rounds == 7


def test_the_steady_tension_is_the_creep_s_asymptote_not_the_first_small_change():
    """Exponential creep (15 % of the gap per round): Aitken's extrapolation of three readings is exact, so
    the reading returned is near the equilibrium, not the lagging one right after the increment."""
    box = CreepingBox(rate=0.15)
    box.deform(0.40, 0.25)  # equilibrium 10, reading 5 right after the increment
    fx = relax_to_steady_tension(box, rtol=0.005)
    assert fx == pytest.approx(10.0, rel=0.02) and box.rounds >= 3


def test_force_control_brackets_and_hits_the_target_and_says_when_it_is_out_of_reach():
    box = CreepingBox()
    fx, within = force_control(box, 7.0, 0.02, 0.01, lx_floor=0.25)
    assert within and fx == pytest.approx(7.0, rel=0.02) and box.lx == pytest.approx(0.37, abs=0.003)
    with pytest.raises(OutOfReach, match="out of reach"):
        force_control(CreepingBox(), 70.0, 0.02, 0.01, lx_floor=0.25, lx_ceiling=0.5)
