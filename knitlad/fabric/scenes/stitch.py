"""The periodised jersey stitch: one stitch of one course, periodic in x and y.

The yarn is one stitch of the jersey centreline (:class:`knitlad.fabric.scenes.knit.KnitGeometry`
with n_x = n_y = 1), closed on itself across the cell: its last edge joins the
first node shifted by the period (l_x, 0, 0). Its periodic images, shifted by
i l_x along x and j l_y along y (|i| <= 2, |j| <= 1, not both 0), are held
copies that follow it (:meth:`knitlad.engine.state.Scene.add_image`): the images along
x are the neighbouring stitches of the same course, those along y the courses
below and above, so that the stitch's loop is threaded by the loops of the
course above and threads those of the course below, as in the fabric.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from knitlad.engine import units
from knitlad.fabric.scenes.knit import KnitGeometry, discrete_loop_half_height
from knitlad.engine.state import Rods, Scene

IMAGES_X = 2  # images up to 2 cells away along x: a loop bulges past its cell (Crane's a = 3/2)
IMAGES_Y = 1


@dataclass
class PeriodicStitch:
    geometry: KnitGeometry
    rods: Rods
    yarn: int  # the real yarn (the images are the other yarns)
    lx: float  # current cell [internal length]
    ly: float

    def set_cell(self, sim, lx: float, ly: float) -> None:
        """Deform the cell of ``sim`` (a :class:`knitlad.engine.simulation.Simulation` of this stitch) affinely to
        (lx, ly) [internal]: the nodes, and a model with the seam and the image shifts of the new cell."""
        scale = np.array([lx / self.lx, ly / self.ly, 1.0])
        sim.state.x[:] *= scale
        sim.replace_model(edge_shift=sim.model.edge_shift * scale, image_shift=sim.model.image_shift * scale)
        self.lx, self.ly = lx, ly

    @property
    def real_edges(self) -> slice:
        """Edges of the real yarn (the first yarn: its edges come first)."""
        m = self.rods.model
        return slice(0, int(np.count_nonzero(m.edge_yarn == self.yarn)))

    @property
    def real_hinges(self) -> np.ndarray:
        m = self.rods.model
        return np.flatnonzero(m.node_yarn[m.edge_a[m.hinge_e0]] == self.yarn)


def build_periodic_stitch(geometry: KnitGeometry) -> PeriodicStitch:
    """One stitch at (geometry.l_x, geometry.l_y), periodic through its images."""
    if geometry.n_x != 1 or geometry.n_y != 1:
        raise ValueError("the periodised stitch is one stitch (n_x = n_y = 1)")
    H = discrete_loop_half_height(geometry)
    pts, t = geometry.course_points(0, H)
    stitch = pts[np.isfinite(t)]  # sinker (t = -pi) to sinker (t = pi): one period
    period = stitch[-1] - stitch[0]
    scene = Scene(geometry.material)
    y = scene.add_yarn(stitch[:-1], closed=True, period=period)
    for i in range(-IMAGES_X, IMAGES_X + 1):
        for j in range(-IMAGES_Y, IMAGES_Y + 1):
            if i or j:
                scene.add_image(y, (i * geometry.l_x, j * geometry.l_y, 0.0))
    rods = scene.build(twist=False)
    return PeriodicStitch(geometry, rods, y, geometry.l_x / units.LENGTH, geometry.l_y / units.LENGTH)
