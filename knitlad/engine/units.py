"""Units: the one place where knitlad's internal unit system is defined.

Kernels work in **millimetre, milligram, millisecond** (mm, mg, ms). Derived
internal units follow:

=============  ===========================  =====================
quantity       internal unit                SI value of one unit
=============  ===========================  =====================
length         mm                           1e-3 m
mass           mg                           1e-6 kg
time           ms                           1e-3 s
velocity       mm/ms                        1 m/s
force          mg mm / ms^2                 1e-3 N  (mN)
energy         mN mm                        1e-6 J  (uJ)
bending B      mN mm^2                      1e-9 N m^2
line density   mg/mm                        1e-3 kg/m
stress, E      mN/mm^2                      1e3 Pa  (kPa)
=============  ===========================  =====================

With these units the paper's numbers are all of order 1e-2..1e4, so no kernel
works near the edges of double precision, and velocities read directly in m/s.

The paper's dimensionless scales (Faulconnier et al., "Laddering of a knitted
fabric", main text): kappa0 = 2 pi / l0, f0 = B kappa0^2, c_b = kappa0 sqrt(B/rho_L),
tension per thread f_x = F_x / (n_y f0), lengths as l/l0, velocities as v/c_b.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field, replace

# --- conversion factors: multiply an SI value by TO_INTERNAL to get internal units
LENGTH = 1e-3  # m per internal length unit
MASS = 1e-6  # kg per internal mass unit
TIME = 1e-3  # s per internal time unit
VELOCITY = LENGTH / TIME  # m/s
FORCE = MASS * LENGTH / TIME**2  # N
ENERGY = FORCE * LENGTH  # J
BENDING_STIFFNESS = FORCE * LENGTH**2  # N m^2
LINE_DENSITY = MASS / LENGTH  # kg/m
STRESS = FORCE / LENGTH**2  # Pa


def to_internal(value_si: float, unit: float) -> float:
    """Convert an SI value to internal units, e.g. ``to_internal(1.88e9, STRESS)``."""
    return value_si / unit


def to_si(value_internal: float, unit: float) -> float:
    """Convert an internal value to SI, e.g. ``to_si(f, FORCE)`` gives newtons."""
    return value_internal * unit


@dataclass(frozen=True)
class Material:
    """An isotropic, circular yarn. All fields in SI units.

    diameter        d        [m]
    line_density    rho_L    [kg/m]
    young_modulus   E        [Pa]
    poisson_ratio   nu       [-]   (sets the twist modulus G J = B / (1 + nu))
    stitch_length   l0       [m]   (yarn length per stitch; sets the paper's scales)
    breaking_force  F_b      [N]   (the tension at which the yarn breaks: knitlad.engine.fracture)
    bending_rigidity   B     [N m^2] (None: E pi d^4/64, a solid round monofilament's; a multifilament's
                                    measured B is far below it, knitlad.experiments.yarn)
    torsional_rigidity G J   [N m^2] (None: B/(1 + nu))

    The Nylon's breaking force is its tenacity times its linear density: drawn nylon 6 and 6,6 textile
    filaments hold 40 to 60 cN/tex (Morton & Hearle, *Physical Properties of Textile Fibres*, 4th ed.,
    2008, the tables of tensile properties), high-tenacity ones up to about 80; at 15.8 tex, 50 cN/tex gives
    7.9 N (6.3 to 9.5 N; about 13 N for a high-tenacity line). That is a stress of 510 MPa, at the modulus
    of 1.88 GPa a strain near 27 %: beyond where the rod's linear spring is exact, so a break's timing is
    the model's, its force the material's. In the paper's units 7.9 N is 530 f0.
    """

    diameter: float = 0.14e-3
    line_density: float = 15.8e-6
    young_modulus: float = 1.88e9
    poisson_ratio: float = 0.4
    stitch_length: float = 9.74e-3
    breaking_force: float = 7.9
    bending_rigidity: float | None = None
    torsional_rigidity: float | None = None

    def __post_init__(self) -> None:
        for name in ("diameter", "line_density", "young_modulus", "stitch_length", "breaking_force"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"Material.{name} must be a positive finite number, got {value!r}")
        for name in ("bending_rigidity", "torsional_rigidity"):
            value = getattr(self, name)
            if value is not None and not (value > 0 and math.isfinite(value)):
                raise ValueError(f"Material.{name} must be None or a positive finite number, got {value!r}")
        if not (-1.0 < self.poisson_ratio <= 0.5):
            raise ValueError(f"Material.poisson_ratio must lie in (-1, 0.5], got {self.poisson_ratio!r}")

    # --- SI derived properties
    @property
    def area(self) -> float:
        """Cross-section pi d^2 / 4 [m^2]."""
        return math.pi * self.diameter**2 / 4.0

    @property
    def stretching_stiffness(self) -> float:
        """E A [N]."""
        return self.young_modulus * self.area

    @property
    def bending_stiffness(self) -> float:
        """B = E pi d^4 / 64 [N m^2] (paper: 3.55e-8 N m^2 for the Nylon), or the measured bending_rigidity."""
        if self.bending_rigidity is not None:
            return self.bending_rigidity
        return self.young_modulus * math.pi * self.diameter**4 / 64.0

    @property
    def twisting_stiffness(self) -> float:
        """G J = E/(2(1+nu)) * pi d^4/32 = B/(1+nu) [N m^2], or the measured torsional_rigidity."""
        if self.torsional_rigidity is not None:
            return self.torsional_rigidity
        return self.bending_stiffness / (1.0 + self.poisson_ratio)

    @property
    def density(self) -> float:
        """Volumetric density rho_L / A [kg/m^3]."""
        return self.line_density / self.area

    @property
    def axial_wave_speed(self) -> float:
        """c_E = sqrt(E / rho) [m/s] (about 1350 m/s for the Nylon)."""
        return math.sqrt(self.young_modulus / self.density)

    # --- the paper's scales
    @property
    def kappa0(self) -> float:
        """kappa0 = 2 pi / l0 [1/m]: curvature of a circle of perimeter l0."""
        return 2.0 * math.pi / self.stitch_length

    @property
    def f0(self) -> float:
        """f0 = B kappa0^2 [N] (paper: 14.8 mN)."""
        return self.bending_stiffness * self.kappa0**2

    @property
    def c_b(self) -> float:
        """c_b = kappa0 sqrt(B / rho_L) [m/s] (paper: 30.6 m/s)."""
        return self.kappa0 * math.sqrt(self.bending_stiffness / self.line_density)

    @property
    def t_b(self) -> float:
        """Bending time l0 / c_b [s]."""
        return self.stitch_length / self.c_b

    def with_(self, **changes: float) -> "Material":
        """A copy with some fields changed: removed in 0.2.0 without notice, back as a deprecated alias of
        ``dataclasses.replace(material, ...)`` until 0.4.0."""
        warnings.warn("Material.with_ is deprecated since knitlad 0.2.0: use dataclasses.replace(material, ...)",
                      DeprecationWarning, stacklevel=2)
        return replace(self, **changes)


NYLON = Material()
"""The paper's Nylon monofilament (Monofil Madeira): d = 0.14 mm, rho_L = 15.8 mg/m,
E = 1.88 GPa, l0 = 9.74 mm (d/l0 = 1/70). nu = 0.4 is our assumption (typical of
polyamide); it only enters the twist modulus. The friction coefficient is a setting of
each run (the paper's 0.4 by default), not of the material: a run stretches at mu = 0."""


@dataclass(frozen=True)
class Scales:
    """The paper's dimensionless conversions for one material and fabric.

    ``n_y`` is the number of courses (threads) carrying the tension F_x.
    """

    material: Material = field(default_factory=Material)

    def tension_per_thread(self, force_x_newton: float, n_y: int) -> float:
        """f_x = F_x / (n_y f0), F_x in newtons."""
        return force_x_newton / (n_y * self.material.f0)

    def force_from_tension(self, f_x: float, n_y: int) -> float:
        """F_x [N] = f_x n_y f0."""
        return f_x * n_y * self.material.f0

    def length_over_l0(self, length_m: float) -> float:
        return length_m / self.material.stitch_length

    def length_from_l0(self, ratio: float) -> float:
        return ratio * self.material.stitch_length

    def velocity_over_cb(self, velocity_m_s: float) -> float:
        return velocity_m_s / self.material.c_b

    def velocity_from_cb(self, ratio: float) -> float:
        return ratio * self.material.c_b

    def as_attributes(self) -> dict[str, float]:
        """Scales to write into every output file (SI units in the key names)."""
        m = self.material
        return {
            "d_m": m.diameter,
            "rho_L_kg_per_m": m.line_density,
            "E_Pa": m.young_modulus,
            "B_N_m2": m.bending_stiffness,
            "GJ_N_m2": m.twisting_stiffness,
            "breaking_force_N": m.breaking_force,
            "l0_m": m.stitch_length,
            "kappa0_per_m": m.kappa0,
            "f0_N": m.f0,
            "c_b_m_per_s": m.c_b,
            "internal_length_m": LENGTH,
            "internal_mass_kg": MASS,
            "internal_time_s": TIME,
        }


# a result in the paper's units, read from its name: a tension per thread (f0), a velocity over c_b, a length over l0
_TENSION = re.compile(r"(^|_)f([xy])(_|$)")


def si_twin(key: str) -> tuple[str, str] | None:
    """The name and SI unit of the twin of the result ``key`` in the paper's units, or None: a tension per thread
    ``..fx..`` -> ``..force..`` + ``_N`` (``fy`` -> ``force_y``), ``.._over_cb`` -> ``.._m_s``, ``.._over_l0`` ->
    ``.._mm``."""
    if key.endswith("_over_cb"):
        return key[: -len("_over_cb")] + "_m_s", "m/s"
    if key.endswith("_over_l0"):
        return key[: -len("_over_l0")] + "_mm", "mm"
    if _TENSION.search(key) and not key.endswith(("_runs", "_N")):
        return _TENSION.sub(lambda m: f"{m[1]}force{'_y' if m[2] == 'y' else ''}{m[3]}", key, count=1) + "_N", "N"
    return None


def si_twin_meanings(results: dict[str, tuple[str, str]], threads: str) -> dict[str, tuple[str, str]]:
    """The (unit, meaning) of the SI twin of each result in ``results`` (key -> (unit, meaning)) that has one;
    ``threads``: what a tension per thread is multiplied by, in words ("n_y")."""
    out = {}
    for key, (unit, _meaning) in results.items():
        twin = si_twin(key)
        if twin is None or unit not in ("f0", "c_b", "l0"):
            continue
        name, si = twin
        how = {"f0": f"{key} x {threads} f0: the pull", "c_b": f"{key} x c_b", "l0": f"{key} x l0"}[unit]
        out[name] = (si, f"{how}, in {si}")
    return out


def si_twins(results: dict, material: Material, threads: int, units_of: dict[str, tuple[str, str]]) -> dict:
    """The SI twins (:func:`si_twin`) of the results in the paper's units, for ``material`` on ``threads``
    threads; ``units_of``: each result's (unit, meaning), which says which results are in f0, c_b or l0."""
    factor = {"f0": threads * material.f0, "c_b": material.c_b, "l0": material.stitch_length * 1e3}
    out = {}
    for key, value in results.items():
        unit = units_of.get(key, ("-",))[0]
        twin = si_twin(key)
        if twin is not None and unit in factor and isinstance(value, (int, float)) and not isinstance(value, bool):
            out[twin[0]] = value * factor[unit]
    return out
