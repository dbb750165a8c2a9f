"""A yarn over a rigid cylinder, pulled at one end against a dead load at the other: at steady sliding
the pull is the load times e^(mu theta) (the capstan equation; theta = pi here). Public API only.

    python examples/capstan.py
"""

import math

import numpy as np

import knitlad as kl


def capstan(mu=0.3, load=0.05, radius=3e-3, leg=6e-3, speed=0.05, duration=0.03):
    """(pull [N], load [N], load e^(mu pi) [N]): the pull averaged over the second half of ``duration`` [s]
    of pulling at ``speed`` [m/s] (the hanging load rings by a few %)."""
    a = radius + 0.5 * kl.NYLON.diameter                                    # the yarn's axis over the cylinder
    arc = np.linspace(math.pi, 0.0, 48)
    down = np.linspace(0.0, leg, 16)[1:]
    points = np.vstack([np.column_stack([np.full(15, -a), -down[::-1], np.zeros(15)]),   # pulled leg
                        np.column_stack([a * np.cos(arc), a * np.sin(arc), 0 * arc]),     # over the top
                        np.column_stack([np.full(15, a), -down, np.zeros(15)])])          # loaded leg
    scene = kl.Scene(kl.NYLON)
    yarn = scene.add_yarn(points)
    scene.hold(yarn, [0], velocity=(0.0, -speed, 0.0))                     # pulled down the left leg
    cylinder = kl.Cylinder(stiffness=2e3, mu=mu, radius_m=radius, axis=(0, 0, 1))
    sim = kl.Simulation(scene.build(), obstacles=[cylinder], implicit_axial=True)
    forces = np.zeros((len(points), 3))
    forces[-1] = (0.0, -load, 0.0)                                          # the dead load
    sim.set_external_forces(forces)
    sim.run(0.5 * duration)
    pulls = []                                                              # the support's pull along -y
    sim.run(0.5 * duration, observe=lambda s: pulls.append(-s.reaction_forces_N()[0][1]), observe_every_s=1e-4)
    return float(np.mean(pulls)), load, load * math.exp(mu * math.pi)


if __name__ == "__main__":
    pull, load, capstan_law = capstan()
    print(f"pull {pull * 1e3:.2f} mN on a load of {load * 1e3:.1f} mN: {pull / load:.3f} x "
          f"(capstan e^(mu pi) = {capstan_law / load:.3f}, {pull / capstan_law - 1:+.1%})")
