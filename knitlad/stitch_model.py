"""Tensions of the periodised jersey stitch at imposed (l_x, l_y), and the f_x = 0 curve.

The stitch (:mod:`knitlad.scenes.stitch`) is built at l_x = min(l_x, 0.30 l0),
l_y = min(l_y, 0.25 l0) (wider or taller, Crane's loops of successive courses
no longer overlap), then the cell is stretched affinely in steps of at most
0.005 l0, each relaxed by FIRE at mu = 0, as the fabric is in
:mod:`knitlad.protocol`.

The tensions are derivatives of the energy of one cell at equilibrium,

    F_x = dE_cell/dL_x,  F_y = dE_cell/dL_y,  f_x = F_x / f0,  f_y = F_y / f0,

taken by central differences under an affine deformation of the relaxed cell:
at equilibrium the internal relaxation does not change E to first order, so
this is the total derivative (the virial tension). One cell holds one course
and one column, so these are the forces per thread. E_cell counts the yarn's
own stretching and bending, its contacts with itself, and half of each contact
with an image (the other half belongs to the neighbouring cell).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from knitlad import units
from knitlad.contact import ContactModel
from knitlad.kernels.contact import contact_energy
from knitlad.kernels.elastic import bending_energy, edge_vectors, stretching_energy
from knitlad.scenes.jersey import Jersey, widest_fitting_width
from knitlad.scenes.stitch import PeriodicStitch, build_periodic_stitch
from knitlad.simulation import Simulation, numba_threads
from knitlad.units import NYLON, Material

BUILD_LX = 0.30
BUILD_LY = 0.25


@dataclass
class StitchSettings:
    lx_over_l0: float = 0.35
    ly_over_l0: float = 0.25
    nodes_per_stitch: int = 36
    contact_force_f0: float = 20.0
    overlap_fraction: float = 0.05
    stretch_increment: float = 0.005
    relax_steps: int = 20_000  # per increment
    force_tol_f0: float = 1e-4  # final relaxation: max |F| on a node, in f0
    material: Material = NYLON


@dataclass
class StitchResult:
    settings: StitchSettings
    fx: float = math.nan
    fy: float = math.nan
    converged: bool = False
    max_overlap_over_d: float = math.nan
    relax_steps: int = 0
    wall_s: float = 0.0

    def summary(self) -> dict:
        return {"fx": self.fx, "fy": self.fy, "lx_over_l0": self.settings.lx_over_l0,
                "ly_over_l0": self.settings.ly_over_l0, "converged": self.converged,
                "max_overlap_over_d": self.max_overlap_over_d, "relax_steps": self.relax_steps,
                "wall_s": self.wall_s}


class StitchRun:
    def __init__(self, settings: StitchSettings) -> None:
        self.s = settings
        m = settings.material
        self.ly = min(settings.ly_over_l0, BUILD_LY)
        self.lx, geometry = self._build_geometry()
        self.cell: PeriodicStitch = build_periodic_stitch(geometry)
        contact = ContactModel.for_force(settings.contact_force_f0 * m.f0, m.diameter,
                                         overlap_fraction=settings.overlap_fraction, friction=0.0)
        self.sim = Simulation(self.cell.state, contact=contact)
        self.result = StitchResult(settings)

    def _build_geometry(self) -> tuple[float, Jersey]:
        """The widest build l_x <= min(target, 0.30 l0) at which a stitch holds l0 and its loop
        overlaps the next course's by at least d (thick yarns need narrower cells)."""
        s, m = self.s, self.s.material
        lx = widest_fitting_width(min(s.lx_over_l0, BUILD_LX), self.ly, m, s.nodes_per_stitch,
                                  min_loop_overlap=m.diameter)
        return lx, Jersey(n_x=1, n_y=1, l_x=lx * m.stitch_length, l_y=self.ly * m.stitch_length,
                          nodes_per_stitch=s.nodes_per_stitch, material=m)

    def _relax(self, steps: int, tol_f0: float) -> bool:
        info = self.sim.relax(force_tol_N=tol_f0 * self.s.material.f0, max_steps=steps)
        self.result.relax_steps += info["steps"]
        return info["converged"]

    def stretch(self) -> None:
        s, l0 = self.s, self.s.material.stitch_length / units.LENGTH
        self._relax(s.relax_steps, 1e-2)
        span = max(s.lx_over_l0 - self.lx, s.ly_over_l0 - self.ly)
        n = max(0, int(math.ceil(span / s.stretch_increment - 1e-9)))
        lx0, ly0 = self.lx, self.ly
        for k in range(1, n + 1):
            self.lx = lx0 + (s.lx_over_l0 - lx0) * k / n
            self.ly = ly0 + (s.ly_over_l0 - ly0) * k / n
            self.cell.set_cell(self.lx * l0, self.ly * l0)
            self._relax(s.relax_steps, 1e-2)
        self.result.converged = self._relax(20 * s.relax_steps, s.force_tol_f0)

    def tensions(self) -> tuple[float, float]:
        return cell_tensions(self.sim, self.cell, self.s.material.f0)

    def run(self) -> StitchResult:
        t0 = time.perf_counter()
        with numba_threads(1):  # a few hundred nodes
            self.stretch()
            self.result.fx, self.result.fy = self.tensions()
            self.sim.compute_forces()
        d = self.s.material.diameter
        self.result.max_overlap_over_d = self.sim.contact_stats().max_overlap_m / d
        self.result.wall_s = time.perf_counter() - t0
        return self.result


def stitch_tensions(lx_over_l0: float, ly_over_l0: float, **kwargs) -> StitchResult:
    return StitchRun(StitchSettings(lx_over_l0=lx_over_l0, ly_over_l0=ly_over_l0, **kwargs)).run()


def zero_tension_lx(ly_over_l0: float, lo: float = 0.22, hi: float = 0.40, tol: float = 1e-3, **kwargs) -> float:
    """l_x/l0 at which the relaxed stitch carries f_x = 0 for this l_y (regula falsi, then bisection)."""
    f_lo = stitch_tensions(lo, ly_over_l0, **kwargs).fx
    f_hi = stitch_tensions(hi, ly_over_l0, **kwargs).fx
    if not f_lo < 0 < f_hi:
        raise ValueError(f"l_y/l0 = {ly_over_l0}: f_x does not change sign between l_x/l0 = {lo} ({f_lo:.3g}) "
                         f"and {hi} ({f_hi:.3g})")
    for it in range(60):
        guess = lo - f_lo * (hi - lo) / (f_hi - f_lo) if it % 2 == 0 else 0.5 * (lo + hi)
        if not lo < guess < hi:
            guess = 0.5 * (lo + hi)
        f = stitch_tensions(guess, ly_over_l0, **kwargs).fx
        if f < 0:
            lo, f_lo = guess, f
        else:
            hi, f_hi = guess, f
        if hi - lo < tol:
            break
    return lo - f_lo * (hi - lo) / (f_hi - f_lo)


def cell_energy(sim: Simulation, cell: PeriodicStitch) -> float:
    """E_cell [internal: mN mm] at the current positions (see the module docstring)."""
    s, c = sim.state, sim.fresh_contacts()
    w = sim.work
    edge_vectors(s.x, s.edge_a, s.edge_b, s.edge_shift, w.e, w.elen)
    real = cell.real_edges
    e = stretching_energy(w.elen[real], s.rest_length[real], s.EA[real])
    h = cell.real_hinges
    e += bending_energy(w.e, w.elen, s.hinge_e0[h], s.hinge_e1[h], s.B_over_l[h])
    if c.pairs.shape[0] == 0:
        return float(e)
    n = int(c.n_pairs[0])
    pairs, slip = c.pairs[:n], c.slip[:n]
    img = c.edge_image[pairs]
    for weight, mask in ((1.0, ~img[:, 0] & ~img[:, 1]), (0.5, img[:, 0] ^ img[:, 1])):
        p = np.ascontiguousarray(pairs[mask])
        e += weight * contact_energy(s.x, s.edge_a, s.edge_b, s.edge_shift, c, p, np.ascontiguousarray(slip[mask]))
    return float(e)


def cell_tensions(sim: Simulation, cell: PeriodicStitch, f0_N: float, rel_step: float = 1e-5) -> tuple[float, float]:
    """(f_x, f_y): central differences of E_cell under affine stretches of the cell, over f0."""
    st = sim.state
    saved = [a.copy() for a in (st.x, st.edge_shift, st.image_shift)]
    lx, ly = cell.lx, cell.ly
    f0 = f0_N / units.FORCE
    out = []
    for axis in (0, 1):
        energies = []
        for sign in (1, -1):
            h = sign * rel_step
            cell.set_cell(lx * (1 + h) if axis == 0 else lx, ly * (1 + h) if axis == 1 else ly)
            energies.append(cell_energy(sim, cell))
            for a, b in zip((st.x, st.edge_shift, st.image_shift), saved):
                a[:] = b
            cell.lx, cell.ly = lx, ly
        length = lx if axis == 0 else ly
        out.append((energies[0] - energies[1]) / (2 * rel_step * length) / f0)
    sim.fresh_contacts()
    return out[0], out[1]
