"""Validated configuration (pydantic v2, extra="forbid"): units in every field's description.

Dimensionless inputs follow the paper: lengths as l/l0, tension as f_x = F_x/(n_y f0).
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Annotated, ClassVar, Literal, get_args, get_origin

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, model_validator

from knitlad.engine.contact import HELD_FRICTION_REMOVED, KNIT_CONTACT_FORCE_F0, KNIT_OVERLAP
from knitlad.engine.deprecation import removed_argument
from knitlad.engine.dissipation import STITCH_BENDING_HZ
from knitlad.engine.kernels.contact_law import LAWS, law_mode
from knitlad.fabric.observers import AUTO_FRAMES
from knitlad.fabric.patterns import PATTERNS
from knitlad.fabric.presets import LADDER_PRESETS, LOOP_PRESETS, PRESET_HELP, STITCH_PRESETS
from knitlad.experiments.yarn import Yarn

Preset = Literal[tuple(LADDER_PRESETS)]  # fast, default, accurate, and the authors' engine (crassous2023)

# a field given in a unit of its own and the SI unit its settings take it in: one stem, the unit's suffix
# (max_time_ms -> max_time_s, pin_radius_mm -> pin_radius_m); every other setting has one name throughout
SI_SUFFIXES = {"_us": ("_s", 1e-6), "_ms": ("_s", 1e-3), "_mm": ("_m", 1e-3)}


def in_si(name: str, value):
    """(the settings' name, the value) of the config field ``name``: its SI twin if it is in us, ms or mm."""
    for suffix, (si, factor) in SI_SUFFIXES.items():
        if name.endswith(suffix):
            return name[: -len(suffix)] + si, None if value is None else value * factor
    return name, value


# a preset's setting not filled where the run gives another way to set the same (a drag per second, not lambda)
PRESET_ALTERNATIVES = {"drag_lambda": ("drag_per_s",)}


class _WithPreset(BaseModel):
    """A run whose resolution (and the settings beside it in ``PRESETS``) default to its accuracy preset's."""

    # no NaN or infinity in any number: a bad value is named as such, not as out of range
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    PRESETS: ClassVar[dict[str, dict]] = LADDER_PRESETS
    # the fields that reach the settings made into another value (field -> what it becomes); every other field
    # reaches them under its own name (tests/experiments/test_config.py)
    COMPOSED: ClassVar[dict[str, str]] = {"preset": "the resolution and the settings beside it (PRESETS)"}

    preset: Preset = Field("default", description=PRESET_HELP)

    def replace(self, **changes):
        """A copy with ``changes``, validated as a new config is (``model_copy(update=...)`` skips validation:
        ``mu=-1`` would pass). A new ``preset`` brings its own settings in place of the old preset's (a
        setting that differs from the old preset's value was given, and stays)."""
        data = self.model_dump()
        for name in derived_from(changes, data, getattr(self, "yarn", None)):
            data.pop(name, None)  # made again from the changed yarn or knit
        if "preset" in changes and changes["preset"] != self.preset:
            old = self.PRESETS.get(self.preset, {})
            data = {k: v for k, v in data.items() if not (k in old and v == old[k] and k not in changes)}
        return type(self).model_validate({**data, **changes})

    def settings_of(self, settings_type, **composed):
        """``settings_type`` (a frozen settings dataclass) filled from this config: each of its fields the config
        declares under the same name (or in us, ms or mm: :func:`in_si`), then ``composed``, the values made of
        several fields or of none (the material of d_over_l0, a band). A setting is declared here once, with
        its default and unit; the settings carry it under the same name to the kernels."""
        wanted = {f.name for f in dataclasses.fields(settings_type)}
        values = dict(in_si(name, getattr(self, name)) for name in type(self).model_fields)
        return settings_type(**{**{name: v for name, v in values.items() if name in wanted}, **composed})

    @classmethod
    def preset_fields(cls) -> tuple[str, ...]:
        """The settings a preset fills (the keys of the presets' tables), in their order."""
        return tuple(dict.fromkeys(key for table in cls.PRESETS.values() for key in table))

    @model_validator(mode="before")
    @classmethod
    def preset_settings(cls, data):
        """Fill each setting of the preset not given, so a resolved config names what it ran with."""
        if isinstance(data, dict) and data.get("preset", "default") in cls.PRESETS:
            chosen = cls.PRESETS[data.get("preset", "default")]
            given = {k for k, v in data.items() if v is not None}
            data = {**data, **{k: v for k, v in chosen.items()
                               if data.get(k) is None and not given & set(PRESET_ALTERNATIVES.get(k, ()))}}
        return data

    @model_validator(mode="before")
    @classmethod
    def no_bool_for_numbers(cls, data):
        """``n_x: true`` is a mistake, not 1, and ``mu: "0.4"`` or ``twist: "yes"`` (quoted in YAML) are text:
        a yes/no is taken only where the field is one, text only where it is a choice of words."""
        if isinstance(data, dict):
            for name, value in data.items():
                field = cls.model_fields.get(name)
                if field is None:
                    continue
                kinds = (field.annotation, *get_args(field.annotation))
                if any(isinstance(k, type) and issubclass(k, BaseModel) for k in kinds):
                    continue  # a yarn: a file's path or its mapping (the_yarn_and_its_knit)
                if isinstance(value, bool) and bool not in kinds:
                    raise ValueError(f"{name}: a number is needed, got {value!r}")
                if isinstance(value, str) and str not in kinds and not any(get_origin(k) is Literal for k in kinds):
                    wanted = "true or false" if bool in kinds else "a number"
                    raise ValueError(f"{name}: {wanted} is needed, got the text {value!r}")
        return data


def _known_law(name: str) -> str:
    law_mode(name)
    return name


# a law's name, checked against the kernels' table (a new law is known here without an edit)
ContactLawName = Annotated[str, AfterValidator(_known_law)]


PatternName = Literal[tuple(PATTERNS)]  # the knit patterns' names (knitlad.fabric.patterns)
KNITTED_BANDS = tuple(name for name in PATTERNS if name != "jersey")  # a band knitted in another pattern
BandName = Literal[("friction", "curvature") + KNITTED_BANDS]


def _contact_law():
    return Field("linear", description=(
        f"the contact's normal spring through its working point (contact_force_f0 at overlap_fraction d): "
        f"{' or '.join(LAWS)}; linear is a penalty, f ~ delta, hertz crossed elastic cylinders, f ~ delta^3/2 "
        "(knitlad.engine.kernels.contact_law) [-]"))


def _stitches_per_course(default: int):
    return Field(default, ge=4, le=200, description="stitches per course [-]")


def _courses(default: int):
    return Field(default, ge=4, le=200, description="courses [-]")


def _yarn():
    return Field(None, description=(
        "the yarn: a YAML file of its properties (configs/yarns/; knitlad.experiments.yarn) or, in a config, "
        "their mapping; none: the paper's Nylon [-]"))


def _stitch_length_mm():
    return Field(None, gt=0, le=200, description=(
        "the knit's stitch length l0, yarn per stitch, with the yarn's diameter setting d_over_l0 [mm]; none: "
        "9.74 mm for the paper's Nylon, the yarn's diameter over d_over_l0 for another yarn"))


# the authors' engine's model (preset crassous2023, knitlad.fabric.presets): its drag and its contact dashpot
def _drag_lambda():
    return Field(None, ge=0, le=1, description=(
        "the global drag in the authors' engine's units (its f = -lambda dx/dt on nodes of mass 1 a yarn's radius "
        "apart): gamma = lambda / (r sqrt(rho_L/EA)), 1.94e7 lambda /s for the paper's Nylon; their README's "
        "range 1e-4 to 1e-3; instead of drag; default: the preset's (docs/paper_claims.md) [-]"))


def _spin_drag():
    return Field(False, description=(
        "the global drag also damps each yarn's spin about its axis at the same rate, -gamma I omega (the "
        "authors' engine damps the twist rate with the same lambda); needs twist [-]"))


def _contact_dashpot():
    return Field("critical", description=(
        "the contact dashpots of the laddering: critical (contact_damping_ratio of critical, normal and "
        "tangential) or absolute (the authors' engine: a normal dashpot sqrt(EA rho_L) per contact whatever the "
        "resolution, none along the surface; contact_damping_ratio not used) [-]"))


KNIT_SOURCES = ("yarn", "stitch_length_mm", "wales_per_cm", "courses_per_cm")
MAX_D_OVER_L0 = 0.1  # d_over_l0's bound: a jersey tighter than this jams before it is knitted
NYLON_DIAMETER_MM = 0.14
NYLON_STITCH_LENGTH_MM = 9.74


def the_yarn_and_its_knit(data: dict, fields) -> dict:
    """A config's yarn and stitch length made into what the model reads: the yarn read from its file, d_over_l0 =
    d/l0, mu and loss_factor from the yarn where the config gives none, and the stretch l_x, l_y from wales and
    courses per cm (l_x = 10 mm / wales per cm). A value given twice must agree; every refusal names its field."""
    from knitlad.experiments.yarn import YarnError, reasons, yarn_of

    if not any(data.get(name) is not None for name in KNIT_SOURCES):
        return data
    data = dict(data)
    try:
        yarn = yarn_of(data.get("yarn"))
        if isinstance(yarn, dict):
            yarn = Yarn.model_validate(yarn)
    except YarnError as e:
        raise ValueError(f"yarn: {e}") from None
    except ValidationError as e:
        raise ValueError(f"yarn: {reasons(e)}") from None
    if yarn is not None:
        data["yarn"] = yarn
    d_mm = yarn.diameter_mm if yarn is not None else NYLON_DIAMETER_MM
    given_ratio = data.get("d_over_l0")
    if data.get("stitch_length_mm") is not None:
        l0_mm = float(data["stitch_length_mm"])
        ratio = d_mm / l0_mm
        if ratio > MAX_D_OVER_L0:
            raise ValueError(f"stitch_length_mm: a yarn of {d_mm:g} mm at {l0_mm:g} mm per stitch is d/l0 = "
                             f"{ratio:.3g}; a jersey cannot be knitted tighter than d/l0 = {MAX_D_OVER_L0:g} "
                             f"(a stitch length of at least {d_mm / MAX_D_OVER_L0:.3g} mm)")
        if given_ratio is not None and not math.isclose(given_ratio, ratio, rel_tol=1e-9):
            raise ValueError(f"d_over_l0: {given_ratio:.6g}, but the yarn's {d_mm:g} mm at stitch_length_mm "
                             f"{l0_mm:g} is {ratio:.6g}: give one of them")
        data["d_over_l0"] = ratio
    elif yarn is not None:
        if given_ratio is None:
            raise ValueError("stitch_length_mm: a yarn needs its knit's stitch length (or d_over_l0)")
        data["stitch_length_mm"] = d_mm / given_ratio
    # wales or courses per cm of the paper's yarn alone: its stitch length, d_over_l0 setting its diameter
    l0_mm = float(data.get("stitch_length_mm") or NYLON_STITCH_LENGTH_MM)
    if yarn is not None:
        for name, value in (("mu", yarn.friction), ("loss_factor", yarn.loss_factor)):
            if value is not None and data.get(name) is None and name in fields:
                data[name] = value
    for count, stretch, others in (("wales_per_cm", "lx", ("fx",)), ("courses_per_cm", "ly", ())):
        if data.get(count) is None:
            continue
        ratio = 10.0 / (float(data[count]) * l0_mm)  # (10 mm / count) / l0
        if data.get(stretch) is not None and not math.isclose(data[stretch], ratio, rel_tol=1e-9):
            raise ValueError(f"{count}: {data[count]:g} per cm at a stitch length of {l0_mm:g} mm is {stretch} = "
                             f"{ratio:.4g}, but {stretch} is {data[stretch]:g}: give one of them")
        for other in others:
            if data.get(other) is not None:
                raise ValueError(f"{count}: sets {stretch} (position control); give it or {other}, not both")
        data[stretch] = ratio
    return data


def derived_from(changes: dict, data: dict, old_yarn) -> tuple[str, ...]:
    """The fields of a config's dump (``data``) that :func:`the_yarn_and_its_knit` made from the sources a
    ``replace(**changes)`` changes: dropped, to be made again (unless the change gives them itself)."""
    drop = []
    knit = any(name in changes for name in ("yarn", "stitch_length_mm", "d_over_l0"))
    if knit and "d_over_l0" not in changes and data.get("stitch_length_mm") is not None:
        drop.append("d_over_l0")
    if "d_over_l0" in changes and "stitch_length_mm" not in changes:
        drop.append("stitch_length_mm")
    if "yarn" in changes and old_yarn is not None:
        for name, value in (("mu", old_yarn.friction), ("loss_factor", old_yarn.loss_factor)):
            if value is not None and data.get(name) == value:
                drop.append(name)
    for count, stretch in (("wales_per_cm", "lx"), ("courses_per_cm", "ly")):
        if data.get(count) is not None and (knit or count in changes):
            drop.append(stretch)
    return tuple(name for name in drop if name not in changes)


def material_of(cfg):
    """The rod's material of a config: its yarn at its stitch length, or the paper's Nylon (material_for)."""
    from knitlad.engine.units import NYLON

    if cfg.yarn is not None:
        return cfg.yarn.material(cfg.stitch_length_mm * 1e-3)
    if cfg.stitch_length_mm is not None:
        return dataclasses.replace(NYLON, stitch_length=cfg.stitch_length_mm * 1e-3)
    return material_for(cfg.d_over_l0)


class _YarnAndKnit:
    """A config's yarn and stitch length (its fields ``yarn``, ``stitch_length_mm``; knitlad.experiments.yarn): made
    into d_over_l0 and, where the config has them, mu, loss_factor, lx and ly (:func:`the_yarn_and_its_knit`); the
    rod's material from them."""

    @model_validator(mode="before")
    @classmethod
    def yarn_and_knit(cls, data):
        return the_yarn_and_its_knit(data, cls.model_fields) if isinstance(data, dict) else data

    def material(self):
        """The rod's material: the yarn at the stitch length, or the paper's Nylon."""
        return material_of(self)


class CutConfig(_WithPreset, _YarnAndKnit):
    """One laddering run (``knitlad cut``, sweep scene ``ladder``): the one declaration of each of its settings.

    The first group are the options of ``knitlad cut``; the second the model's choices,
    each a measurement (README, docs/accuracy.md), settable from Python and sweeps.
    """

    # fields added after sweeps of this scene were first run: at their default they stay out
    # of a job's id (knitlad.studies.sweep.job_id), so a finished job keeps its id and is not run again
    ADDED_LATER: ClassVar[tuple[str, ...]] = (
        "drag_per_s", "twist", "d_over_l0", "contact_force_f0", "overlap_fraction", "contact_counting", "edge",
        "contact_damping_ratio", "stretch_damping_ratio", "stretch_increment", "steps_per_increment",
        "fx_tolerance", "dt_safety", "stretch_start", "natural_curvature", "axial_stiffness_factor",
        "twist_inertia_factor", "framed_twist", "implicit_axial", "predicted_dashpots", "memory_peak_ratio",
        "stop_at_edge", "loss_factor", "loss_peak_hz", "air_drag", "stop_after_stitches", "contact_law",
        "band_row", "band_courses", "band_friction_factor", "pattern", "band", "band_curvature", "bars",
        "clip_friction", "knit_seed", "drag_lambda", "spin_drag", "contact_dashpot", *KNIT_SOURCES)
    # fields added here after the experiments built on this config (cycle, tensile, snag, resistance) had run
    # sweeps: at their default they stay out of those scenes' job ids too (their ADDED_LATER lists their own)
    ADDED_LATER_FOR_ALL: ClassVar[tuple[str, ...]] = ("band_curvature", "bars", "clip_friction", "knit_seed",
                                                      "drag_lambda", "spin_drag", "contact_dashpot", *KNIT_SOURCES)
    COMPOSED: ClassVar[dict[str, str]] = {
        "preset": "the resolution and the settings beside it (PRESETS)",
        "d_over_l0": "material (material_of)",
        "drag_lambda": "drag_per_s (knitlad.engine.dissipation.authors_drag_per_s)",
        **{name: "material (material_of), d_over_l0, mu, loss_factor, lx, ly" for name in KNIT_SOURCES},
        **{band: "pattern_band, memory_band or friction_band" for band in (
            "band", "band_row", "band_courses", "band_friction_factor", "band_curvature")},
    }

    fx: float | None = Field(None, gt=0, le=40, description="target tension per thread f_x^ini = F_x/(n_y f0) [-] (force control)")
    lx: float | None = Field(None, gt=0.2, lt=1.0, description="stretch l_x/l0 [-] (position control, instead of fx)")
    ly: float = Field(0.25, gt=0.2, lt=0.5, description="stretch l_y/l0 [-]")
    mu: float = Field(0.4, ge=0, le=2, description="yarn-yarn friction coefficient during laddering [-]")
    n_x: int = _stitches_per_course(42)
    n_y: int = _courses(42)
    pattern: PatternName = Field("jersey", description=(
        "the knit's pattern: jersey (the paper's), rib (1x1: knit and purl columns) or garter (knit and purl "
        "courses); rib and garter are stretched affinely from a narrower build (docs/patterns.md) [-]"))
    resolution: int | None = Field(None, ge=12, le=280, description="nodes per stitch (segment = l0/resolution) [-]; default: the preset's")
    max_time_ms: float = Field(30.0, gt=0, description="longest laddering time simulated after the cut [ms]")
    arrest_ms: float = Field(2.0, gt=0, description="the ladder has stopped when no cell changed for this long [ms]")
    observe_every_us: float = Field(20.0, gt=0, description="interval between front/tension samples [us]")
    frame_every_us: float | None = Field(None, gt=0, description=(
        "interval between stored frames (positions, velocities, laddered cells) [us]; default: 1/60 of the "
        "ladder's expected duration, n_y l_y / 2 over the paper's velocity 0.1 f_x^ini c_b, for a movie of 50+ frames"))
    drag_per_s: float = Field(0.0, ge=0, le=1e5, json_schema_extra={"cli": "--drag"}, description=(
        "global drag -gamma m v on every node during the laddering [1/s]: the damping of the paper's engine, "
        "not physics (0: none; docs/dissipation.md)"))
    drag_lambda: float | None = _drag_lambda()
    spin_drag: bool = _spin_drag()
    loss_factor: float = Field(0.0, ge=0, le=1, description=(
        "the yarn's material damping: peak loss factor of its viscoelasticity, a standard linear solid in "
        "stretching and bending [-]; Nylon: 0.03 (0.01 dry to 0.1 humid); 0: none (docs/dissipation.md)"))
    loss_peak_hz: float = Field(STITCH_BENDING_HZ, gt=0, le=1e7, description=(
        "frequency of the material damping's loss peak [Hz]; default: a stitch's bending wave, c_b kappa0 / 2 pi"))
    air_drag: bool = Field(False, json_schema_extra={"cli": "--air"}, description=(
        "still air around the yarns during the laddering: a cylinder's cross-flow drag at its Reynolds number "
        "and a skin friction along it [-] (docs/dissipation.md)"))
    stop_after_stitches: int | None = Field(None, ge=3, le=200, description=(
        "stop once a front has run this many stitches from the cut row [-]: enough for v_lad when above 10, "
        "at a fraction of the cost; n_lad/n_y and f_x^fin are then those of that moment; none: not"))
    twist: bool = Field(False, description=(
        "the yarns carry twist during the laddering, so friction also turns them (the friction couple) [-]; "
        "costs more (docs/performance.md)"))
    band_row: int | None = Field(None, ge=0, le=199, description=(
        "a run-stop band: its first course, counted from the bottom (the cut is at n_y // 2) [-]; none: no band"))
    band_courses: int = Field(2, ge=1, le=200, description="courses of the run-stop band [-]")
    band: BandName = Field("friction", description=(
        "what the run-stop band is: courses of a yarn with more friction (band_friction_factor), of a yarn "
        "that remembers its knitted shape (band_curvature; twist on, tiled stretch), or courses knitted in rib "
        "or garter (the fabric's friction: band_friction_factor is not used; stretched affinely) [-]"))
    band_friction_factor: float = Field(2.0, ge=0, le=10, description=(
        "the band's yarn friction over the fabric's: a contact touching a band course has this factor x mu "
        "during the laddering [-]"))
    band_curvature: float = Field(1.0, gt=0, le=20, description=(
        "a curvature band's memory: mean (kappa_bar/kappa0)^2 of its courses' natural curvature, as "
        "natural_curvature is the rest of the knit's [-]"))
    # --- the model's choices
    d_over_l0: float = Field(1 / 70, gt=0, le=0.1, description=(
        "yarn diameter over stitch length d/l0 [-]; 1/70, the paper's rounded value and the default, means its "
        "Nylon itself: d = 0.14 mm with l0 = 9.74 mm, d/l0 = 0.01437 (knitlad.experiments.config.material_for)"))
    contact_force_f0: float = Field(KNIT_CONTACT_FORCE_F0, gt=0, description=(
        "contact stiffness: a contact carrying this force overlaps by overlap_fraction d [f0]"))
    overlap_fraction: float = Field(KNIT_OVERLAP, gt=0, lt=1, description="overlap at contact_force_f0, over d [-]")
    yarn: Yarn | None = _yarn()
    stitch_length_mm: float | None = _stitch_length_mm()
    wales_per_cm: float | None = Field(None, gt=0, le=100, description=(
        "the stretched knit's wales per cm: l_x = 10 mm / wales_per_cm, position control instead of lx [1/cm]"))
    courses_per_cm: float | None = Field(None, gt=0, le=100, description=(
        "the stretched knit's courses per cm: l_y = 10 mm / courses_per_cm, instead of ly [1/cm]"))
    sagitta_radius: float | None = Field(None, ge=0, le=1000, description=(
        "the contact's sagitta correction: each segment's contact radius is r - l^2/(12 R), R this many yarn "
        "diameters (the stitch's contacts' radius of curvature), l the segment; 0: capsules of the yarn's "
        "radius [d]; default: the preset's"))
    contact_law: ContactLawName = _contact_law()
    contact_counting: Literal["union", "all_pairs"] = Field("union", description=(
        "contact counting of the laddering dynamics: union (exact friction) or all_pairs (conserves energy) [-]"))
    edge: Literal["clamped", "tail", "continuous"] = Field("clamped", description=(
        "course ends: clamped at the edge sinkers, held at tails, or continuous (one yarn turning in clips) [-]"))
    bars: Literal["held", "sliding"] = Field("held", description=(
        "the courses below and above: held, or sliding along x (the experiment's clips on its bars) [-]"))
    clip_friction: float = Field(0.0, ge=0, le=2, description=(
        "Coulomb coefficient of the clips on their bars (sliding bars, the continuous edge), on at the cut [-]"))
    knit_seed: int | None = Field(None, ge=0, strict=True, description=(
        "a knit of an ensemble: after the stretch every free node is displaced across its yarn at random, 0.001 d "
        "rms, drawn from this seed (a sweep's ensemble gives each member its own); none: the knit as stretched [-]"))
    contact_damping_ratio: float = Field(0.3, ge=0, description=(
        "normal and tangential contact dashpots of the laddering dynamics, fraction of critical [-]"))
    contact_dashpot: Literal["critical", "absolute"] = _contact_dashpot()
    stretch_damping_ratio: float = Field(0.2, ge=0, description=(
        "the yarn's axial dashpot during the laddering, fraction of critical [-]"))
    stretch_increment: float = Field(0.005, gt=0, le=0.05, description="affine stretch per relaxation round [l/l0]")
    steps_per_increment: int = Field(750, ge=1, description="FIRE steps per relaxation round [-]")
    fx_tolerance: float = Field(0.02, gt=0, lt=1, description="force control: accepted relative error of f_x^ini [-]")
    natural_curvature: float = Field(0.0, ge=0, le=20, description=(
        "the yarn's memory of its knitted shape: mean (kappa_bar/kappa0)^2 of its natural curvature, a "
        "fraction of the unloaded fabric's curvature (the paper measures ~1, up to 3.5) [-]; > 0 turns twist on"))
    memory_peak_ratio: float | None = Field(None, ge=1, le=50, description=(
        "the memory concentrated at the most bent places (the loop heads): max/mean of (kappa_bar/kappa0)^2 "
        "over the stitch (the paper's thread: about 3.5; default: the scaled copy's own, 1.6) [-]; needs "
        "natural_curvature > 0"))
    stretch_start: Literal["tiled", "affine"] = Field("tiled", description=(
        "how the knit reaches its stretch: tiled with the periodised stitch stretched to the target, "
        "then corrected (clamped ends; tails, and yarns too thick for the stitch, d/l0 = 1/20, affine), or affine increments of the built knit [-]"))
    dt_safety: float = Field(0.35, gt=0, le=1, description=(
        "time step of the laddering dynamics, fraction of the stability limit of the yarns' sliding (rods and "
        "contact springs; with twist the spin modes are only held stable) [-]; default: the preset's, from "
        "paired time-step studies (0.35 at fast and default: docs/accuracy.md; 0.7 at accurate, whose limit "
        "is shorter: docs/performance.md)"))
    axial_stiffness_factor: float = Field(1.0, gt=0, le=1, description=(
        "stretching stiffness of the laddering dynamics over the yarn's EA [-]; below 1 the axial waves "
        "slow down and the step grows as 1/sqrt(factor), every edge keeping its tension at the cut; it "
        "changes v_lad and f_x^fin (docs/accuracy.md)"))
    twist_inertia_factor: float = Field(1.0, ge=1, le=1000, description=(
        "with twist: the yarn's inertia about its axis in the laddering dynamics over rho_L d^2/8 per length [-]; "
        "a setting for studies (the step does not need it); large factors slow the ladder, as the yarns roll "
        "at the contacts (docs/accuracy.md)"))
    framed_twist: bool = Field(False, description=(
        "with twist and no natural curvature: bend and twist through material frames (framed DER, the "
        "averaged material curvature) instead of the frame-free isotropic path (|kb|^2 and the reference "
        "twist by holonomy), whose bent hinges are a little softer in twist (by B |kb|^2 / 4GJ); costlier: "
        "for comparisons [-]"))
    implicit_axial: bool | None = Field(None, description=(
        "the laddering dynamics take the yarn's axial springs and dashpots at the end of each kick "
        "(linearly implicit, a tridiagonal solve per yarn): the axial waves set no limit and the step, "
        "dt_safety x the contact and bending limit, grows; the static tensions are unchanged [-]; "
        "default: the preset's"))
    stop_at_edge: bool = Field(True, description=(
        "stop the run when a ladder reaches an edge course (its damage and f_x^fin are then those of that moment); "
        "false: go on until every front has stopped (or max_time_ms) [-]"))
    predicted_dashpots: bool = Field(False, description=(
        "the laddering dynamics' dashpots (axial and contact) act on the velocity at the end of each step, "
        "predicted from the last forces (second order in dt), instead of the half-step velocity (first order); "
        "their stability limit is lower (0.57 against 0.74 x the undamped one at the contacts' 0.3 of critical) [-]"))

    @model_validator(mode="before")
    @classmethod
    def removed_settings(cls, data):
        """``friction_every``, removed in 0.15.0 (engine/deprecation.removed_argument): 1 warns, any other value is
        refused."""
        if isinstance(data, dict) and "friction_every" in data:
            data = dict(data)
            removed_argument(data, cls.__name__, "friction_every", 1, "0.15.0", HELD_FRICTION_REMOVED)
        return data

    @model_validator(mode="before")
    @classmethod
    def patterns_stretch_affinely(cls, data):
        """A pattern with purl stitches has no periodised stitch to tile: its knit is stretched affinely."""
        knitted_band = isinstance(data, dict) and data.get("band", "friction") in KNITTED_BANDS
        if isinstance(data, dict) and (data.get("pattern", "jersey") != "jersey" or knitted_band) \
                and "stretch_start" not in data:
            data = {**data, "stretch_start": "affine"}
        return data

    @model_validator(mode="before")
    @classmethod
    def natural_curvature_carries_twist(cls, data):
        """A yarn with natural curvature carries twist (its curvature lives in its material frame)."""
        if not isinstance(data, dict):
            return data
        k = data.get("natural_curvature")
        remembers = isinstance(k, (int, float)) and not isinstance(k, bool) and k > 0
        banded = data.get("band") == "curvature" and data.get("band_row") is not None
        if remembers or banded:
            if data.get("twist") is False:
                name = "natural_curvature" if remembers else "band"
                raise ValueError(f"{name}: a yarn with natural curvature carries twist (twist: true)")
            data = {**data, "twist": True}
        return data

    @model_validator(mode="after")
    def one_control(self) -> "CutConfig":
        if self.fx is not None and self.lx is not None:
            raise ValueError("give either fx (force control) or lx (position control), not both")
        if self.fx is None and self.lx is None:
            raise ValueError("give fx (force control) or lx (position control)")
        check_stretch(self)
        check_drag(self)
        check_sagitta(self.resolution, self.d_over_l0, self.sagitta_radius)
        check_band(self)
        check_clips(self)
        check_observations(self)
        return self

    @property
    def nodes(self) -> int:
        """Nodes of the knit: n_y free courses and two held edge courses of n_x stitches each."""
        return (self.n_y + 2) * (self.n_x * self.resolution + 1)

    def memory_estimate_bytes(self) -> int:
        """What a run holds in memory, about: ~2 kB per node (model, state, work arrays and contact
        buffers of 4 pairs per edge) and the position frames (float32) kept until written."""
        frames = int(self.max_time_ms * 1e3 / self.frame_every_us) + 2 if self.frame_every_us else AUTO_FRAMES + 2
        return self.nodes * (2048 + 24 * frames)  # positions and velocities, float32

    def stretch_settings(self):
        from knitlad.fabric.preparation import StretchSettings

        return self.settings_of(
            StretchSettings, material=self.material(),
            pattern_band=(self.band, self.band_row, self.band_courses) if self.knitted_band else None,
            memory_band=self.memory_band)

    @property
    def knitted_band(self) -> bool:
        """A run-stop band knitted in another pattern (not a band of friction or of memory)."""
        return self.band_row is not None and self.band in KNITTED_BANDS

    @property
    def memory_band(self) -> tuple[int, int, float] | None:
        """(first course, courses, K) of a band of yarn that remembers its knitted shape, or None."""
        if self.band_row is None or self.band != "curvature":
            return None
        return (self.band_row, self.band_courses, self.band_curvature)

    def dynamics_settings(self):
        from knitlad.engine.contact import Counting
        from knitlad.experiments.laddering import DynamicsSettings

        return self.settings_of(
            DynamicsSettings, contact_counting=Counting(self.contact_counting), drag_per_s=drag_of(self),
            friction_band=(self.band_row, self.band_courses, self.band_friction_factor)
            if self.band_row is not None and self.band == "friction" else None)

    def settings(self):
        from knitlad.experiments.laddering import LadderSettings

        return LadderSettings(self.stretch_settings(), self.dynamics_settings())


# the bars' settings, shared by protocol B (CycleConfig) and the tensile test (TensileConfig): declared once
def _bar_speed():
    return Field(0.25, gt=0, le=10, description=(
        "speed of each held end away from (or towards) the knit's centre line [m/s]; quasi-static when halving it "
        "changes nothing that counts (16 x 16: 0.5 against 0.25 m/s moves delta l by 2 %, docs/quasistatic.md)"))


def _bar_damping():
    return Field(2e4, gt=0, le=1e7, description=(
        "mass-proportional damping alpha while the bars move and hold [1/s]; biases a reading taken while "
        "moving by alpha M V (knitlad/engine/quasistatic.py)"))


def _readings_per_leg(default: int):
    return Field(default, ge=2, le=10000, description="readings per loading or unloading [-]")


def _hold_ms():
    return Field(5.0, gt=0, le=1000, description="longest hold at the top of the loading, a settle [ms]")


def _hold_tol_f0():
    return Field(1e-3, gt=0, le=1, description="a hold has settled when no free node carries more [f0]")


class CycleConfig(CutConfig):
    """Protocol B (``knitlad cycle``, sweep scene ``cycle``; paper Fig. 4a): the knit stretched at mu = 0 to
    Delta x_min (``fx``, the holding tension, or ``lx``), then cycled with friction on to Delta x_max
    (``lx_max``) and back; a copy is cut at Delta x_max of the last cycle, the uncut twin unloads.
    The laddering's settings are those of ``knitlad cut``."""

    ADDED_LATER: ClassVar[tuple[str, ...]] = ("contact_law",)
    # the laddering's run length and recording, which a pull does not use: not its options, refused if set
    UNUSED: ClassVar[tuple[str, ...]] = ("max_time_ms", "arrest_ms", "observe_every_us", "frame_every_us",
                                         "stop_after_stitches", "stop_at_edge")
    n_x: int = _stitches_per_course(16)  # a loading (a pull) costs many cuts' steps: 16 x 16 unless asked
    n_y: int = _courses(16)
    fx: float | None = Field(None, gt=0, le=40, description=(
        "tension per thread f_x at Delta x_min, where the knit is stretched at mu = 0 [-] (force control; the "
        "experiments' 0.68)"))
    lx: float | None = Field(None, gt=0.2, lt=1.0, description="l_x/l0 at Delta x_min [-] (position control, instead of fx)")
    mu: float = Field(0.4, ge=0, le=2, description="yarn-yarn friction coefficient while cycling and laddering [-]")
    lx_max: float = Field(..., gt=0.2, lt=1.0, description="the box's l_x/l0 at Delta x_max [-]")
    cycles: int = Field(3, ge=1, le=10, description="loading cycles; the cut comes at Delta x_max of the last [-]")
    bar_speed: float = _bar_speed()
    cycle_damping_per_s: float = _bar_damping()
    readings_per_leg: int = _readings_per_leg(20)
    hold_ms: float = _hold_ms()
    hold_tol_f0: float = _hold_tol_f0()
    fx_thr: float | None = Field(None, gt=0, le=40, description=(
        "threshold tension f_x^thr [-]: delta l is read where the uncut twin's unloading crosses it; none: not read"))
    cut: bool = Field(True, description="cut a copy at Delta x_max of the last cycle and follow its ladder [-]")
    stop_at_edge: bool = Field(False, description=(
        "stop the laddering when a ladder reaches an edge course; false: go on until every front has stopped, "
        "the damage Eq. 1 predicts [-]"))

    @model_validator(mode="after")
    def loads(self) -> "CycleConfig":
        if self.lx is not None and self.lx_max <= self.lx:
            raise ValueError(f"lx_max: {self.lx_max:g} is not above the start lx = {self.lx:g}")
        return self

    def cycle_settings(self):
        from knitlad.experiments.cycling import CycleSettings

        return self.settings_of(CycleSettings)


class TensileConfig(CutConfig):
    """The fabric's tensile test (``knitlad tensile``, sweep scene ``tensile``; knitlad.experiments.tensile): the
    knit stretched at mu = 0 (``fx`` or ``lx``, and ``ly``), then with friction on its box pulled to
    (``lx_max``, ``ly_max``), held, and brought back; f_x and f_y read after every ramp."""

    ADDED_LATER: ClassVar[tuple[str, ...]] = ("contact_law", "cycles")
    # the laddering's run length and recording, which a pull does not use: not its options, refused if set
    UNUSED: ClassVar[tuple[str, ...]] = ("max_time_ms", "arrest_ms", "observe_every_us", "frame_every_us",
                                         "stop_after_stitches", "stop_at_edge")
    n_x: int = _stitches_per_course(16)  # a loading (a pull) costs many cuts' steps: 16 x 16 unless asked
    n_y: int = _courses(16)
    mu: float = Field(0.4, ge=0, le=2, description="yarn-yarn friction coefficient while pulled [-]")
    lx_max: float | None = Field(None, gt=0.2, lt=1.0, description="the box's l_x/l0 at the top [-] (none: l_x stays)")
    ly_max: float | None = Field(None, gt=0.2, lt=0.5, description="the box's l_y/l0 at the top [-] (none: l_y stays)")
    unload: bool = Field(True, description="bring the box back to the start after the hold [-]")
    bar_speed: float = _bar_speed()
    cycle_damping_per_s: float = _bar_damping()
    readings_per_leg: int = _readings_per_leg(10)
    hold_ms: float = _hold_ms()
    hold_tol_f0: float = _hold_tol_f0()
    cycles: int = Field(1, ge=1, le=10, description=(
        "loadings, each held and brought back (a tester's cycles; the second and later from the unloaded knit) [-]"))

    @model_validator(mode="after")
    def moves(self) -> "TensileConfig":
        for name in self.UNUSED:
            if getattr(self, name) != type(self).model_fields[name].default:
                raise ValueError(f"{name}: the tensile test does not use it (it sets a ladder's run)")
        if self.lx_max is None and self.ly_max is None:
            raise ValueError("lx_max: give lx_max, ly_max or both (the box must move)")
        if self.lx is not None and self.lx_max is not None and self.lx_max <= self.lx:
            raise ValueError(f"lx_max: {self.lx_max:g} is not above the start lx = {self.lx:g} (a tensile test pulls)")
        if self.ly_max is not None and self.ly_max <= self.ly:
            raise ValueError(f"ly_max: {self.ly_max:g} is not above the start ly = {self.ly:g} (a tensile test pulls)")
        if self.bars == "sliding" and self.ly_max is not None:
            raise ValueError("ly_max: sliding bars are moved along x only; pull along y with held bars")
        if self.cycles > 1 and not self.unload:
            raise ValueError("cycles: a second cycle starts from the unloaded knit; give unload")
        return self

    def tensile_settings(self):
        from knitlad.experiments.tensile import TensileSettings

        return self.settings_of(TensileSettings)


class SnagConfig(CutConfig):
    """A snag (``knitlad snag``; knitlad.experiments.snag): the knit stretched at mu = 0 (``fx`` or ``lx``, and
    ``ly``), then with friction on a pin behind one loop's head pulls it out of the fabric until the yarn
    breaks; the ladder follows from the break as from the paper's cut."""

    ADDED_LATER: ClassVar[tuple[str, ...]] = ("contact_law",)
    # the laddering's run length and recording, which a pull does not use: not its options, refused if set
    UNUSED: ClassVar[tuple[str, ...]] = ("max_time_ms", "arrest_ms", "observe_every_us", "frame_every_us",
                                         "stop_after_stitches", "stop_at_edge")
    n_x: int = _stitches_per_course(16)  # a loading (a pull) costs many cuts' steps: 16 x 16 unless asked
    n_y: int = _courses(16)
    snag_speed: float = Field(1.0, gt=0, le=30, description="the pin's pull speed, out of the fabric's plane [m/s]")
    pin_radius_mm: float = Field(0.2, gt=0, le=2, description="the pin's radius [mm]")
    max_pull_mm: float = Field(10.0, gt=0, le=100, description="the pin lets go after this travel without a break [mm]")
    breaking_force: float | None = Field(None, gt=0, description=(
        "every segment's breaking force [N] (none: the material's, 7.9 N for the paper's Nylon)"))
    weak_point_force: float | None = Field(None, gt=0, description=(
        "the breaking force of the hooked head's segments, a worn spot [N] (none: as the rest)"))
    snag_row: int | None = Field(None, ge=0, description="the hooked loop's course [-] (none: the centre)")
    snag_column: int | None = Field(None, ge=0, description="the hooked loop's column [-] (none: the centre)")

    @model_validator(mode="after")
    def snag_in_knit(self) -> "SnagConfig":
        if self.snag_row is not None and self.snag_row >= self.n_y:
            raise ValueError(f"snag_row: {self.snag_row} is outside the knit's {self.n_y} courses")
        if self.snag_column is not None and self.snag_column >= self.n_x:
            raise ValueError(f"snag_column: {self.snag_column} is outside the knit's {self.n_x} columns")
        # a loop on the knit's border has its tail or a held course beside it: no ladder can run from it
        for name, value, size in (("snag_row", self.snag_row, self.n_y), ("snag_column", self.snag_column, self.n_x)):
            if value is not None and value in (0, size - 1):
                raise ValueError(f"{name}: {value} is on the knit's edge; a snag ladders from a loop inside it "
                                 f"(1 to {size - 2})")
        strength = self.breaking_force if self.breaking_force is not None else self.material().breaking_force
        if self.weak_point_force is not None and self.weak_point_force > strength:
            raise ValueError(f"weak_point_force: {self.weak_point_force:g} N is stronger than the yarn it weakens "
                             f"({strength:g} N): a weak point breaks first")
        return self

    def snag_settings(self):
        from knitlad.experiments.snag import SnagSettings

        return self.settings_of(SnagSettings)


class ResistanceConfig(SnagConfig):
    """A ladder-resistance test of a knit design (``knitlad resistance``; knitlad.experiments.resistance): the
    snag at ``fx`` (or ``lx``), then the paper's cut at each of ``tensions``; the design is the knit's
    pattern, band, d/l0 and mu, every other setting as for ``knitlad cut``."""

    ADDED_LATER: ClassVar[tuple[str, ...]] = ()
    tensions: list[float] = Field([2.0, 4.0, 8.0], min_length=2, max_length=12, description=(
        "the cut series' f_x^ini, force control (repeat the option) [-]: the damage and velocity against "
        "tension, and the threshold bracketed between the highest that does not ladder and the lowest that does"))

    @model_validator(mode="after")
    def tensions_in_range(self) -> "ResistanceConfig":
        for k, fx in enumerate(self.tensions):
            if not 0 < fx <= 40:
                raise ValueError(f"tensions[{k}]: {fx} is not a tension f_x^ini in (0, 40]")
        if len(set(self.tensions)) != len(self.tensions):
            raise ValueError("tensions: a tension is given twice")
        return self


class LoopConfig(_WithPreset):
    """One single-loop run (``knitlad loop``, paper Fig. 5b,c)."""

    PRESETS: ClassVar[dict[str, dict]] = LOOP_PRESETS
    COMPOSED: ClassVar[dict[str, str]] = {**_WithPreset.COMPOSED, "geometry": "the settings' type, columns and sinkers_held",
                                          "columns": "columns (the strip's only)"}

    fx: float = Field(8.0, gt=0, le=40, description="tension per thread pulling the loop's ends, f_x = F/f0 [-]")
    mu: float = Field(0.4, ge=0, le=2, description="yarn-yarn friction coefficient after the release [-]")
    lx: float = Field(0.30, gt=0.2, le=0.34, description=(
        "column width l_x/l0 [-] (wider, the loops no longer overlap); geometry tails only: the periodic rows "
        "take theirs from f_x"))
    ly: float = Field(0.25, gt=0.2, lt=0.35, description="row spacing l_y/l0 [-]")
    resolution: int | None = Field(None, ge=12, le=280, description="nodes per stitch [-]; default: the preset's")
    max_time_ms: float = Field(1.0, gt=0, le=100, description="longest time simulated after the release [ms]")
    geometry: Literal["tails", "periodic", "periodic-sinkers", "strip"] = Field("tails", description=(
        "tails: three one-stitch rows ending in tails (knitlad.experiments.loop_model); periodic: rows periodic along the "
        "course, one stitch per period under the imposed tension; periodic-sinkers: the same with the loop "
        "row's sinkers held in y; strip: periodic rows of `columns` columns at fixed period, one lower loop "
        "removed (knitlad.experiments.periodic_loop) [-]"))
    columns: int = Field(8, ge=2, le=32, description="columns of the strip geometry [-]")

    @model_validator(mode="after")
    def geometry_fields(self) -> "LoopConfig":
        # a resolved config names every field: only a value other than the default is a mistake
        defaults = type(self).model_fields
        if self.geometry != "tails" and self.lx != defaults["lx"].default:
            raise ValueError(f"lx: the {self.geometry} geometry takes its column width from fx; give lx only "
                             "with geometry tails")
        if self.geometry != "strip" and self.columns != defaults["columns"].default:
            raise ValueError("columns: only the strip geometry has columns")
        return self

    def settings(self, **model_choices):
        """The run's settings; ``model_choices``: other fields of :class:`knitlad.experiments.loop_model.LoopSettings`
        (geometry tails) or :class:`knitlad.experiments.periodic_loop.PeriodicLoopSettings`."""
        if self.geometry == "tails":
            from knitlad.experiments.loop_model import LoopSettings

            return self.settings_of(LoopSettings, **model_choices)
        from knitlad.experiments.periodic_loop import PeriodicLoopSettings

        return self.settings_of(PeriodicLoopSettings, **{
            "columns": self.columns if self.geometry == "strip" else 1,
            "sinkers_held": self.geometry == "periodic-sinkers", **model_choices})


class _StitchCell(_WithPreset, _YarnAndKnit):
    """The periodised stitch's cell but its width: its height, resolution, contact, yarn and pattern."""

    PRESETS: ClassVar[dict[str, dict]] = STITCH_PRESETS
    COMPOSED: ClassVar[dict[str, str]] = {**_WithPreset.COMPOSED, "d_over_l0": "material (material_of)",
                                          "yarn": "material (material_of), d_over_l0",
                                          "stitch_length_mm": "material (material_of), d_over_l0"}

    ly: float = Field(0.25, gt=0.15, lt=0.4, description="cell height l_y/l0 [-]")
    resolution: int | None = Field(None, ge=12, le=280, description="nodes per stitch [-]; default: the preset's")
    sagitta_radius: float | None = Field(None, ge=0, le=1000, description=(
        "the contact's sagitta correction (see knitlad cut --help) [d]; 0: none; default: the preset's"))
    d_over_l0: float = Field(1 / 70, gt=0, le=0.1, description=(
        "yarn diameter over stitch length d/l0 [-]; 1/70, the paper's rounded value and the default, means its "
        "Nylon itself: d = 0.14 mm with l0 = 9.74 mm, d/l0 = 0.01437 (knitlad.experiments.config.material_for)"))
    yarn: Yarn | None = _yarn()
    stitch_length_mm: float | None = _stitch_length_mm()
    contact_law: ContactLawName = _contact_law()
    pattern: PatternName = Field("jersey", description=(
        "the knit's pattern: the cell holds one repeat (jersey 1 x 1, rib 2 x 1, garter 1 x 2 stitches) and the "
        "tensions are per thread and per stitch [-]"))

    @model_validator(mode="after")
    def sagitta_within_reach(self) -> "_StitchCell":
        check_sagitta(self.resolution, self.d_over_l0, self.sagitta_radius)
        return self

    def cell_settings(self, lx: float | None = None, **model_choices):
        """The stitch's settings at width ``lx`` (l_x/l0); ``model_choices``: other fields of
        :class:`knitlad.fabric.stitch_model.StitchSettings` (``lx_over_l0=``, its name up to 0.13, still
        works, with a DeprecationWarning)."""
        import warnings

        from knitlad.fabric.stitch_model import StitchSettings

        if "lx_over_l0" in model_choices:
            warnings.warn("cell_settings(lx_over_l0=...) is deprecated since 0.14.0: use lx=", DeprecationWarning,
                          stacklevel=2)
            lx = model_choices.pop("lx_over_l0")
        return self.settings_of(StitchSettings, lx=lx, material=self.material(), **model_choices)


class StitchConfig(_StitchCell):
    """One periodised stitch (``knitlad stitch``): tensions at imposed (l_x, l_y)."""

    ADDED_LATER: ClassVar[tuple[str, ...]] = ("contact_law", "pattern", "yarn", "stitch_length_mm")

    lx: float = Field(0.35, gt=0.2, lt=0.6, description="cell width l_x/l0 [-]")

    def settings(self, **model_choices):
        """The run's settings; ``model_choices``: other fields of :class:`knitlad.fabric.stitch_model.StitchSettings`."""
        return self.cell_settings(self.lx, **model_choices)


class DiagramConfig(_StitchCell):
    """One point of the configuration diagram (``knitlad diagram``): the width l_x at which the periodised stitch
    carries f_x = 0 at l_y (the paper's f_x = 0 curve)."""

    def settings(self):
        """The stitch's settings at l_y (its l_x, the search's lower bracket, is the one the search replaces)."""
        return self.cell_settings(0.22)


# the longest segment, over the correction's radius of curvature R, at which the sagitta correction
# is taken: it is l^2/(12 R) to leading order in l/R, measured from 24 nodes per stitch up (l = 0.27 R)
SAGITTA_MAX_SEGMENT = 0.3


def check_stretch(cfg: CutConfig) -> None:
    """Refuse a stretch the knit cannot be given: a memory or a pattern needs its own way of stretching."""
    if cfg.natural_curvature > 0 and (cfg.stretch_start, cfg.edge) != ("tiled", "clamped"):
        raise ValueError("natural_curvature: set in the periodised stitch and tiled over the knit, it needs "
                         "stretch_start tiled and edge clamped")
    if cfg.pattern != "jersey" and cfg.stretch_start != "affine":
        raise ValueError(f"stretch_start: the periodised stitch is jersey's; a {cfg.pattern} knit is stretched "
                         "affinely (stretch_start affine)")
    if cfg.memory_peak_ratio is not None and cfg.natural_curvature == 0 and cfg.memory_band is None:
        raise ValueError("memory_peak_ratio: shapes the memory of natural_curvature > 0; the yarn has none")


def drag_of(cfg: CutConfig) -> float:
    """The global drag of the laddering [1/s]: ``drag_per_s``, or the authors' ``drag_lambda`` converted
    (:func:`knitlad.engine.dissipation.authors_drag_per_s`)."""
    if cfg.drag_lambda is None:
        return cfg.drag_per_s
    from knitlad.engine.dissipation import authors_drag_per_s

    return authors_drag_per_s(cfg.drag_lambda, cfg.material())


def check_drag(cfg: CutConfig) -> None:
    """One drag, given one way; a drag on the spin needs a spin."""
    if cfg.drag_lambda is not None and cfg.drag_per_s > 0:
        raise ValueError(f"drag_lambda: {cfg.drag_lambda:g} and a drag of {cfg.drag_per_s:g} /s both given; give one")
    if cfg.spin_drag and not cfg.twist:
        raise ValueError("spin_drag: the yarns carry no twist to damp (twist: true)")


def check_observations(cfg: CutConfig) -> None:
    """Refuse a run that would not be read: shorter than one observation, or frames between observations."""
    if cfg.max_time_ms * 1e3 < cfg.observe_every_us:
        raise ValueError(f"max_time_ms: {cfg.max_time_ms:g} ms is shorter than one observation "
                         f"(observe_every_us {cfg.observe_every_us:g}): the ladder would not be read once")
    if cfg.frame_every_us is not None and cfg.frame_every_us < cfg.observe_every_us:
        raise ValueError(f"frame_every_us: {cfg.frame_every_us:g} is shorter than observe_every_us "
                         f"({cfg.observe_every_us:g}): frames are taken at observations")


def check_clips(cfg: CutConfig) -> None:
    """Refuse clip friction on a knit without clips: they are the sliding bars' and the continuous edge's."""
    if cfg.clip_friction > 0 and cfg.bars == "held" and cfg.edge != "continuous":
        raise ValueError("clip_friction: this knit has no clips (bars held, edge not continuous); use bars sliding "
                         "or edge continuous")


def check_band(cfg: CutConfig) -> None:
    """Refuse a run-stop band that is not one (one line naming the field): a band needs its first course and
    must lie inside the knit, off the cut course; a knitted band is stretched affinely, a curvature band tiled."""
    if cfg.band == "friction" and cfg.band_row is not None and cfg.edge == "continuous":
        raise ValueError("band: a friction band names its courses' yarns; on the continuous edge they are one yarn")
    if cfg.band != "friction" and cfg.band_row is None:
        raise ValueError(f"band: a {cfg.band} band needs its first course (band_row)")
    if cfg.knitted_band and cfg.stretch_start != "affine":
        raise ValueError(f"stretch_start: a knit with a {cfg.band} band is stretched affinely (stretch_start affine)")
    if cfg.memory_band is not None and (cfg.stretch_start, cfg.edge) != ("tiled", "clamped"):
        raise ValueError("band: a curvature band is set in the periodised stitch and tiled over the knit; it needs "
                         "stretch_start tiled and edge clamped")
    if cfg.band_row is not None and cfg.band_row + cfg.band_courses > cfg.n_y:
        raise ValueError(f"band_row: a band of {cfg.band_courses} courses from course {cfg.band_row} ends past the "
                         f"knit's {cfg.n_y} courses")
    if cfg.band_row is not None and cfg.band_row <= cfg.n_y // 2 < cfg.band_row + cfg.band_courses:
        raise ValueError(f"band_row: the band holds the cut course {cfg.n_y // 2}; put it above or below")


def check_sagitta(resolution: int, d_over_l0: float, sagitta_radius: float) -> None:
    """Refuse a sagitta correction on segments too long for it (one line naming the field)."""
    if sagitta_radius > 0:
        segment = 1.0 / (d_over_l0 * resolution)  # in yarn diameters
        if segment > SAGITTA_MAX_SEGMENT * sagitta_radius:
            raise ValueError(
                f"sagitta_radius: the correction holds for segments up to {SAGITTA_MAX_SEGMENT:g} R; at {resolution} "
                f"nodes per stitch a segment is {segment / sagitta_radius:.2f} R: give sagitta_radius 0 (as the fast "
                f"preset does) or at least {math.ceil(1.0 / (d_over_l0 * SAGITTA_MAX_SEGMENT * sagitta_radius))} "
                "nodes per stitch")


def material_for(d_over_l0: float):
    """The paper's Nylon with the diameter set by d/l0 (l0 = 9.74 mm kept)."""
    import dataclasses

    from knitlad.engine.units import NYLON

    if abs(d_over_l0 - NYLON.diameter / NYLON.stitch_length) < 1e-12 or abs(d_over_l0 - 1 / 70) < 1e-12:
        return NYLON
    return dataclasses.replace(NYLON, diameter=d_over_l0 * NYLON.stitch_length)


def parse_stitches(text: str) -> tuple[int, int]:
    """'42' -> (42, 42); '8x10' -> (8, 10)."""
    m = re.fullmatch(r"\s*(\d+)\s*(?:[xX]\s*(\d+))?\s*", text)
    if not m:
        raise ValueError(f"stitches must be N or NXxNY (e.g. 42 or 8x10), got {text!r}")
    n_x = int(m.group(1))
    return n_x, int(m.group(2)) if m.group(2) else n_x


MAX_ERRORS = 5  # the validation errors one line says (then "and N more")


def one_line(error: ValidationError, prefix: tuple = (), where=None) -> str:
    """The validation errors as 'field: reason; field: reason' (each field's path joined by dots, after
    ``prefix``; ``where(field)``, if given, names a top-level field as the user wrote it: its option, its YAML
    key), the first MAX_ERRORS of them: a config with three mistakes says three."""
    said = []
    for e in error.errors()[:MAX_ERRORS]:
        # pydantic names the member of a union it tried ("list[any]", "Range"): not part of the user's path
        loc = [str(p) for p in prefix + tuple(e.get("loc", ())) if not (isinstance(p, str) and p in ("list[any]", "Range"))]
        if where is not None and loc:
            loc[0] = where(loc[0])
        # never str(error): it formats the whole input, which an alias-expanded document makes huge
        msg = (e["msg"] if "msg" in e else "invalid value").removeprefix("Value error, ")
        said.append(f"{'.'.join(loc) or 'config'}: {msg}")
    more = error.error_count() - len(said)
    return "; ".join(dict.fromkeys(said)) + (f"; and {more} more" if more > 0 else "")


def cli_option(model: type[BaseModel], field: str) -> str:
    """The command-line option of a config field: ``--field-name`` unless the field names its own (``cli``)."""
    extra = model.model_fields[field].json_schema_extra or {}
    return extra.get("cli", "--" + field.replace("_", "-"))
