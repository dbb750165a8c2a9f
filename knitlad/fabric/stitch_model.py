"""Tensions of the periodised stitch (one repeat of a knit pattern) at imposed (l_x, l_y), and the f_x = 0 curve.

The stitch (:mod:`knitlad.fabric.scenes.stitch`) is built at l_x = min(l_x, 0.30 l0),
l_y = min(l_y, 0.25 l0) (wider or taller, Crane's loops of successive courses
no longer overlap), then the cell is stretched affinely in steps of at most
0.005 l0, each relaxed by FIRE at mu = 0, by the same stretch as the fabric
(:mod:`knitlad.fabric.stretching`).

The tensions are derivatives of the energy of one cell at equilibrium,

    F_x = dE_cell/dL_x,  F_y = dE_cell/dL_y,  f_x = F_x / f0,  f_y = F_y / f0,

taken by central differences under an affine deformation of the relaxed cell:
at equilibrium the internal relaxation does not change E to first order, so
this is the total derivative (the virial tension). A jersey cell holds one course
and one column, so these are the forces per thread; a pattern's repeat of n_c columns
and n_r courses is n_c l_x wide and carried by n_r threads, so f_x = dE_cell/dl_x / (n_c n_r f0),
the derivative by one stitch's periodicity per stitch (and f_y alike). E_cell counts the yarns'
own stretching and bending (and twisting, with natural curvature: framed DER),
their contacts with each other, and half of each contact with an image (the other
half belongs to the neighbouring cell).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import KNIT_CONTACT_FORCE_F0, KNIT_OVERLAP, ContactModel
from knitlad.engine.deprecation import renamed_arguments, renamed_fields
from knitlad.engine.kernels.contact import contact_energy
from knitlad.engine.kernels.elastic import bending_energy, edge_vectors, framed_bending_twisting_energy, stretching_energy
from knitlad.engine.kernels.frames import material_frames, transport_reference_frames, update_reference_twist
from knitlad.fabric.patterns import knit_pattern
from knitlad.fabric.shape_memory import remember_shape
from knitlad.fabric.presets import STITCH_PRESETS
from knitlad.fabric.scenes.knit import BUILD_LX, KnitGeometry, build_loop_overlap, widest_fitting_width
from knitlad.fabric.scenes.stitch import PeriodicStitch, build_periodic_stitch
from knitlad.engine.simulation import Simulation, small_scene_threads
from knitlad.fabric.stretching import stretch_to
from knitlad.engine.units import NYLON, Material

BUILD_LY = 0.25  # tallest l_y/l0 the stitch is built at


@renamed_fields({"lx_over_l0": "lx", "ly_over_l0": "ly", "nodes_per_stitch": "resolution",
                 "sagitta_radius_d": "sagitta_radius"}, since="0.14.0")
@dataclass
class StitchSettings:
    """Inputs of one periodised stitch, built by :meth:`knitlad.experiments.config.StitchConfig.settings` (which has
    the defaults and units of the first three and the material); the rest are the model's own choices."""

    lx: float  # l_x/l0
    ly: float  # l_y/l0
    resolution: int
    material: Material
    contact_force_f0: float = KNIT_CONTACT_FORCE_F0
    overlap_fraction: float = KNIT_OVERLAP
    sagitta_radius: float = 0.0  # the contact's sagitta correction (knitlad.engine.contact.sagitta_corrected_radius), in d; 0: none
    contact_law: str = "linear"  # the contact's normal law (knitlad.engine.kernels.contact_law)
    pattern: str = "jersey"  # the knit pattern whose repeat the cell holds (knitlad.fabric.patterns)
    stretch_increment: float = 0.005
    relax_steps: int = 20_000  # per increment
    force_tol_f0: float = 1e-4  # final relaxation: max |F| on a node, in f0


@dataclass
class StitchResult:
    settings: StitchSettings
    fx: float = math.nan
    fy: float = math.nan
    converged: bool = False
    residual_f0: float = math.nan  # the largest force left on a node by the final relaxation, in f0
    max_overlap_over_d: float = math.nan
    relax_steps: int = 0
    wall_s: float = 0.0

    def summary(self) -> dict:
        return {"fx": self.fx, "fy": self.fy, "lx_over_l0": self.settings.lx,
                "ly_over_l0": self.settings.ly, "converged": self.converged, "residual_f0": self.residual_f0,
                "max_overlap_over_d": self.max_overlap_over_d, "relax_steps": self.relax_steps,
                "wall_s": self.wall_s}


class StitchRun:
    def __init__(self, settings: StitchSettings) -> None:
        self.s = settings
        self.ly = min(settings.ly, BUILD_LY)
        self.lx, geometry = self._build_geometry()
        self.cell: PeriodicStitch = build_periodic_stitch(geometry)
        contact = ContactModel.of_settings(settings, mu=0.0)
        self.sim = Simulation(self.cell.rods, contact=contact)
        self.result = StitchResult(settings)

    def _build_geometry(self) -> tuple[float, KnitGeometry]:
        """The widest build l_x <= min(target, 0.30 l0) at which a stitch holds l0 and its loop
        overlaps the next course's by at least d, and as far as thick yarns need
        (:func:`~knitlad.fabric.scenes.knit.build_loop_overlap`: they need narrower cells)."""
        s, m = self.s, self.s.material
        lx = widest_fitting_width(min(s.lx, BUILD_LX), self.ly, m, s.resolution,
                                  min_loop_overlap=max(m.diameter, build_loop_overlap(m, s.pattern)),
                                  pattern=s.pattern)
        columns, courses = knit_pattern(s.pattern).period
        return lx, KnitGeometry(n_x=columns, n_y=courses, l_x=lx * m.stitch_length, l_y=self.ly * m.stitch_length,
                                resolution=s.resolution, material=m, pattern=s.pattern)

    def _relax(self, steps: int, tol_f0: float) -> dict:
        info = self.sim.relax(force_tol_N=tol_f0 * self.s.material.f0, max_steps=steps)
        self.result.relax_steps += info["steps"]
        return info

    # the stitch as a box of knitlad.fabric.stretching: deformed affinely, relaxed, read for f_x
    def deform(self, lx: float, ly: float) -> None:
        l0 = self.s.material.stitch_length / units.LENGTH
        self.lx, self.ly = lx, ly
        self.cell.set_cell(self.sim, lx * l0, ly * l0)

    def relax(self) -> dict:
        """One round at the stretch's tolerance (1e-2 f0)."""
        return self._relax(self.s.relax_steps, 1e-2)

    def tension(self) -> float:
        return self.tensions()[0]

    def remember_shape(self, K: float, peak_ratio: float | None = None) -> None:
        """From here on the yarn carries twist and remembers its current shape: its natural curvature is
        the fraction of the current curvature whose mean (kappa_bar/kappa0)^2 is ``K``, concentrated at the
        most bent hinges to a max/mean of ``peak_ratio`` if given
        (:func:`knitlad.fabric.shape_memory.remember_shape`)."""
        rods = remember_shape(self.sim.rods, K, self.cell.real_hinges, self.s.material, peak_ratio)
        self.cell.rods = rods
        self.sim = Simulation(rods, contact=self.sim.contact_model)

    def settle(self) -> dict:
        """The final relaxation, to ``force_tol_f0``."""
        return self._relax(20 * self.s.relax_steps, self.s.force_tol_f0)

    def stretch(self) -> None:
        """Relax as built, stretch affinely to the target (knitlad.fabric.stretching), relax to ``force_tol_f0``."""
        s = self.s
        self.relax()
        stretch_to(self, s.lx, s.ly, s.stretch_increment, min_increments=0)
        info = self.settle()
        self.result.converged = info["converged"]
        self.result.residual_f0 = info["max_force_N"] / s.material.f0

    def tensions(self) -> tuple[float, float]:
        return cell_tensions(self.sim, self.cell, self.s.material.f0)

    def run(self) -> StitchResult:
        t0 = time.perf_counter()
        with small_scene_threads():
            self.stretch()
            self.result.fx, self.result.fy = self.tensions()
            self.sim.compute_forces()
        d = self.s.material.diameter
        self.result.max_overlap_over_d = self.sim.contact_stats().max_overlap_m / d
        self.result.wall_s = time.perf_counter() - t0
        return self.result


RENAMED_CELL_ARGUMENTS = {"lx_over_l0": "lx", "ly_over_l0": "ly", "nodes_per_stitch": "resolution"}


@renamed_arguments(RENAMED_CELL_ARGUMENTS, since="0.14.0")
def stitch_tensions(lx: float, ly: float, resolution: int | None = None,
                    material: Material = NYLON, sagitta_radius: float | None = None,
                    contact_law: str = "linear", pattern: str = "jersey") -> StitchResult:
    """The stitch (one repeat of ``pattern``) at (l_x, l_y) [l/l0]; the resolution and the sagitta correction
    default to the default preset's (:mod:`knitlad.fabric.presets`)."""
    preset = STITCH_PRESETS["default"]
    if resolution is None:
        resolution = preset["resolution"]
    if sagitta_radius is None:
        sagitta_radius = preset["sagitta_radius"]
    return StitchRun(StitchSettings(lx, ly, resolution, material,
                                    sagitta_radius=sagitta_radius, contact_law=contact_law,
                                    pattern=pattern)).run()


@renamed_arguments(RENAMED_CELL_ARGUMENTS, since="0.14.0")
def zero_tension_lx(ly: float, lo: float = 0.22, hi: float = 0.40, tol: float = 1e-3, **kwargs) -> float:
    """l_x/l0 at which the relaxed stitch carries f_x = 0 for this l_y (regula falsi, then bisection)."""
    f_lo = stitch_tensions(lo, ly, **kwargs).fx
    f_hi = stitch_tensions(hi, ly, **kwargs).fx
    if not f_lo < 0 < f_hi:
        raise ValueError(f"l_y/l0 = {ly}: f_x does not change sign between l_x/l0 = {lo} ({f_lo:.3g}) "
                         f"and {hi} ({f_hi:.3g})")
    for it in range(60):
        guess = lo - f_lo * (hi - lo) / (f_hi - f_lo) if it % 2 == 0 else 0.5 * (lo + hi)
        if not lo < guess < hi:
            guess = 0.5 * (lo + hi)
        f = stitch_tensions(guess, ly, **kwargs).fx
        if f < 0:
            lo, f_lo = guess, f
        else:
            hi, f_hi = guess, f
        if hi - lo < tol:
            break
    return lo - f_lo * (hi - lo) / (f_hi - f_lo)


@dataclass(frozen=True)
class ZeroTensionResult:
    """One point of the configuration diagram's f_x = 0 curve: the width l_x/l0 at which the relaxed stitch
    carries no tension at ``settings.ly`` (``settings.lx`` is that width)."""

    settings: StitchSettings
    wall_s: float

    def summary(self) -> dict:
        return {"ly_over_l0": self.settings.ly, "lx_over_l0_at_fx0": self.settings.lx,
                "wall_s": self.wall_s}


def zero_tension_width(settings: StitchSettings, lo: float = 0.22, hi: float = 0.40) -> ZeroTensionResult:
    """:func:`zero_tension_lx` for the stitch of ``settings`` at its l_y (its l_x is not read): the diagram's
    experiment (`knitlad diagram`)."""
    t0 = time.perf_counter()
    lx = zero_tension_lx(settings.ly, lo, hi, resolution=settings.resolution,
                         material=settings.material, sagitta_radius=settings.sagitta_radius,
                         contact_law=settings.contact_law, pattern=settings.pattern)
    return ZeroTensionResult(dataclasses.replace(settings, lx=lx), time.perf_counter() - t0)


def cell_energy(sim: Simulation, cell: PeriodicStitch) -> float:
    """E_cell [internal: mN mm] at the current positions (see the module docstring)."""
    m, x, c = sim.model, sim.state.x, sim.fresh_contacts()
    w = sim.work
    edge_vectors(x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen)
    real = cell.real_edges
    e = stretching_energy(w.elen[real], m.rest_length[real], m.EA[real])
    h = cell.real_hinges
    if sim.twist:
        e += sum(framed_energy(sim, h))
    else:
        e += bending_energy(w.e, w.elen, m.hinge_e0[h], m.hinge_e1[h], m.B_over_l[h])
    if c.pairs.shape[0] == 0:
        return float(e)
    n = int(c.n_pairs[0])
    pairs, slip = c.pairs[:n], c.slip[:n]
    img = c.edge_image[pairs]
    for weight, mask in ((1.0, ~img[:, 0] & ~img[:, 1]), (0.5, img[:, 0] ^ img[:, 1])):
        p = np.ascontiguousarray(pairs[mask])
        e += weight * contact_energy(x, m.edge_a, m.edge_b, m.edge_shift, c, p, np.ascontiguousarray(slip[mask]))
    return float(e)


def framed_energy(sim: Simulation, hinges: np.ndarray) -> tuple[float, float]:
    """(bending, twisting) energy of ``hinges`` at the current positions, with the reference frames
    carried from the last step's tangents to the current ones (as a step would; the state is untouched)."""
    m, s, w = sim.model, sim.state, sim.work
    tangent, ref_u, ref_twist = s.tangent.copy(), s.ref_u.copy(), s.ref_twist.copy()
    transport_reference_frames(w.e, w.elen, tangent, ref_u)
    update_reference_twist(tangent, ref_u, m.hinge_e0, m.hinge_e1, ref_twist)
    d1, d2 = np.zeros_like(tangent), np.zeros_like(tangent)
    material_frames(tangent, ref_u, s.theta, d1, d2)
    return framed_bending_twisting_energy(
        w.e, w.elen, d1, d2, m.hinge_e0[hinges], m.hinge_e1[hinges], m.B_over_l[hinges], m.GJ_over_l[hinges],
        np.ascontiguousarray(m.kappa_bar[hinges]), ref_twist[hinges], m.twist_bar[hinges], s.theta)


def cell_tensions(sim: Simulation, cell: PeriodicStitch, f0_N: float, rel_step: float = 1e-5) -> tuple[float, float]:
    """(f_x, f_y): central differences of E_cell under affine stretches of the cell, over f0."""
    x_saved, model_saved = sim.state.x.copy(), sim.model
    lx, ly = cell.lx, cell.ly
    f0 = f0_N / units.FORCE
    out = []
    for axis in (0, 1):
        energies = []
        for sign in (1, -1):
            h = sign * rel_step
            cell.set_cell(sim, lx * (1 + h) if axis == 0 else lx, ly * (1 + h) if axis == 1 else ly)
            energies.append(cell_energy(sim, cell))
            sim.state.x[:] = x_saved
            sim.replace_model(edge_shift=model_saved.edge_shift, image_shift=model_saved.image_shift)
            cell.lx, cell.ly = lx, ly
        length = lx if axis == 0 else ly
        out.append((energies[0] - energies[1]) / (2 * rel_step * length) / (cell.stitches * f0))
    sim.fresh_contacts()
    return out[0], out[1]
