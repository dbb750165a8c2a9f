"""A column straight at rest, started with a small imperfection, compressed by moving one end:
the force plateaus at Euler's load pi^2 B / L^2 (pinned ends). Public API only.

    python examples/euler_buckling.py
"""

import numpy as np

import knitlad as kl


def buckle(length=0.02, nodes=41, imperfection=0.001, shortening=0.01, increments=10):
    """Reaction force [N] on the fixed end after each increment of the end's shortening (fractions of L)."""
    s = np.linspace(0.0, length, nodes)
    scene = kl.Scene(kl.NYLON)
    bow = imperfection * length * np.sin(np.pi * s / length)          # first mode, L/1000 at mid-span
    column = scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]), start=np.column_stack([s, bow, 0 * s]))
    sim = kl.Simulation(scene.build())                                  # twist-free: pinned ends
    ends = sim.nodes_of(column, [0, -1])
    sim.hold(ends)
    forces = []
    for _ in range(increments):
        sim.move_held(ends[1], by_m=(-shortening * length / increments, 0.0, 0.0))
        sim.relax(force_tol_N=1e-9, max_steps=400_000)
        forces.append(sim.reaction_forces_N()[ends[0], 0])             # the support pushes back along +x
    return np.array(forces)


if __name__ == "__main__":
    euler = np.pi**2 * kl.NYLON.bending_stiffness / 0.02**2
    for k, f in enumerate(buckle(), start=1):
        print(f"shortening {k / 1000:.3f} L: force {f * 1e3:.4f} mN = {f / euler:.4f} x Euler's {euler * 1e3:.4f} mN")
