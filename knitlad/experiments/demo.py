"""The rod demo: a Nylon cantilever checked against beam theory, in a few seconds."""

from __future__ import annotations

import math
import time

from knitlad.fabric.scenes.rod import Cantilever
from knitlad.engine.simulation import Simulation


def cantilever_demo(n_nodes: int = 41, length_m: float = 0.02) -> list[dict]:
    """Small and large deflection and first frequency, knitlad vs theory (rows of a table)."""
    c = Cantilever(length_m, n_nodes)
    B = c.material.bending_stiffness
    rows = []

    force = 1e-3 * B / length_m**2
    t = time.perf_counter()
    sim = Simulation(c.build(tip_force=(0.0, -force, 0.0)))
    sim.relax(force_tol_N=force * 1e-6, max_steps=5_000_000)
    knit = -sim.positions_m()[-1, 1]
    ref = c.small_deflection(force)
    rows.append(dict(check="tip deflection, F L^3/3B", knitlad=knit, theory=ref, unit="m", wall_s=time.perf_counter() - t))

    # release from the loaded shape and time the oscillation
    t = time.perf_counter()
    period = 2 * math.pi / c.first_frequency()
    sim = Simulation(sim.rods.replace_model(f_ext=0.0 * sim.model.f_ext), drag_per_s=0.0)
    tips: list[tuple[float, float]] = []
    sim.run(4.5 * period, observe=lambda s: tips.append((s.time_s, s.state.x[-1, 1])), observe_every_s=period / 100)
    ups = [
        t0 - y0 * (t1 - t0) / (y1 - y0)
        for (t0, y0), (t1, y1) in zip(tips, tips[1:])
        if y0 < 0 <= y1
    ]
    # mean period over all upward zero crossings (the first includes the release transient)
    omega = 2 * math.pi * (len(ups) - 1) / (ups[-1] - ups[0]) if len(ups) >= 2 else float("nan")
    rows.append(dict(check="first frequency 1.875^2 sqrt(B/rho_L L^4)", knitlad=omega, theory=c.first_frequency(), unit="rad/s", wall_s=time.perf_counter() - t))
    rows.append(dict(check="node-steps/s (dynamics)", knitlad=n_nodes * sim.steps / rows[-1]["wall_s"], theory=float("nan"), unit="1/s", wall_s=0.0))
    return rows
