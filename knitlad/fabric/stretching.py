"""The affine stretch and force control of a periodic structure, shared by the knit and the periodised stitch.

A *box* is anything with a current stretch (``lx``, ``ly`` in l/l0) that can be
deformed affinely, relaxed one round, and read for its tension per thread f_x
(:class:`Box`). With mu = 0 the relaxed state is history-free, and an affine
increment leaves the yarn in the bulk only a local rearrangement to make (yarn
drawn from its own loop) instead of sliding from the held ends across the fabric.
"""

from __future__ import annotations

import math
from typing import Callable, Protocol


class Box(Protocol):
    lx: float  # current stretch l_x/l0
    ly: float  # current stretch l_y/l0

    def deform(self, lx: float, ly: float) -> None:
        """Map every node affinely to the box (lx, ly) [l/l0]."""

    def relax(self) -> dict:
        """One round of relaxation at the current box (the report of Simulation.relax)."""

    def tension(self) -> float:
        """Tension per thread f_x at the current positions."""


Progress = Callable[[float], None]  # fraction done


class OutOfReach(RuntimeError):
    """Force control cannot reach its target tension by stretching."""


def stretch_to(box: Box, lx: float, ly: float, increment: float, progress: Progress | None = None,
               min_increments: int = 1) -> None:
    """Affine increments of at most ``increment`` (l/l0) from the current box to (lx, ly), each relaxed."""
    span = max(abs(lx - box.lx), abs(ly - box.ly))
    n = max(min_increments, int(math.ceil(span / increment - 1e-9)))  # 1e-9: no extra step from round-off
    lx0, ly0 = box.lx, box.ly
    for k in range(1, n + 1):
        box.deform(lx0 + (lx - lx0) * k / n, ly0 + (ly - ly0) * k / n)
        box.relax()
        if progress is not None:
            progress(k / n)


def relax_to_steady_tension(box: Box, rtol: float = 0.005, max_rounds: int = 60) -> float:
    """Relax in rounds until f_x is within ``rtol`` of its extrapolated asymptote; returns f_x.

    After a stretch f_x creeps toward equilibrium with a time constant of a few
    rounds (42 x 42 with tail ends: from 2.1 to 5.0 over 14 rounds at l_x = 0.38 l0;
    clamped ends: 2.36 to 2.28 over 30 rounds at 0.355), so a small change between
    two rounds does not mean convergence. The asymptote is estimated by Aitken's
    delta-squared extrapolation of the last three readings.
    """
    readings = [box.tension()]
    for _ in range(max_rounds):
        box.relax()
        readings.append(box.tension())
        if len(readings) >= 3:
            older, old, new = readings[-3:]
            curvature = new - 2 * old + older
            limit = new - (new - old) ** 2 / curvature if abs(curvature) > 1e-12 else new
            if abs(new - limit) <= rtol * max(abs(limit), 0.1) and abs(new - old) <= 4 * rtol * max(abs(new), 0.1):
                return new
    return readings[-1]


def force_control(box: Box, target: float, tol: float, increment: float, lx_floor: float,
                  lx_ceiling: float = 0.95, progress: Progress | None = None) -> tuple[float, bool]:
    """Stretch along x at fixed l_y until the relaxed f_x matches ``target`` within ``tol``
    (relative); returns (f_x, whether it is within the tolerance).

    A reading taken right after an increment lags the relaxed tension (42 x 42 with
    tail ends at l_x = 0.38 l0: 1.9 read, 5.0 relaxed), so only steady (extrapolated)
    readings decide near the target: cheap increments while the reading is below a
    quarter of the target, then a steady reading after every increment until the
    target is bracketed, then interpolation on steady readings. ``lx_floor``: the
    narrowest box to step back to; ``lx_ceiling``: the widest to try.
    """
    report = progress or (lambda fraction: None)
    ly = box.ly

    def step_out() -> None:
        if box.lx + increment >= lx_ceiling:
            raise OutOfReach(f"l_x/l0 reached {box.lx:.3f}: the target f_x = {target} is out of reach")
        stretch_to(box, box.lx + increment, ly, increment)

    box.relax()
    fx = box.tension()
    while fx < 0.25 * target:
        step_out()
        fx = box.tension()
        report(0.5 * max(fx, 0.0) / target)
    a, fa = box.lx, relax_to_steady_tension(box)
    if fa > (1 + tol) * target:
        # the cheap phase overshot: bracket from below by stepping back (not below the floor)
        b, fb = a, fa
        a = max(lx_floor, box.lx - 4 * increment)
        if a < box.lx - 1e-9:
            stretch_to(box, a, ly, increment)
            fa = relax_to_steady_tension(box)
        if fa > (1 + tol) * target:
            raise OutOfReach(f"at l_x/l0 = {a:.3f} the relaxed knit already carries f_x = {fa:.2f} > {target}: "
                             "use position control (--lx) for this tension")
    else:
        b, fb = a, fa
        while fb < (1 - tol) * target:
            a, fa = b, fb
            step_out()
            b, fb = box.lx, relax_to_steady_tension(box)
            report(0.5 + 0.5 * min(max(fb, 0.0) / target, 1.0))
    fx, lx = (fb, b) if abs(fb - target) <= abs(fa - target) else (fa, a)
    for _ in range(10):
        if abs(fx - target) <= tol * target:
            break
        # interpolate in the bracket (the curve is steep and smooth), bisect if it leaves it
        guess = a + (target - fa) * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        if not min(a, b) < guess < max(a, b):
            guess = 0.5 * (a + b)
        stretch_to(box, guess, ly, increment)
        fx, lx = relax_to_steady_tension(box), guess
        if fx < target:
            a, fa = guess, fx
        else:
            b, fb = guess, fx
    if abs(box.lx - lx) > 1e-12:
        stretch_to(box, lx, ly, increment)
        fx = relax_to_steady_tension(box)
    report(1.0)
    return fx, bool(abs(fx - target) <= tol * target)
