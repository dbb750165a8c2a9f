"""A plain-weave patch of crossing yarns: a dense contact scene for tests and benchmarks."""

from __future__ import annotations

import numpy as np

from knitlad.engine.state import Scene
from knitlad.engine.units import NYLON, Material


def plain_weave(
    n_yarns: int,
    spacing: float,
    nodes_per_spacing: int = 8,
    material: Material = NYLON,
    amplitude: float | None = None,
) -> Scene:
    """``n_yarns`` warp yarns along x and as many weft yarns along y, interlaced.

    Warp j: z = a cos(pi x / s) (-1)^j; weft i: z = -a cos(pi y / s) (-1)^i, so at
    every crossing the two axes are 2a apart; a = 0.6 d by default (a gap of
    0.2 d). Yarn ends are held. Lengths in metres.
    """
    d = material.diameter
    a = 0.6 * d if amplitude is None else amplitude
    length = n_yarns * spacing
    t = np.linspace(-0.5 * spacing, length - 0.5 * spacing, n_yarns * nodes_per_spacing + 1)
    scene = Scene(material)
    for j in range(n_yarns):
        pts = np.column_stack([t, np.full_like(t, j * spacing), a * np.cos(np.pi * t / spacing) * (-1) ** j])
        y = scene.add_yarn(pts)
        scene.hold(y, [0, -1])
    for i in range(n_yarns):
        pts = np.column_stack([np.full_like(t, i * spacing), t, -a * np.cos(np.pi * t / spacing) * (-1) ** i])
        y = scene.add_yarn(pts)
        scene.hold(y, [0, -1])
    return scene
