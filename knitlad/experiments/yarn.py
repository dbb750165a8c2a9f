"""A yarn in a textile engineer's units: a YAML file (``--yarn my_yarn.yaml``, ``yarn:`` in a config) or its fields,
made into the rod's :class:`~knitlad.engine.units.Material` once the knit's stitch length is known.

    name: Nylon monofilament 0.14 mm
    source: Faulconnier et al. 2026, "Laddering of a knitted fabric", Materials and methods
    diameter_mm: 0.14
    linear_density_tex: 15.8          # g/km; or density_kg_m3
    young_modulus_GPa: 1.88           # the tensile modulus (E A = E pi d^2/4)
    bending_rigidity_N_m2: null       # none: E pi d^4/64, a monofilament's; give it for a multifilament
    poisson_ratio: 0.4                # or torsional_rigidity_N_m2
    friction: 0.4                     # yarn on yarn, the laddering's mu unless a run sets mu
    breaking_force_N: 7.9
    loss_factor: null                 # the material's, the laddering's loss_factor unless a run sets it

A multifilament or spun yarn bends far more easily than a solid rod of its diameter and modulus: its fibres slide
on each other, so that B lies between the fibres' sum and the solid rod's (Hearle, Grosberg & Backer, *Structural
Mechanics of Fibers, Yarns, and Fabrics*, 1969, ch. 12). Give such a yarn its measured bending rigidity; its modulus
then sets only the stretching.
"""

from __future__ import annotations

import math
from pathlib import Path

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from knitlad.engine.units import NYLON, Material

MAX_YARN_FILE_BYTES = 64_000  # a yarn file is a dozen lines; anything larger is not one


class YarnError(ValueError):
    """A yarn file that cannot be read or is not a yarn: its one-line reason."""


class Yarn(BaseModel):
    """One yarn's properties, each in the unit its name ends with."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    name: str = Field("", max_length=200, description="what the yarn is [-]")
    source: str = Field("", max_length=1000, description="where its values come from [-]")
    diameter_mm: float = Field(gt=0, le=5, description="the yarn's diameter d, as the contact sees it [mm]")
    linear_density_tex: float | None = Field(None, gt=0, le=100_000, description=(
        "linear density rho_L [tex = g/km]; or density_kg_m3"))
    density_kg_m3: float | None = Field(None, gt=0, le=30_000, description=(
        "the material's density, rho_L = density pi d^2/4 [kg/m^3]; or linear_density_tex"))
    young_modulus_GPa: float = Field(gt=0, le=1000, description=(
        "tensile modulus E, the stretching stiffness E pi d^2/4 [GPa]"))
    bending_rigidity_N_m2: float | None = Field(None, gt=0, le=1.0, description=(
        "bending rigidity B [N m^2]; none: E pi d^4/64 (a solid round monofilament)"))
    poisson_ratio: float | None = Field(None, gt=-1, le=0.5, description=(
        "Poisson's ratio nu, the twist rigidity B/(1 + nu) [-]; none: 0.4, or torsional_rigidity_N_m2"))
    torsional_rigidity_N_m2: float | None = Field(None, gt=0, le=1.0, description=(
        "torsional rigidity G J [N m^2]; or poisson_ratio"))
    friction: float | None = Field(None, ge=0, le=2, description=(
        "yarn-on-yarn friction coefficient: the laddering's mu unless a run gives mu [-]"))
    breaking_force_N: float = Field(gt=0, le=10_000, description="the force at which the yarn breaks [N]")
    loss_factor: float | None = Field(None, ge=0, le=1, description=(
        "the material's loss factor tan(delta): the runs' loss_factor unless a run gives it [-]"))

    @model_validator(mode="after")
    def one_of_each_pair(self) -> "Yarn":
        if (self.linear_density_tex is None) == (self.density_kg_m3 is None):
            raise ValueError("give linear_density_tex or density_kg_m3, one of them")
        if self.poisson_ratio is not None and self.torsional_rigidity_N_m2 is not None:
            raise ValueError("give poisson_ratio or torsional_rigidity_N_m2, not both")
        return self

    @property
    def diameter_m(self) -> float:
        return self.diameter_mm * 1e-3

    @property
    def line_density_kg_m(self) -> float:
        """rho_L [kg/m] (1 tex = 1e-6 kg/m)."""
        if self.linear_density_tex is not None:
            return self.linear_density_tex * 1e-6
        return self.density_kg_m3 * math.pi * self.diameter_m**2 / 4

    def material(self, stitch_length_m: float) -> Material:
        """The rod's material for a knit of stitch length l0 [m] (which sets the paper's scales)."""
        nu = self.poisson_ratio if self.poisson_ratio is not None else NYLON.poisson_ratio
        return Material(diameter=self.diameter_m, line_density=self.line_density_kg_m,
                        young_modulus=self.young_modulus_GPa * 1e9, poisson_ratio=nu,
                        stitch_length=stitch_length_m, breaking_force=self.breaking_force_N,
                        bending_rigidity=self.bending_rigidity_N_m2, torsional_rigidity=self.torsional_rigidity_N_m2)


PAPER_NYLON = Yarn(
    name="Nylon monofilament 0.14 mm (Monofil Madeira)",
    source="Faulconnier et al. 2026 (d, rho_L, E, mu); Morton & Hearle 2008 (breaking force, 50 cN/tex)",
    diameter_mm=0.14, linear_density_tex=15.8, young_modulus_GPa=1.88, poisson_ratio=0.4, friction=0.4,
    breaking_force_N=7.9)
"""The paper's yarn, as ``configs/yarns/nylon_paper.yaml`` gives it (its material at 9.74 mm is
:data:`knitlad.engine.units.NYLON`: tests/experiments/test_yarn.py)."""


def read_yarn(path: str | Path) -> Yarn:
    """A yarn file, validated; every problem is a :class:`YarnError` of one line naming the file and the field."""
    path = Path(path)
    try:
        if path.is_dir():
            raise YarnError(f"{path}: a folder, not a yarn file")
        with open(path, "rb") as f:
            raw = f.read(MAX_YARN_FILE_BYTES + 1)
    except OSError as e:
        raise YarnError(f"{path}: cannot read ({e.strerror or e})") from None
    if len(raw) > MAX_YARN_FILE_BYTES:
        raise YarnError(f"{path}: larger than {MAX_YARN_FILE_BYTES // 1000} kB, not a yarn file")
    try:
        data = yaml.safe_load(raw.decode("utf-8"))
    except (UnicodeDecodeError, yaml.YAMLError) as e:
        raise YarnError(f"{path}: not a YAML text ({getattr(e, 'problem', None) or e})") from None
    if not isinstance(data, dict):
        raise YarnError(f"{path}: a yarn file is a mapping of its properties (diameter_mm, ...)")
    try:
        return Yarn.model_validate(data)
    except ValidationError as e:
        raise YarnError(f"{path}: {reasons(e)}") from None


def reasons(error: ValidationError, most: int = 3) -> str:
    """A yarn's validation errors as 'field: reason; field: reason' (the first ``most``)."""
    said = [f"{'.'.join(map(str, e.get('loc', ()))) or 'yarn'}: {e['msg'].removeprefix('Value error, ')}"
            for e in error.errors()[:most]]
    return "; ".join(dict.fromkeys(said))


def yarn_of(value) -> Yarn | dict | None:
    """A config's ``yarn``: a file's path is read (a :class:`YarnError` if it cannot be), a mapping or a Yarn kept
    for pydantic to validate."""
    if isinstance(value, (str, Path)):
        return read_yarn(value)
    return value
