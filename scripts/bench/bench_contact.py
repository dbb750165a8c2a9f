"""Benchmark: contact cost against the number of segments (O(N)), and node-steps/s with contact.

A plain weave of n x n Nylon yarns, crossings 4 d apart, pressed together
(crossing axes 0.8 d apart), one Numba thread. For each size it prints the
segments, the touching pairs, the time per step with the neighbour list reused,
the time of one neighbour-list rebuild, node-steps/s with contact on and off,
and the time per step per segment (flat = linear scaling).

    python scripts/bench/bench_contact.py [--sizes 8 16 32 64] [--steps 200]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import knitlad as kl
from knitlad.engine.contact import ContactModel
from knitlad.engine.kernels.contact import STALE, refresh_contacts
from knitlad.engine.kernels.integrate import verlet_steps
from knitlad.fabric.scenes.weave import plain_weave


def timed_steps(sim: kl.Simulation, steps: int) -> float:
    verlet_steps(sim.model, sim.state, sim.work, sim.contacts, sim.dt, 5, sim.twist_mode, sim.has_contact, sim.damping)  # warm
    best = float("inf")
    for _ in range(3):
        t = time.perf_counter()
        verlet_steps(sim.model, sim.state, sim.work, sim.contacts, sim.dt, steps, sim.twist_mode, sim.has_contact, sim.damping)
        best = min(best, time.perf_counter() - t)
    return best / steps


def timed_rebuild(sim: kl.Simulation, repeats: int = 5) -> float:
    m, c = sim.model, sim.contacts
    best = float("inf")
    for _ in range(repeats):
        c.status[STALE] = 1
        t = time.perf_counter()
        refresh_contacts(sim.state.x, m.edge_a, m.edge_b, m.edge_shift, c)
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 32, 64])
    p.add_argument("--steps", type=int, default=200)
    args = p.parse_args()
    try:
        import numba

        numba.set_num_threads(1)
    except Exception:
        pass
    d = kl.NYLON.diameter
    model = ContactModel.for_force(kl.NYLON.f0, d, overlap_fraction=0.05, mu=0.4)
    print(f"{'yarns':>6s} {'segments':>9s} {'touching':>9s} {'step [us]':>10s} {'us/seg':>8s} "
          f"{'rebuild [us]':>12s} {'node-steps/s contact':>21s} {'no contact':>11s}")
    rows = []
    for n in args.sizes:
        scene = plain_weave(n, spacing=4 * d, nodes_per_spacing=8, amplitude=0.4 * d)
        rods = scene.build()
        sim = kl.Simulation(rods.copy(), contact=model)
        bare = kl.Simulation(rods.copy(), dt_s=sim.dt_s)
        nseg = rods.model.edge_a.shape[0]
        t_step = timed_steps(sim, args.steps)
        t_bare = timed_steps(bare, args.steps)
        t_rebuild = timed_rebuild(sim)
        rate = rods.model.n_nodes / t_step
        rows.append((nseg, t_step))
        print(f"{2 * n:6d} {nseg:9d} {sim.contact_stats().touching:9d} {t_step * 1e6:10.1f} "
              f"{t_step / nseg * 1e6:8.4f} {t_rebuild * 1e6:12.1f} {rate:21.3e} {rods.model.n_nodes / t_bare:11.3e}")
    segs, times = np.array(rows).T
    slope = np.polyfit(np.log(segs), np.log(times), 1)[0]
    print(f"cost per step ~ segments^{slope:.2f} (1 = linear)")


if __name__ == "__main__":
    main()
