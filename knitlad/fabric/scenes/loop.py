"""The single-loop model (paper, Fig. 5b): one loop under tension, hooked to a lower loop.

Three one-stitch courses of the jersey centreline (:class:`knitlad.fabric.scenes.knit.KnitGeometry`
with n_x = 1), bottom to top: the *lower* row n - 1 (held whole; removed to start
the ladder), the *loop* row n (free, pulled at both ends by the tension f_x f0)
and the *upper* row n + 1 (held whole). The legs of the loop pass through the
head of the lower row, and the legs of the upper row through the head of the
loop: the jersey topology of one column.

The ends of the loop row slide along x only: in the fabric the neighbouring
stitches of a course keep them at the course's height; free in y, the loop
climbs out over the upper row (seen). Limitation: the held upper row cannot
yield, and at high tension the tightened head of the loop is trapped between
its diverging legs (no release at f_x = 20 with mu = 0, f_x >= 16 with mu = 0.4).
Variants tried and dropped, with what each did: docs/single_loop.md ("Variants of the tails geometry").
"""

from __future__ import annotations

from dataclasses import dataclass

from knitlad.fabric.scenes.knit import KnitGeometry, discrete_loop_half_height
from knitlad.engine.state import Rods, Scene


@dataclass
class LoopScene:
    geometry: KnitGeometry
    rods: Rods
    lower: int  # yarn index of the held lower row (removed to start the ladder)
    loop: int  # the free row whose release is timed
    upper: int  # the held row above it
    tension_N: float


def build_single_loop(geometry: KnitGeometry, tension_N: float) -> LoopScene:
    """The three rows of one column at (l_x, l_y); the loop row's ends pulled by ``tension_N``."""
    if geometry.n_x != 1:
        raise ValueError("the single-loop model has one stitch per row (n_x = 1)")
    H = discrete_loop_half_height(geometry)
    scene = Scene(geometry.material)
    yarns = []
    for row in (-1, 0, 1):
        pts, _ = geometry.course_points(row, H)
        y = scene.add_yarn(pts)
        last = pts.shape[0] - 1
        if row == 0:
            scene.apply_force(y, 0, (-tension_N, 0.0, 0.0))
            scene.apply_force(y, last, (tension_N, 0.0, 0.0))
            scene.slide(y, [0, last], (1.0, 0.0, 0.0))
        else:
            scene.hold(y, range(pts.shape[0]))
        yarns.append(y)
    rods = scene.build(twist=False)
    return LoopScene(geometry, rods, lower=yarns[0], loop=yarns[1], upper=yarns[2], tension_N=tension_N)
