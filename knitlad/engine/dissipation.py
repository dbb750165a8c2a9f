"""Where a rod's energy goes: the physical dissipations (SI) and the energy ledger of a dynamic run.

Three dissipations besides friction, each off by default, each with its source
(the kernels: :mod:`knitlad.engine.kernels.dissipation`):

* :class:`MaterialDamping`: the yarn's polymer is viscoelastic. Nylon's loss factor (tan delta, the energy
  lost per cycle over 2 pi times the energy stored) is a few per cent at room temperature: 0.01 to 0.05 for
  dry polyamides in Ashby's loss-coefficient charts (M. F. Ashby, *Materials Selection in Mechanical
  Design*, the loss coefficient-modulus chart), rising towards 0.1 with the water it absorbs (J. M. R.
  Quistwater, *The influence of water sorption on the dynamic mechanical properties of nylon 6-6*, M.Sc.
  thesis, University of British Columbia, 1958, on 15-denier monofilaments). Modelled as one standard
  linear solid branch in the rod's strains, with its loss peak at ``peak_hz``: by default the bending wave
  of one stitch, c_b kappa0 / 2 pi = 3.1 kHz, the frequency of a loop letting go (a loop's release takes
  0.1 to 0.5 ms). Away from the peak the loss factor falls (:meth:`MaterialDamping.loss_factor_at`): to
  half at about 0.27 and 3.7 times the peak frequency, to a fifth at about 0.1 and 10 times.
* :class:`AirDrag`: still air at 20 degrees C and 1 atm (density 1.204 kg/m^3, kinematic viscosity
  1.516e-5 m^2/s). At the ladder's speeds (up to ~40 m/s, d = 0.14 mm) the yarn's Reynolds number is 10 to
  400: the cross-flow drag coefficient of a cylinder (White's fit, 1 + 10 Re^(-2/3)) and a tangential skin
  friction coefficient :data:`SKIN_FRICTION`.
* The global drag -gamma m v (``Simulation.set_drag``): the damping of the authors' engine (its jersey
  example: a drag of 0.1, then 0.01, per axial-wave time of a segment). A way to reproduce their
  simulation, not physics: real air gives ~1e2 /s at the ladder's speeds. Their engine also damps each
  segment's spin at the same rate (``Simulation.set_spin_drag``); :func:`authors_drag_per_s` converts their
  lambda.

The ledger (:class:`EnergyLedger`, ``Simulation.ledger()``): the rods' energy now (elastic, stored in the
contacts' springs and in the viscoelastic branches, kinetic, the potential of constant external forces),
the work the supports and obstacles did on them, and the energy each mechanism took out, since
``Simulation.reset_ledger()``. What is left over is the integrator's own error (``residual``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from knitlad.engine import units
from knitlad.engine.kernels.dissipation import LEDGER_NAMES, DampingParams, branch_energy, relaxed_branches
from knitlad.engine.kernels.elastic import edge_vectors
from knitlad.engine.kernels.integrate import kinetic_energy, potential_energy

# the authors' engine (J. Crassous, Frictional-Fibers, commit b2c502d) in its own units: a segment as long as the
# yarn's radius (its jersey example: radius 1, l0 1, 120 segments per stitch at d/l0 = 1/60), a node's mass 1,
# the stretching stiffness k0 = EA 1; so its time unit is the axial wave's time over a radius, r sqrt(rho_L/EA)
AUTHORS_AXIAL_DASHPOT = 2.8  # lambda_internal of its jersey example (main.c), in sqrt(EA rho_L): 1.98 x critical
AUTHORS_CONTACT_DASHPOT = 1.0  # lambda_contact_n of its jersey example (main.c), in sqrt(EA rho_L)
AUTHORS_TWIST_INERTIA = 2.0  # its j = masse (jersey.c) is m r^2 per segment, twice a cylinder's m r^2 / 2
NYLON_LOSS_FACTOR = 0.03  # the loss factor "on" means: the middle of dry Nylon's 0.01-0.05 (module docstring)
STITCH_BENDING_HZ = 3.1e3  # c_b kappa0 / 2 pi of the paper's knit: 30.6 m/s x 645 /m / 2 pi
# C_T of a smooth monofilament sliding along itself: a laminar boundary layer grown over about one stitch
# (Re_l ~ 2e4 at 30 m/s: 1.33/sqrt(Re_l) = 0.01), doubled for the transverse curvature of a layer thicker than
# the yarn's radius. An estimate (0.01-0.05): the tangential drag is a tenth of the normal one at equal speeds.
SKIN_FRICTION = 0.02
AIR_DENSITY = 1.204  # kg/m^3, 20 degrees C, 1 atm
AIR_VISCOSITY = 1.516e-5  # m^2/s, kinematic, 20 degrees C


@dataclass(frozen=True)
class MaterialDamping:
    """The yarn as a standard linear solid (one Maxwell branch in parallel with its elasticity), in its
    stretching and bending (:func:`knitlad.engine.kernels.dissipation.viscoelastic_forces`).

    ``loss_factor``: the peak loss factor eta_max [-] (Nylon: :data:`NYLON_LOSS_FACTOR`, 0.01-0.1).
    ``peak_hz``: the frequency of the peak [Hz]. The branch's stiffness over the elastic one is
    ratio = 2 eta^2 + 2 eta sqrt(1 + eta^2) (from eta_max = ratio / (2 sqrt(1 + ratio))) and its
    relaxation time tau = 1 / (omega_peak sqrt(1 + ratio)).
    """

    loss_factor: float = NYLON_LOSS_FACTOR
    peak_hz: float = STITCH_BENDING_HZ

    def __post_init__(self) -> None:
        if not (0.0 < self.loss_factor <= 1.0):
            raise ValueError(f"loss_factor must lie in (0, 1], got {self.loss_factor!r}")
        if not (0.0 < self.peak_hz < math.inf):
            raise ValueError(f"peak_hz must be a positive frequency in Hz, got {self.peak_hz!r}")

    @property
    def branch_ratio(self) -> float:
        eta = self.loss_factor
        return 2.0 * eta * eta + 2.0 * eta * math.sqrt(1.0 + eta * eta)

    @property
    def relaxation_time_s(self) -> float:
        return 1.0 / (2.0 * math.pi * self.peak_hz * math.sqrt(1.0 + self.branch_ratio))

    def loss_factor_at(self, frequency_hz: float) -> float:
        """eta(omega) = ratio omega tau / (1 + (1 + ratio)(omega tau)^2), the loss factor at ``frequency_hz``."""
        r, wt = self.branch_ratio, 2.0 * math.pi * frequency_hz * self.relaxation_time_s
        return r * wt / (1.0 + (1.0 + r) * wt * wt)

    def storage_factor_at(self, frequency_hz: float) -> float:
        """The storage modulus over the elastic one at ``frequency_hz``:
        1 + ratio (omega tau)^2 / (1 + (omega tau)^2)."""
        wt = 2.0 * math.pi * frequency_hz * self.relaxation_time_s
        return 1.0 + self.branch_ratio * wt * wt / (1.0 + wt * wt)


@dataclass(frozen=True)
class AirDrag:
    """Still air around the yarns (:func:`knitlad.engine.kernels.dissipation.air_drag_forces`): SI."""

    density_kg_m3: float = AIR_DENSITY
    kinematic_viscosity_m2_s: float = AIR_VISCOSITY
    skin_friction: float = SKIN_FRICTION

    def __post_init__(self) -> None:
        for name in ("density_kg_m3", "kinematic_viscosity_m2_s"):
            value = getattr(self, name)
            if not (0.0 < value < math.inf):
                raise ValueError(f"{name} must be positive, got {value!r}")
        if not (0.0 <= self.skin_friction < math.inf):
            raise ValueError(f"skin_friction must be >= 0, got {self.skin_friction!r}")


def authors_time_unit_s(material) -> float:
    """The authors' engine's time unit for ``material`` [s]: r sqrt(rho_L / EA), r the yarn's radius (the
    constants above)."""
    return 0.5 * material.diameter * math.sqrt(material.line_density / material.stretching_stiffness)


def authors_drag_per_s(drag_lambda: float, material) -> float:
    """The global drag rate gamma [1/s] of the authors' drag ``lambda`` (their code units) on ``material``.

    Their engine (``kernel_le_force_v9.6.cl``, ``kernel_Calculate_le``) puts f = -lambda (x_t - x_t-1)/dt on
    every node, of mass 1 per segment of length r, so gamma = lambda / (r sqrt(rho_L/EA)) per unit time, and
    the same lambda on the twist rate of a segment of inertia 2 x a cylinder's gives the spin the same rate.
    The paper's Nylon (d = 0.14 mm): gamma = 1.94e7 lambda /s, so the README's range 1e-4 to 1e-3 is 1.9e3 to
    1.9e4 /s. A per-length drag: at any resolution of ours the same lambda is the same gamma."""
    if not (drag_lambda >= 0 and math.isfinite(drag_lambda)):
        raise ValueError(f"drag_lambda must be >= 0, got {drag_lambda!r}")
    return drag_lambda / authors_time_unit_s(material)


def authors_contact_dashpot(material) -> float:
    """The authors' normal contact dashpot c_n [N s/m]: lambda_contact_n sqrt(EA rho_L), absolute per contact
    (``kernel_contact_v9.6.cl``: fn = kn delta + lambda_n (delta_t - delta_t-1)/dt), whatever the resolution."""
    return AUTHORS_CONTACT_DASHPOT * math.sqrt(material.stretching_stiffness * material.line_density)


def damping_params(drag_per_ms: float, material: MaterialDamping | None, air: AirDrag | None,
                   supports_moving: bool, spin_drag_per_ms: float = 0.0) -> DampingParams:
    """What the kernels take (internal units) from the SI settings."""
    ratio, tau = (material.branch_ratio, material.relaxation_time_s / units.TIME) if material else (0.0, 1.0)
    if air is None:
        rho, nu, skin = 0.0, 1.0, 0.0
    else:
        rho = air.density_kg_m3 / (units.MASS / units.LENGTH**3)
        nu = air.kinematic_viscosity_m2_s / (units.LENGTH**2 / units.TIME)
        skin = air.skin_friction
    return DampingParams(float(drag_per_ms), float(ratio), float(tau), float(rho), float(nu), float(skin),
                         bool(supports_moving), float(spin_drag_per_ms))


@dataclass(frozen=True)
class EnergyLedger:
    """Where the energy of a dynamic run went [J], since the ledger was last reset.

    Stored now: ``stretching``, ``bending``, ``twisting`` (elastic), ``branches`` (the viscoelastic
    branches), ``contact`` (the contacts' normal and tangential springs), ``kinetic``, ``external`` (the
    potential -f.x of constant external forces such as gravity). Put in: ``support_work`` (held nodes that
    move), ``obstacle_work`` (the obstacles' forces, their springs, dashpots and friction together),
    ``owner_changes`` (the jumps of the contact energy where the union counting passes a contact from one edge
    to its neighbour, either sign: :func:`knitlad.engine.kernels.contact.pair_contact_forces`; 0 when counting
    all pairs). Taken
    out (each >= 0 up to round-off): ``axial_dashpot`` (the numerical dashpot of the axial springs, and with
    implicit axial springs the scheme's own damping of axial waves), ``contact_dashpot``, ``friction``
    (sliding at the Coulomb limit, the tangential dashpot, springs lost when pairs separate),
    ``global_drag``, ``material``, ``air``, ``fracture`` (the energy stored in what a break cut away:
    :mod:`knitlad.engine.fracture`). ``start``: the stored energy at the reset. ``residual``: the
    change of the stored energy plus what was taken out less what was put in: the integrator's error
    (docs/dissipation.md). ``turnover``: what was put in or taken out, the scale the residual is judged against.
    """

    stretching: float
    bending: float
    twisting: float
    branches: float
    contact: float
    kinetic: float
    external: float
    axial_dashpot: float
    contact_dashpot: float
    friction: float
    global_drag: float
    material: float
    air: float
    support_work: float
    obstacle_work: float
    start: float
    time_s: float
    fracture: float = 0.0
    owner_changes: float = 0.0

    DISSIPATED = ("axial_dashpot", "contact_dashpot", "friction", "global_drag", "material", "air", "fracture")
    STORED = ("stretching", "bending", "twisting", "branches", "contact", "kinetic", "external")

    @property
    def stored(self) -> float:
        return sum(getattr(self, k) for k in self.STORED)

    @property
    def dissipated(self) -> float:
        return sum(getattr(self, k) for k in self.DISSIPATED)

    @property
    def work_in(self) -> float:
        return self.support_work + self.obstacle_work + self.owner_changes

    @property
    def residual(self) -> float:
        return self.stored - self.start + self.dissipated - self.work_in

    @property
    def turnover(self) -> float:
        """The energy that moved through the ledger: the larger of the work put in and the energy taken out
        (both counted positive), at least the change of the stored energy."""
        return max(abs(self.work_in), self.dissipated, abs(self.stored - self.start))

    def as_dict(self) -> dict[str, float]:
        out = asdict(self)
        out.update(stored=self.stored, dissipated=self.dissipated, work_in=self.work_in, residual=self.residual,
                   turnover=self.turnover)
        return out



class DissipationControl:
    """The dissipations of a :class:`knitlad.engine.simulation.Simulation` and its energy ledger (mixed into
    it): the global drag and the air, settable during a run, the kernels' parameters, the viscoelastic
    branches' start, and the ledger's start and reading."""

    def set_drag(self, per_s: float) -> None:
        """A global viscous drag -gamma m v on every free node from the next step on [1/s] (0: none)."""
        if not (per_s >= 0 and math.isfinite(per_s)):
            raise ValueError(f"drag must be >= 0 per second, got {per_s!r}")
        self.drag = per_s * units.TIME

    def set_spin_drag(self, per_s: float) -> None:
        """A global drag -gamma I omega on every free edge's spin about its axis from the next step on [1/s]
        (0: none; with twist only): the authors' engine damps the twist rate as the nodes, at the same rate."""
        if not (per_s >= 0 and math.isfinite(per_s)):
            raise ValueError(f"spin drag must be >= 0 per second, got {per_s!r}")
        self.spin_drag = per_s * units.TIME

    def set_air(self, air: AirDrag | None) -> None:
        """Air drag on every edge from the next step on (:class:`knitlad.engine.dissipation.AirDrag`; None: none)."""
        if air is not None and not isinstance(air, AirDrag):
            raise TypeError(f"air must be an AirDrag or None, got {type(air).__name__}")
        self.air = air

    @property
    def damping(self):
        """The dissipation the kernels apply (:func:`knitlad.engine.dissipation.damping_params`)."""
        m = self.model
        moving = bool(np.any(m.v_prescribed[m.held])) if m.held.any() else False
        if m.rail_node.size and not moving:  # a rail carried across itself (ramp_held's rails) is a moving support
            v = self.state.v[m.rail_node]
            moving = bool(np.any(v - np.sum(v * m.rail_axis, axis=1)[:, None] * m.rail_axis))
        return damping_params(self.drag, self.material_damping, self.air, moving, self.spin_drag)

    def relax_branches(self) -> None:
        """Put the viscoelastic branches at rest at the current shape: as after a long rest, which is how a
        simulation starts (a state handed over carries no branch history)."""
        m, w = self.model, self.work
        edge_vectors(self.state.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen)
        relaxed_branches(w.e, w.elen, m.rest_length, m.hinge_e0, m.hinge_e1, w.branch_ext, w.branch_kb)

    def reset_ledger(self) -> None:
        """Start the energy ledger (:meth:`ledger`) now: nothing taken out or put in, the stored energy now its
        start."""
        self.work.ledger[:] = 0.0
        self._ledger_start = (0.0, 0.0)
        self._fracture_J = 0.0
        first = self.ledger()
        self._ledger_start = (first.stored, self.time_s)

    def ledger(self) -> EnergyLedger:
        """Where the energy went since :meth:`reset_ledger` [J] (:class:`EnergyLedger`). Counted over dynamic
        steps (``step``, ``run``, ``ramp_held``, ``settle``); a ``relax`` starts it again. The stored energies
        are read at the last step's end."""
        e = self.energies_J()
        m, w = self.model, self.work
        ratio = self.material_damping.branch_ratio if self.material_damping else 0.0
        branches = branch_energy(w.elen, m.rest_length, m.EA, m.hinge_e0, m.hinge_e1, w.e, m.B_over_l, ratio,
                                 w.branch_ext, w.branch_kb) * units.ENERGY
        totals = w.ledger.sum(axis=0) * units.ENERGY
        start, t0 = self._ledger_start
        return EnergyLedger(
            stretching=e["stretching"], bending=e["bending"], twisting=e["twisting"], branches=float(branches),
            contact=e["contact"], kinetic=e["kinetic"], external=e["external"],
            **{name: float(totals[k]) for k, name in enumerate(LEDGER_NAMES)}, start=start,
            time_s=self.time_s - t0, fracture=self._fracture_J)

    def energies_J(self) -> dict[str, float]:
        """Kinetic, stretching, bending, twisting, contact (stored), external-potential and total energy [J]."""
        es, eb, et, ec, ext = potential_energy(self.model, self.state, self.work, self.contacts, self.twist_mode,
                                               self.has_contact)
        ek = kinetic_energy(self.model, self.state)
        e = {"kinetic": ek, "stretching": es, "bending": eb, "twisting": et, "contact": ec, "external": ext}
        e["total"] = sum(e.values())
        return {k: float(v) * units.ENERGY for k, v in e.items()}
