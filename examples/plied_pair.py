"""Two yarns plied into a double helix, pulled at their ends: each presses on the other with the line force
of a helical rod, p = kappa (T + B tau^2) (Kirchhoff: the tension turned, and the bending moment turned),
kappa = a / (a^2 + c^2), tau = c / (a^2 + c^2), a the helix radius, 2 pi c its pitch. Public API only.

    python examples/plied_pair.py
"""

import numpy as np

import knitlad as kl


def ply(pitch=2e-3, turns=3, nodes_per_turn=40, pull=0.01, stiffness=2e4):
    """(p [N/m], kappa (T + B tau^2) [N/m], B tau^2 / T) on the middle third, the ends pulled apart by ``pull`` L."""
    d, B, EA, scene = kl.NYLON.diameter, kl.NYLON.bending_stiffness, kl.NYLON.stretching_stiffness, kl.Scene()
    phi, length = np.linspace(0.0, 2 * np.pi * turns, turns * nodes_per_turn + 1), pitch * turns
    for phase in (0.0, np.pi):                                            # touching: axes d apart
        scene.add_yarn(np.column_stack([0.5 * d * np.cos(phi + phase), 0.5 * d * np.sin(phi + phase),
                                        pitch * phi / (2 * np.pi)]))
    sim = kl.Simulation(scene.build(), contact=kl.ContactModel(stiffness=stiffness))
    for yarn in (0, 1):
        sim.hold(sim.nodes_of(yarn, [0, 1, -2, -1]))                      # clamped ends
        sim.move_held(sim.nodes_of(yarn, [-2, -1]), by_m=(0.0, 0.0, pull * length))
    assert sim.relax(force_tol_N=1e-8, max_steps=400_000)["converged"]
    x = sim.positions_m()[sim.nodes_of(0, list(range(phi.size)))]
    mid = (x[:, 2] > length / 3) & (x[:, 2] < 2 * length / 3)
    a = np.hypot(x[mid, 0], x[mid, 1]).mean()
    c = 1.0 / np.polyfit(x[mid, 2], np.unwrap(np.arctan2(x[mid, 1], x[mid, 0])), 1)[0]
    rest = 2 * np.pi * np.hypot(0.5 * d, pitch / (2 * np.pi)) / nodes_per_turn  # each edge's rest length
    T = EA * (np.linalg.norm(np.diff(x, axis=0), axis=1)[mid[1:] & mid[:-1]].mean() / rest - 1)
    pairs = sim.contact_pairs()
    inside = np.abs(pairs.points_m[:, 2] - length / 2) < length / 6
    p = np.linalg.norm(pairs.normal_N[inside], axis=1).sum() / (length / 3 * np.hypot(a, c) / c)
    return p, a / (a**2 + c**2) * (T + B * c**2 / (a**2 + c**2) ** 2), B * c**2 / (a**2 + c**2) ** 2 / T


if __name__ == "__main__":
    p, kirchhoff, bending = ply()
    print(f"line force {p:.2f} N/m, kappa (T + B tau^2) {kirchhoff:.2f} N/m ({p / kirchhoff - 1:+.2%}); "
          f"B tau^2 / T = {bending:.2f}")
