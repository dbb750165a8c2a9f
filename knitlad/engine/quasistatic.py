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

Jumps or ramps. With friction the answer depends on the path, and a jump of the supports
(``move_held`` then ``settle`` or ``relax``) is a path of its own: the knit rings after each jump and
its contacts slip further than under a steady pull. :meth:`QuasiStatics.ramp_held` moves the supports
at a steady speed under the same damping instead. On a 4 x 4 knit at mu = 0.4 (a course pulled out by
0.2 mm, ``tests/engine/test_quasistatic.py``) ramps at 0.01, 0.02 and 0.04 m/s and alpha 1e4 or 2e4 /s
give one pull to 1e-4; jumps of 20 um give 15 % less, of 2.5 um 2 % less (docs/quasistatic.md).
"""

from __future__ import annotations

import math

import numpy as np

from knitlad.engine import units
from knitlad.engine.timestep import step_count


class QuasiStatics:
    """Static equilibrium reached by damped dynamics (a mixin of :class:`~knitlad.engine.simulation.Simulation`)."""

    def residual_force_N(self) -> float:
        """The largest force on a free node at the last evaluation, the global drag excluded [N]."""
        m, free = self.model, ~self.model.held
        if not np.any(free):
            return 0.0
        f = self.work.force[free] + self.drag * m.mass[free, None] * self.state.v[free]
        return float(np.sqrt(np.max(np.sum(f * f, axis=1))) * units.FORCE)

    def ramp_held(self, nodes, by_m, speed_m_s: float, damping_per_s: float, rails=(), rails_by_m=None) -> dict:
        """Move held ``nodes`` by ``by_m`` [m] (one 3-vector, or one per node) at a steady speed of at most
        ``speed_m_s`` under the damping ``damping_per_s`` = alpha [1/s] (module docstring), then hold them
        still; the drag in force before is restored. They land on ``by_m`` to round-off (the speed is lowered to a
        whole number of steps). Read forces after :meth:`settle`, or while moving with the bias alpha M V.
        ``rails``: nodes on rails (clips) carried with the supports by ``rails_by_m`` across their rails (the
        part along a rail is left out: along it the clip slides), landing there to round-off.

        Returns ``time_s`` (simulated) and ``steps``.
        """
        idx = self._nodes(nodes)
        if not self.model.held[idx].all():
            raise ValueError("ramp_held moves held nodes only: hold() them first")
        if not (speed_m_s > 0 and math.isfinite(speed_m_s) and damping_per_s > 0):
            raise ValueError("speed_m_s and damping_per_s must be positive")
        by = np.broadcast_to(np.asarray(by_m, dtype=float), (idx.size, 3))
        carried, axis, across = self._rails_across(rails, rails_by_m)
        if not (np.all(np.isfinite(by)) and np.all(np.isfinite(across))):
            raise ValueError("by_m or rails_by_m contains NaN or infinity")
        reach = float(np.max(np.linalg.norm(np.concatenate([by, across]), axis=1), initial=0.0))
        steps = max(1, step_count("by_m / speed_m_s", math.ceil(reach / speed_m_s / self.dt_s)))
        before = self.drag / units.TIME
        self.set_drag(damping_per_s)
        v = self.state.v
        try:
            self.hold(idx, velocity_m_s=by / (steps * self.dt_s))
            # a rail moves with its node's velocity across it: the rail takes every force across, so it stays
            v[carried] += across / (steps * self.dt_s) / units.VELOCITY
            self.step(steps)
        finally:
            self.hold(idx)
            v[carried] = np.sum(v[carried] * axis, axis=1)[:, None] * axis
            self.set_drag(before)
        return {"time_s": steps * self.dt_s, "steps": steps}

    def _rails_across(self, rails, rails_by_m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rail nodes, their rails' axes, their move [m] across their rails) of :meth:`ramp_held`."""
        m = self.model
        carried = self._nodes(rails) if len(rails) else np.zeros(0, dtype=np.int64)
        row = np.full(m.n_nodes, -1, dtype=np.int64)
        row[m.rail_node] = np.arange(m.rail_node.size)
        if np.any(row[carried] < 0):
            raise ValueError("rails: ramp_held carries nodes on rails only: slide() them first")
        axis = m.rail_axis[row[carried]]
        by = np.broadcast_to(np.asarray(0.0 if rails_by_m is None else rails_by_m, dtype=float), (carried.size, 3))
        return carried, axis, by - np.sum(by * axis, axis=1)[:, None] * axis

    def settle(self, force_tol_N: float, max_time_s: float, damping_per_s: float,
               check_every_s: float | None = None) -> dict:
        """Run damped dynamics (``damping_per_s`` = alpha [1/s], module docstring) until
        :meth:`residual_force_N` is at most ``force_tol_N``, checked every ``check_every_s`` (default:
        1/alpha; at least one such interval is run), or until ``max_time_s`` of simulated time. The drag
        in force before is restored.

        Returns ``converged``, ``time_s`` (simulated) and ``max_force_N`` (the residual at the end).
        """
        for name, value in (("force_tol_N", force_tol_N), ("max_time_s", max_time_s), ("damping_per_s", damping_per_s)):
            if not value > 0:
                raise ValueError(f"{name} must be positive, got {value!r}")
        if not math.isfinite(damping_per_s):
            raise ValueError(f"damping_per_s must be finite, got {damping_per_s!r}: an infinite drag holds every node")
        step_count("max_time_s", max_time_s / self.dt_s)  # infinity, or a settle that would not end
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
