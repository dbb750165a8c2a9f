"""Rows of the jersey knit periodic along the course: the periodised single-loop model's scene.

Each row is an endless course: a closed yarn of ``columns`` copies of one stitch whose
last edge joins its first node shifted by the period (L, 0, 0), L = columns l_x, with
held images shifted by +-L and +-2L (:meth:`knitlad.engine.state.Scene.add_image`) so that
every row meets its neighbours across the seam. Rows are stacked l_y apart along y,
bottom to top; unlike the periodised stitch there are no images along y: the bottom
and top rows end the stack.

The rows are copies of the relaxed periodised stitch (:mod:`knitlad.fabric.scenes.stitch`),
so the stack starts at the stitch's equilibrium but at its two end rows. The period
is a degree of freedom of its own (:class:`PeriodicRows.set_period`, deformed
affinely along x): a tension is imposed on it by :class:`knitlad.experiments.loop_model.TensionBox`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from knitlad.engine import units
from knitlad.engine.state import Rods, Scene
from knitlad.engine.units import Material

IMAGES_X = 2  # as the periodised stitch: a loop bulges past its cell


@dataclass
class PeriodicRows:
    rods: Rods
    rows: int
    columns: int  # stitches per period
    lx: float  # current column width [internal length]: the period is columns * lx
    ly: float  # row spacing [internal length]
    images: dict[int, list[int]]  # row -> the yarn indices of its images
    absent: set[int] = field(default_factory=set)  # rows out of the energy (removed, or a support)

    @property
    def period(self) -> float:
        return self.columns * self.lx

    def family(self, row: int) -> list[int]:
        """The yarn of ``row`` and its images."""
        return [row] + self.images[row]

    def set_period(self, sim, lx: float) -> None:
        """Deform the stack affinely along x to column width ``lx`` [internal]: every node (held
        and railed ones too), the seams and the image shifts."""
        self.set_cell(sim, lx, self.ly)

    def set_cell(self, sim, lx: float, ly: float) -> None:
        """As :meth:`knitlad.fabric.scenes.stitch.PeriodicStitch.set_cell` (for the cell-energy read-out): ``ly`` is
        the row spacing, the rows being scaled along y about y = 0."""
        scale = np.array([lx / self.lx, ly / self.ly, 1.0])
        sim.state.x[:] *= scale
        sim.replace_model(edge_shift=sim.model.edge_shift * scale, image_shift=sim.model.image_shift * scale)
        self.lx, self.ly = lx, ly

    def _present(self, yarn: np.ndarray) -> np.ndarray:
        return (yarn < self.rows) & ~np.isin(yarn, list(self.absent))

    @property
    def real_edges(self) -> np.ndarray:
        """Edges of the rows present (not their images): the cell's own energy."""
        m = self.rods.model
        return np.flatnonzero(self._present(m.edge_yarn))

    @property
    def real_hinges(self) -> np.ndarray:
        m = self.rods.model
        return np.flatnonzero(self._present(m.node_yarn[m.edge_a[m.hinge_e0]]))

    def row_nodes(self, sim, row: int) -> slice:
        start = sim.model.yarn_start
        return slice(int(start[row]), int(start[row + 1]))


def build_periodic_rows(stitch_nodes: np.ndarray, lx: float, ly: float, rows: int, columns: int,
                        material: Material, rails: dict[int, Sequence[int] | None] | None = None,
                        held: Sequence[int] = (), rest_length: np.ndarray | None = None) -> PeriodicRows:
    """``rows`` rows of ``columns`` copies of one stitch.

    ``stitch_nodes`` (k, 3) [internal length]: one period of a relaxed periodised stitch of
    width ``lx`` and height ``ly`` [internal], sinker to sinker (its closing node excluded).
    ``rails``: row -> the nodes of each of its stitches (local to one stitch, 0 the sinker; None:
    all) that slide along x only, held in y and z (the ends of the stack, or a course's height).
    ``held``: rows held whole (a support). ``rest_length`` (k,) [internal]: the stitch's edge rest
    lengths (edge j from node j; default: the given shape is at rest, which drops the stitch's
    axial strain, and so its tension: f_x f0 / EA of the length, 1.3 f0 on a node at f_x = 4).
    """
    if rows < 2 or columns < 1:
        raise ValueError("the stack needs at least 2 rows of at least 1 column")
    k = stitch_nodes.shape[0]
    course = np.vstack([stitch_nodes + np.array([c * lx, 0.0, 0.0]) for c in range(columns)])
    period = np.array([columns * lx, 0.0, 0.0])
    scene = Scene(material)
    for r in range(rows):
        y = scene.add_yarn((course + np.array([0.0, r * ly, 0.0])) * units.LENGTH, closed=True,
                           period=period * units.LENGTH)
        if r in held:
            scene.hold(y, range(columns * k))
        local = (rails or {}).get(r, ())
        nodes = range(k) if local is None else [j % k for j in local]
        scene.slide(y, [c * k + j for c in range(columns) for j in nodes], (1.0, 0.0, 0.0))
    images: dict[int, list[int]] = {r: [] for r in range(rows)}
    for r in range(rows):
        for i in range(-IMAGES_X, IMAGES_X + 1):
            if i:
                images[r].append(scene.add_image(r, period * i * units.LENGTH))
    rods = scene.build(twist=False)
    if rest_length is not None:
        if rest_length.shape != (k,):
            raise ValueError(f"rest_length must have one entry per stitch edge ({k}), got shape {rest_length.shape}")
        m = rods.model
        # every yarn is closed (as many edges as nodes), so its first edge has its first node's index
        local = (np.arange(m.edge_a.shape[0]) - m.yarn_start[m.edge_yarn]) % k
        rods = rods.replace_model(rest_length=np.asarray(rest_length, dtype=float)[local])
    return PeriodicRows(rods, rows, columns, lx, ly, images)
