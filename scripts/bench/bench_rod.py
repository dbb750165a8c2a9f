"""Benchmark: node-steps per second of the rod core (stretching + bending).

A straight-at-rest Nylon rod of N nodes, bent into a gentle arc so every kernel
does real work, advanced with velocity Verlet on one Numba thread.
Prints node-steps/s; the issue's goal is >= 3e7 per core.

    python scripts/bench/bench_rod.py [--nodes 50000] [--steps 2000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import knitlad as kl
from knitlad.engine.kernels.integrate import TWIST_FRAMED, TWIST_OFF, TWIST_STRAIGHT, verlet_steps


def build(n_nodes: int, twist: bool = False) -> kl.Simulation:
    seg = kl.NYLON.diameter / 2
    s = np.arange(n_nodes) * seg
    radius = n_nodes * seg / 3.0  # an arc of one radian
    pts = np.column_stack([radius * np.sin(s / radius), radius * (1 - np.cos(s / radius)), np.zeros(n_nodes)])
    scene = kl.Scene()
    y = scene.add_yarn(pts)
    scene.hold(y, [0, 1])
    return kl.Simulation(scene.build(twist=twist))


def measure(sim: kl.Simulation, steps: int, repeats: int = 3, mode: int | None = None) -> float:
    """node-steps/s of ``steps`` Verlet steps (best of ``repeats``); ``mode``: the kernels' twist mode, default the scene's."""
    mode = sim.twist_mode if mode is None else mode
    verlet_steps(sim.model, sim.state, sim.work, sim.contacts, sim.dt, 10, mode, sim.has_contact, sim.damping)  # compile / warm
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        verlet_steps(sim.model, sim.state, sim.work, sim.contacts, sim.dt, steps, mode, sim.has_contact, sim.damping)
        best = min(best, time.perf_counter() - t)
    return sim.model.n_nodes * steps / best


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nodes", type=int, default=50_000)
    p.add_argument("--steps", type=int, default=2_000)
    args = p.parse_args()
    try:
        import numba

        numba.set_num_threads(1)
    except Exception:
        pass
    for label, twist, mode in (("stretch+bend", False, TWIST_OFF), ("stretch+bend+twist (frame-free)", True, TWIST_STRAIGHT),
                               ("stretch+bend+twist (framed DER)", True, TWIST_FRAMED)):
        rate = measure(build(args.nodes, twist), args.steps, mode=mode)
        print(f"{label:34s} N={args.nodes:6d}  {rate:.3e} node-steps/s  ({rate / 3e7:.2f} x the 3e7 goal)")


if __name__ == "__main__":
    main()
