"""Single-rod scenes for validation and the demo: a clamped cantilever."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from knitlad.engine.state import Rods, Scene
from knitlad.engine.units import NYLON, Material


@dataclass(frozen=True)
class Cantilever:
    """A rod clamped at x = 0 along +x, free at x = length.

    Clamp convention: nodes 0 and 1 are held at x = -h/2 and +h/2, so the clamp
    sits at the midpoint of the first edge and the tip at x = length; the
    discrete deflection then converges as O(h^2).
    """

    length: float  # m
    n_nodes: int
    material: Material = NYLON

    @property
    def segment(self) -> float:
        return self.length / (self.n_nodes - 1.5)

    def points(self) -> np.ndarray:
        pts = np.zeros((self.n_nodes, 3))
        pts[:, 0] = (np.arange(self.n_nodes) - 0.5) * self.segment
        return pts

    def build(
        self,
        tip_force: tuple[float, float, float] = (0.0, 0.0, 0.0),
        twist: bool = False,
        stretch_damping_ratio: float = 0.2,
    ) -> Rods:
        scene = Scene(self.material)
        y = scene.add_yarn(self.points(), natural_curvature="straight")
        scene.hold(y, [0, 1])
        if twist:
            scene.hold_twist(y, [0])
        scene.apply_force(y, -1, tip_force)
        return scene.build(twist=twist, stretch_damping_ratio=stretch_damping_ratio)

    def small_deflection(self, force: float) -> float:
        """Euler-Bernoulli tip deflection F L^3 / (3 B) [m]."""
        return force * self.length**3 / (3.0 * self.material.bending_stiffness)

    def first_frequency(self) -> float:
        """Angular frequency of the first bending mode, (1.8751)^2 sqrt(B / (rho_L L^4)) [rad/s]."""
        m = self.material
        return 1.875104068711961**2 * np.sqrt(m.bending_stiffness / (m.line_density * self.length**4))
