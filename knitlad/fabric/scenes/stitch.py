"""The periodised stitch: one repeat of a knit pattern (one stitch of jersey), periodic in x and y.

Each yarn is one course of the repeat of the centreline (:class:`knitlad.fabric.scenes.knit.KnitGeometry`
with n_x, n_y the pattern's period: 1 x 1 for jersey, 2 x 1 for 1x1 rib, 1 x 2 for garter), closed on
itself across the cell: its last edge joins the first node shifted by the period (n_x l_x, 0, 0). Its
periodic images, shifted by i n_x l_x along x and j n_y l_y along y (up to IMAGES_X stitches and
IMAGES_Y repeats away, not both 0), are held copies that follow it
(:meth:`knitlad.engine.state.Scene.add_image`): the images along x are the neighbouring stitches of the
same course, those along y the courses below and above, so that each loop is threaded by the loops of
the course above and threads those of the course below, as in the fabric.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from knitlad.engine import units
from knitlad.fabric.patterns import knit_pattern
from knitlad.fabric.scenes.knit import KnitGeometry, discrete_loop_half_height
from knitlad.engine.state import Rods, Scene

IMAGES_X = 2  # images up to 2 cells away along x: a loop bulges past its cell (Crane's a = 3/2)
IMAGES_Y = 1


@dataclass
class PeriodicStitch:
    geometry: KnitGeometry
    rods: Rods
    yarn: int  # the first real yarn (the repeat's courses are yarns yarn ... yarn + repeat[1] - 1)
    lx: float  # current periodicities of one stitch [internal length]: the cell is repeat[0] l_x wide
    ly: float
    repeat: tuple[int, int] = (1, 1)  # (columns, courses) of the pattern's repeat the cell holds

    @property
    def stitches(self) -> int:
        """Stitches in the cell."""
        return self.repeat[0] * self.repeat[1]

    def _real(self, yarn: np.ndarray) -> np.ndarray:
        return (yarn >= self.yarn) & (yarn < self.yarn + self.repeat[1])

    def set_cell(self, sim, lx: float, ly: float) -> None:
        """Deform the cell of ``sim`` (a :class:`knitlad.engine.simulation.Simulation` of this stitch) affinely to
        (lx, ly) [internal]: the nodes, and a model with the seam and the image shifts of the new cell."""
        scale = np.array([lx / self.lx, ly / self.ly, 1.0])
        sim.state.x[:] *= scale
        sim.replace_model(edge_shift=sim.model.edge_shift * scale, image_shift=sim.model.image_shift * scale)
        self.lx, self.ly = lx, ly

    @property
    def real_edges(self) -> slice:
        """Edges of the real yarns (the first yarns: their edges come first)."""
        m = self.rods.model
        return slice(0, int(np.count_nonzero(self._real(m.edge_yarn))))

    @property
    def real_hinges(self) -> np.ndarray:
        m = self.rods.model
        return np.flatnonzero(self._real(m.node_yarn[m.edge_a[m.hinge_e0]]))


def build_periodic_stitch(geometry: KnitGeometry) -> PeriodicStitch:
    """One repeat of ``geometry.pattern`` at (geometry.l_x, geometry.l_y), periodic through its images."""
    columns, courses = knit_pattern(geometry.pattern).period
    if (geometry.n_x, geometry.n_y) != (columns, courses) or geometry.band is not None:
        raise ValueError(f"the periodised stitch is one repeat of its pattern ({columns} x {courses} stitches "
                         f"of {geometry.pattern}, no band), not {geometry.n_x} x {geometry.n_y}")
    H = discrete_loop_half_height(geometry)
    scene = Scene(geometry.material)
    yarns = []
    for row in range(courses):
        pts, t = geometry.course_points(row, H)
        course = pts[np.isfinite(t)]  # sinker (t = -pi) to sinker: one period
        yarns.append(scene.add_yarn(course[:-1], closed=True, period=course[-1] - course[0]))
    reach_x = -(-IMAGES_X // columns)  # repeats along x that reach IMAGES_X stitches
    for y in yarns:  # the real yarns first: their edges come first
        for i in range(-reach_x, reach_x + 1):
            for j in range(-IMAGES_Y, IMAGES_Y + 1):
                if i or j:
                    scene.add_image(y, (i * columns * geometry.l_x, j * courses * geometry.l_y, 0.0))
    rods = scene.build(twist=False)
    return PeriodicStitch(geometry, rods, yarns[0], geometry.l_x / units.LENGTH, geometry.l_y / units.LENGTH,
                          repeat=(columns, courses))
