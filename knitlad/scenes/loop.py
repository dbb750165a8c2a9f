"""The single-loop model (paper, Fig. 5b): one loop under tension, hooked to a lower loop.

Three one-stitch courses of the jersey centreline (:class:`knitlad.scenes.jersey.Jersey`
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
Variants tried and dropped: a free upper row (under the same tension, or with
pinned ends) and a row held above it (the loops ring against each other and
part only at f_x <= 2), the column stretched from 0.30 to 0.39 l0 before
the release (the upper row's legs then trap the head at every tension), and the
loop row without tails, clamped at its sinkers and sliding along x as the
fabric's courses are held (never released, f_x = 1 to 20, mu = 0), and
rows three stitches wide with only the middle stitch of the lower row removed, so
that the loop's neighbours stay hooked to held rows (never released in 2 ms,
f_x = 0.05 to 20, mu = 0: the tails are drawn out by 0.1 l0 and spring back, the
head stays on the upper row's legs), and the three rows copied from the relaxed
periodised stitch at the fabric's l_x for each f_x (l_x/l0 from 0.346 at f_x = 1 to
0.405 at 20; the 42 x 42 fabric measures 0.348 to 0.394): where the loop lets go,
v_lad is within 15 % of this model's (mu = 0: 0.65, 0.83, 1.11 at f_x 1, 4, 8; one
exception: 0.49 against 0.67 at mu = 0.8, f_x = 2), but
it stays hooked at f_x >= 12 for every mu, and at some lower tensions too (mu = 0 at
f_x = 2, mu = 0.4 and 0.8 at 1): whether the recoil carries the head past the held
upper row's legs decides release or trap. With the tails' tips clamped along x (the
last two nodes on rails), the loop never lets go (f_x = 0.05 to 16, mu = 0 and 0.4):
the recoil that frees it here swings the legs about the tips.
"""

from __future__ import annotations

from dataclasses import dataclass

from knitlad.scenes.jersey import Jersey, discrete_loop_half_height
from knitlad.state import Rods, Scene


@dataclass
class LoopScene:
    geometry: Jersey
    rods: Rods
    lower: int  # yarn index of the held lower row (removed to start the ladder)
    loop: int  # the free row whose release is timed
    upper: int  # the held row above it
    tension_N: float


def build_single_loop(geometry: Jersey, tension_N: float) -> LoopScene:
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
