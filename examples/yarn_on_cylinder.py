"""A yarn dropped across a rigid cylinder under gravity comes to rest on its top, the cylinder carrying
its weight, each half a cantilever whose end sags by w a^4 / (8 B) (a Nylon yarn bends far less than the
cylinder's curvature: it touches at one point). Public API only.

    python examples/yarn_on_cylinder.py
"""

import numpy as np

import knitlad as kl


def drop(length=0.03, nodes=61, radius=2e-3, gap=5e-4, mu=0.5, fall=0.03, g=9.81):
    """(weight [N], force on the cylinder [N, 3-vector], the ends' sag below the middle [m, 2], the
    cantilever's w a^4 / (8 B) [m]) after ``fall`` [s] of dynamics from ``gap`` [m] above the top, relaxed."""
    x = np.linspace(-length / 2, length / 2, nodes)
    top = radius + 0.5 * kl.NYLON.diameter + gap
    scene = kl.Scene(kl.NYLON)
    scene.add_yarn(np.column_stack([x, np.full(nodes, top), np.zeros(nodes)]))
    cylinder = kl.Cylinder(stiffness=500.0, mu=mu, radius_m=radius, axis=(0, 0, 1))
    sim = kl.Simulation(scene.build(), obstacles=[cylinder], drag_per_s=200.0)   # air drag settles the ringing
    weight = kl.NYLON.line_density * length * g
    per_node = np.full(nodes, weight / (nodes - 1))
    per_node[[0, -1]] *= 0.5                                                  # end nodes carry half an edge
    sim.set_external_forces(np.column_stack([0 * per_node, -per_node, 0 * per_node]))
    sim.run(fall)
    sim.relax(force_tol_N=1e-10, max_steps=400_000)
    y = sim.positions_m()[:, 1]
    cantilever = (weight / length) * (length / 2) ** 4 / (8 * kl.NYLON.bending_stiffness)
    return weight, sim.obstacle_reactions_N()[0], y[nodes // 2] - y[[0, -1]], cantilever


if __name__ == "__main__":
    weight, on_cylinder, sag, cantilever = drop()
    print(f"weight {weight * 1e6:.3f} uN, carried by the cylinder to {on_cylinder[1] / -weight - 1:+.1e}; "
          f"ends sag {sag[0] * 1e6:.2f} and {sag[1] * 1e6:.2f} um (w a^4/8B: {cantilever * 1e6:.2f} um)")
