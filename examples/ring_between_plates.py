"""A ring squeezed between two rigid plates, step by step: the force against the shortening of the
diameter it pushes on, against a thin ring's closed form delta = (pi/4 - 2/pi) F R^3 / B. Public API only.

    python examples/ring_between_plates.py
"""

import math

import numpy as np

import knitlad as kl


def squeeze(radius=5e-3, nodes=80, steps=(0.01, 0.02, 0.05), stiffness=200.0):
    """[(F [N], delta [m], closed-form F [N])], the plates moved in by ``steps`` x radius in all."""
    phi = 2 * math.pi * np.arange(nodes) / nodes
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([radius * np.cos(phi), radius * np.sin(phi), 0 * phi]), closed=True,
                   natural_curvature="rest")                                        # a ring, force-free
    r = 0.5 * kl.NYLON.diameter
    plates = [kl.Plane(stiffness=stiffness, point_m=(0, -radius - r, 0), normal=(0, 1, 0)),
              kl.Plane(stiffness=stiffness, point_m=(0, radius + r, 0), normal=(0, -1, 0))]
    sim = kl.Simulation(scene.build(twist=True), obstacles=plates)
    B, done, out = kl.NYLON.bending_stiffness, 0.0, []
    for total in steps:
        move, done = 0.5 * (total - done) * radius, total
        sim.move_obstacle(0, (0, move, 0))
        sim.move_obstacle(1, (0, -move, 0))
        assert sim.relax(force_tol_N=1e-9, max_steps=400_000)["converged"]
        y = sim.positions_m()[:, 1]
        delta = 2 * radius - (y.max() - y.min())                                    # the squeezed diameter
        F = sim.obstacle_reactions_N()[1, 1]                                        # on the upper plate, along +y
        out.append((F, delta, delta * B / ((math.pi / 4 - 2 / math.pi) * radius**3)))
    return out


if __name__ == "__main__":
    for F, delta, closed_form in squeeze():
        print(f"delta = {delta * 1e3:.4f} mm: F = {F * 1e3:.4f} mN, closed form {closed_form * 1e3:.4f} mN "
              f"({F / closed_form - 1:+.2%})")
