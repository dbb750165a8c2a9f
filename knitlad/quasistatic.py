"""Quasi-static equilibrium through the dynamics, friction history included (mixed into Simulation).

FIRE (``Simulation.relax``) zeroes the velocities whenever the power turns negative and steps with
its own time step: with friction, whose spring stretches with the slip per step, it can wander or
stall (the API issue's 200,000-iteration relaxations). :meth:`QuasiStatics.settle` instead runs the
ordinary dynamics, the friction history advancing as in any run, with a mass-proportional (Rayleigh
alpha) damping -alpha m v on the free nodes, until the largest free-node force less that damping
falls below a tolerance, or a time limit passes, and says which.

Damping and its bias. A mode of angular frequency omega gets the damping ratio alpha / (2 omega):
alpha = 2 omega_1 damps the slowest mode critically and the faster ones less (they settle anyway,
faster). At equilibrium the damping force vanishes with the velocity, so a settled reading carries
no bias. During a protocol that keeps moving (a bar pulled at speed V between settles, or without
them), the damping pulls back on the moving mass M with alpha M V: the bias on a measured force,
to be kept small against it (alpha M V << F), or removed by settling before each reading.
"""

from __future__ import annotations

import math

import numpy as np

from knitlad import units


class QuasiStatics:
    """Static equilibrium reached by damped dynamics (a mixin of :class:`~knitlad.simulation.Simulation`)."""

    def residual_force_N(self) -> float:
        """The largest force on a free node at the last evaluation, the global drag excluded [N]."""
        m, free = self.model, ~self.model.held
        if not np.any(free):
            return 0.0
        f = self.work.force[free] + self.drag * m.mass[free, None] * self.state.v[free]
        return float(np.sqrt(np.max(np.sum(f * f, axis=1))) * units.FORCE)

    def settle(self, force_tol_N: float, max_time_s: float, damping_per_s: float,
               check_every_s: float | None = None) -> dict:
        """Run damped dynamics (``damping_per_s`` = alpha [1/s], module docstring) until
        :meth:`residual_force_N` is at most ``force_tol_N``, checked every ``check_every_s`` (default:
        1/alpha; at least one such interval is run), or until ``max_time_s`` of simulated time. The drag
        in force before is restored.

        Returns ``converged``, ``time_s`` (simulated) and ``max_force_N`` (the residual at the end).
        """
        if not (force_tol_N > 0 and max_time_s > 0 and damping_per_s > 0):
            raise ValueError("force_tol_N, max_time_s and damping_per_s must be positive")
        every = check_every_s if check_every_s is not None else 1.0 / damping_per_s
        if not (every > 0 and math.isfinite(every)):
            raise ValueError(f"check_every_s must be positive, got {check_every_s!r}")
        before, t0 = self.drag / units.TIME, self.time_s
        self.set_drag(damping_per_s)
        try:
            # at least one chunk: the forces at hand may predate a move (move_held, move_obstacle keep them)
            while True:
                chunk = min(every, max_time_s - (self.time_s - t0))
                self.step(max(1, int(round(chunk / self.dt_s))))
                residual = self.residual_force_N()
                if residual <= force_tol_N or self.time_s - t0 >= max_time_s * (1 - 1e-9):
                    break
        finally:
            self.set_drag(before)
        return {"converged": residual <= force_tol_N, "time_s": self.time_s - t0, "max_force_N": residual}
