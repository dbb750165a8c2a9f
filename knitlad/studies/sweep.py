"""Parameter sweeps: a YAML config, validated, expanded into jobs with stable ids, run in a pool.

A sweep config (``knitlad sweep config.yaml --out DIR``)::

    scene: ladder            # the laddering experiment of `knitlad cut` (or loop: `knitlad loop`)
    fixed:                   # every job: the options of `knitlad cut`, same units
      n_x: 8
      n_y: 10
      resolution: 16
    sweep:
      expand: grid           # grid: every combination; zip: the i-th values together
      axes:
        fx: [4, 8, 13.6]                          # a list ...
        ly: {start: 0.25, stop: 0.30, num: 2}     # ... or a range (end included)
      ensemble: 3            # knits per point: force-control targets 0.5 % apart (paired ensembles)
    output:
      frame_every_us: 100
      compression: gzip

Each job is the fully resolved scene config; its id is a hash of that config, so
the same inputs always give the same id, and a finished job is found again by
its file ``DIR/jobs/<id>.h5``. The summary table is rebuilt from those files,
so it is always consistent with what is on disk, whatever interrupted the sweep.

An ensemble (``ensemble: N``, force control) runs each point on N knits stretched to targets a fraction of a
per cent apart (:func:`knitlad.studies.ensemble.target_offsets`), member k's yarn displaced at random from seed k
(``knit_seed``: force control alone left members within its tolerance the same knit): one run's velocity at low
tension is one
sample of a stick-slip sequence, scattering by about 20 %. Jobs of one point that differ only in the
dynamics (mu, the dissipations, ...) share each member's stretched knit, so the comparison is paired. The
summary gives each job's ``ensemble_member`` and ``fx_nominal``; ``knitlad plot`` draws means with their
standard errors.
"""

from __future__ import annotations

import difflib
import hashlib
import itertools
import json
import math
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from knitlad.experiments.config import one_line
from knitlad.io.atomic import read_config_text
from knitlad.studies.ensemble import ENSEMBLE_SPREAD, target_offsets
from knitlad.studies.registry import EXPERIMENTS

MAX_JOBS = 10_000  # a sweep of more jobs is refused unless asked for (--max-jobs)
COMPRESSIONS = ("gzip", "lzf", "none")


class SweepError(ValueError):
    """A config that cannot be run: the message is one line, 'key: reason'."""


class Range(BaseModel):
    """Evenly spaced values from start to stop (both included): num of them, or every step."""

    model_config = ConfigDict(extra="forbid")
    start: float = Field(allow_inf_nan=False, description="first value, in the axis' unit")
    stop: float = Field(allow_inf_nan=False, description="last value, in the axis' unit (included)")
    # no bound here: the sweep's job count is checked against --max-jobs before any value is built
    num: int | None = Field(None, ge=1, strict=True, description="number of values [-]")
    step: float | None = Field(None, gt=0, allow_inf_nan=False, description="spacing, in the axis' unit")

    @model_validator(mode="after")
    def one_spacing(self) -> "Range":
        if (self.num is None) == (self.step is None):
            raise ValueError("give num or step (one of them)")
        if self.stop < self.start:
            raise ValueError("stop must be >= start")
        return self

    def count(self) -> int:
        if self.num is not None:
            return self.num
        return int(math.floor((self.stop - self.start) / self.step + 1e-9)) + 1

    def values(self) -> list[float]:
        n = self.count()
        if n == 1:
            return [self.start]
        h = (self.stop - self.start) / (n - 1) if self.num is not None else self.step
        return [round(self.start + k * h, 12) for k in range(n)]


class Sweep(BaseModel):
    model_config = ConfigDict(extra="forbid")
    expand: Literal["grid", "zip"] = Field("grid", description="grid: all combinations; zip: i-th values together")
    axes: dict[str, list[Any] | Range] = Field(description="swept fields of the scene config, each a list or a range")
    ensemble: int = Field(1, ge=1, le=50, strict=True, description=(
        "knits per point, stretched to force-control targets 0.5 % apart around its fx (paired ensembles) [-]"))
    ensemble_spread: float = Field(ENSEMBLE_SPREAD, gt=0, le=0.05, description=(
        "relative spacing of the ensemble's targets [-]"))

    @field_validator("axes", mode="before")
    @classmethod
    def ranges(cls, axes):
        """A mapping is a Range: report its own error rather than 'not a list'."""
        if not isinstance(axes, dict):
            return axes
        out = {}
        for name, values in axes.items():
            if isinstance(values, dict):
                try:
                    values = Range.model_validate(values)
                except ValidationError as e:
                    raise ValueError(f"{name}: {one_line(e).replace('config: ', '')}") from None
            elif not isinstance(values, list):
                raise ValueError(f"{name}: give a list of values or a range {{start, stop, num or step}}, got {values!r}")
            out[name] = values
        return out

    @field_validator("axes")
    @classmethod
    def not_empty(cls, axes: dict) -> dict:
        if not axes:
            raise ValueError("empty sweep: give at least one axis")
        for name, values in axes.items():
            if isinstance(values, list) and not values:
                raise ValueError(f"axis {name!r} has no values")
        return axes

    def values(self) -> dict[str, list]:
        return {k: v.values() if isinstance(v, Range) else list(v) for k, v in self.axes.items()}

    def counts(self) -> dict[str, int]:
        """How many values each axis has (without building them)."""
        return {k: v.count() if isinstance(v, Range) else len(v) for k, v in self.axes.items()}


class Output(BaseModel):
    model_config = ConfigDict(extra="forbid")
    frame_every_us: float = Field(100.0, gt=0, description="interval between stored position frames [us]")
    frames: bool = Field(True, description="store position frames at all (they dominate the file size)")
    compression: Literal["gzip", "lzf", "none"] = Field("gzip", description="HDF5 compression of the frames")


class SweepConfig(BaseModel):
    """A whole sweep file (see the module docstring)."""

    model_config = ConfigDict(extra="forbid")
    scene: Literal[tuple(EXPERIMENTS)] = Field(
        "ladder", description="what each job runs: " + "; ".join(f"{k} = {s.description}" for k, s in EXPERIMENTS.items()))
    fixed: dict[str, Any] = Field(default_factory=dict, description="scene fields common to all jobs (scene units)")
    sweep: Sweep = Field(description="the swept axes and how they combine")
    output: Output = Field(default_factory=Output, description="what each job writes")


class Job(BaseModel):
    """One fully resolved run; ``id`` is a hash of everything that determines its output."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    scene: str
    params: dict[str, Any]
    output: Output
    ensemble_member: int = 0  # which knit of its point's ensemble (0 without one)
    fx_nominal: float | None = None  # the point's target f_x^ini, of which params' fx is a member's

    @property
    def id(self) -> str:
        return job_id(self.scene, self.params, self.output)

    @property
    def point(self) -> str:
        """The id of the point an ensemble's member belongs to: its params less the member's own fx and knit seed."""
        return job_id(self.scene, {k: v for k, v in self.params.items() if k not in ("fx", "knit_seed")}, self.output)

    def scene_config(self) -> BaseModel:
        return EXPERIMENTS[self.scene].config.model_validate(self.params)


def job_id(scene: str, params: dict, output: Output) -> str:
    """Hash of the resolved parameters, less those a scene added later left at their neutral value."""
    model = EXPERIMENTS[scene].config
    later = getattr(model, "ADDED_LATER", ()) + getattr(model, "ADDED_LATER_FOR_ALL", ())
    neutral = {name: model.model_fields[name].default for name in later}
    params = {k: v for k, v in params.items() if not (k in neutral and v == neutral[k])}
    blob = json.dumps({"scene": scene, "params": params, "output": output.model_dump()}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


# --------------------------------------------------------------------- loading
class _UniqueKeyLoader(yaml.SafeLoader):
    """YAML with each key of a mapping given once: a repeated key is an error, not 'the last wins'."""


def _mapping_with_unique_keys(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise yaml.constructor.ConstructorError(None, None, f"key {key!r} is given twice", key_node.start_mark)
        seen.add(key)
    return loader.construct_mapping(node, deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping_with_unique_keys)



# what a sweep file may hold: nesting and the values it expands to (aliases counted each time they are used)
MAX_YAML_DEPTH = 64
MAX_YAML_VALUES = 100_000


def bounded_yaml(text: str, where: str):
    """The document of ``text`` (unique keys), refused with a SweepError before it is built if it nests
    deeper than MAX_YAML_DEPTH, expands to more than MAX_YAML_VALUES values through its aliases (a
    "billion laughs" of a few hundred bytes), or uses a list or mapping as a mapping key."""
    depth = 0
    for event in yaml.parse(text, Loader=_UniqueKeyLoader):  # a stream of events: no recursion, no expansion
        if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            depth += 1
            if depth > MAX_YAML_DEPTH:
                raise SweepError(f"{where}: line {event.start_mark.line + 1}: nested deeper than {MAX_YAML_DEPTH} levels")
        elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            depth -= 1
    loader = _UniqueKeyLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_values(node, {}, where)
        return loader.construct_document(node)
    finally:
        loader.dispose()


def _expanded_values(node: yaml.Node, seen: dict, where: str) -> int:
    """Values under ``node`` with every alias expanded, counted without expanding (memoised by node)."""
    if id(node) in seen:
        return seen[id(node)]
    count = 1
    if isinstance(node, yaml.SequenceNode):
        count += sum(_expanded_values(child, seen, where) for child in node.value)
    elif isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            if not isinstance(key, yaml.ScalarNode):
                raise SweepError(f"{where}: line {key.start_mark.line + 1}: a mapping key must be a plain value, "
                                 "not a list or a mapping")
            count += 1 + _expanded_values(value, seen, where)
    if count > MAX_YAML_VALUES:
        raise SweepError(f"{where}: line {node.start_mark.line + 1}: expands to more than {MAX_YAML_VALUES:,} values "
                         "(aliases of aliases?)")
    seen[id(node)] = count
    return count


def load_sweep(path: str | Path, max_jobs: int = MAX_JOBS) -> tuple[SweepConfig, list[Job]]:
    """Read, validate and expand a sweep file; every problem raises SweepError('key: reason')."""
    path = Path(path)
    try:
        text = read_config_text(path)
    except UnicodeDecodeError:
        raise SweepError(f"{path}: not a text file (a YAML sweep config is text)") from None
    except OSError as e:
        raise SweepError(f"{path}: cannot read ({e.strerror or e})") from None
    except ValueError as e:
        raise SweepError(f"{path}: {e}") from None
    try:
        raw = bounded_yaml(text, str(path))
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else "YAML"
        raise SweepError(f"{path}: {where}: not valid YAML ({getattr(e, 'problem', None) or e})") from None
    if not isinstance(raw, dict):
        raise SweepError(f"{path}: the file must be a mapping with keys scene, fixed, sweep, output")
    try:
        cfg = SweepConfig.model_validate(raw)
    except ValidationError as e:
        raise SweepError(one_line(e)) from None
    return cfg, expand(cfg, max_jobs)


# the settings' names before 0.14.0 (a sweep config of then names them): their names now
RENAMED_SETTINGS = {"lx_over_l0": "lx", "ly_over_l0": "ly", "fx_target": "fx", "nodes_per_stitch": "resolution",
                    "sagitta_radius_d": "sagitta_radius", "bar_speed_m_s": "bar_speed", "speed_m_s": "snag_speed",
                    "breaking_force_N": "breaking_force", "weak_point_N": "weak_point_force"}


def _did_you_mean(key: str, fields) -> str:
    """'; it is now x' for a setting renamed in 0.14.0, else '; did you mean x?' for the field nearest ``key`` in
    spelling, or nothing."""
    if RENAMED_SETTINGS.get(key) in fields:
        return f"; it was renamed {RENAMED_SETTINGS[key]} in 0.14.0"
    close = difflib.get_close_matches(key, sorted(fields), n=1, cutoff=0.6)
    return f"; did you mean {close[0]}?" if close else ""


def expand(cfg: SweepConfig, max_jobs: int = MAX_JOBS) -> list[Job]:
    """All jobs of a sweep, each validated by its scene's config (errors name the YAML key).

    The number of jobs is counted before any is built: more than ``max_jobs`` is refused."""
    model = EXPERIMENTS[cfg.scene].config
    fields = set(model.model_fields)
    counts = cfg.sweep.counts()
    n_jobs = (math.prod(counts.values()) if cfg.sweep.expand == "grid" else max(counts.values())) * cfg.sweep.ensemble
    if n_jobs > max_jobs:
        sizes = " x ".join(f"{c:.3g}" if c >= 1e6 else str(c) for c in counts.values())
        raise SweepError(f"sweep.axes: {n_jobs:.3g} jobs ({sizes}), more than {max_jobs}; use fewer values or "
                         "--max-jobs")
    # the settings the swept presets fill (each preset's table): all given, the preset axis changes nothing
    swept = cfg.sweep.axes.get("preset") if hasattr(model, "PRESETS") else None
    presets = swept if isinstance(swept, list) and all(isinstance(p, str) for p in swept) else list(
        getattr(model, "PRESETS", {}))
    preset_sets = tuple(dict.fromkeys(k for p in presets for k in model.PRESETS.get(p, {})))
    if "preset" in cfg.sweep.axes and preset_sets and all(k in cfg.fixed or k in cfg.sweep.axes for k in preset_sets):
        raise SweepError(f"sweep.axes.preset: has no effect where {', '.join(preset_sets)} are given (the preset "
                         "only sets them)")
    axes = cfg.sweep.values()
    unknown = [f"{where}.{key}: not a field of scene {cfg.scene!r}{_did_you_mean(key, fields)}"
               for where, keys in (("fixed", cfg.fixed), ("sweep.axes", axes)) for key in keys if key not in fields]
    if unknown:  # every mistyped key at once, each with the field it resembles
        raise SweepError("; ".join(unknown) + f" (every field: knitlad cut --help, or knitlad columns {cfg.scene})")
    for key in axes:
        if key in cfg.fixed:
            raise SweepError(f"sweep.axes.{key}: also given in fixed; give it in one place")
    names = list(axes)
    if cfg.sweep.expand == "zip":
        lengths = {k: len(v) for k, v in axes.items()}
        if len(set(lengths.values())) > 1:
            raise SweepError(f"sweep.axes: zip needs axes of equal length, got {lengths}")
        index_sets = [tuple(i for _ in names) for i in range(len(axes[names[0]]))]
    else:
        index_sets = list(itertools.product(*(range(len(axes[k])) for k in names)))
    extras = {}
    if "frame_every_us" in fields and "frame_every_us" not in getattr(model, "UNUSED", ()):
        extras["frame_every_us"] = cfg.output.frame_every_us
    jobs, seen = [], set()
    for idx in index_sets:
        params = {**cfg.fixed, **extras, **{k: axes[k][i] for k, i in zip(names, idx)}}
        try:
            resolved = model.model_validate(params)
        except ValidationError as e:
            def key(field: str, idx=idx) -> str:  # where the user wrote the field
                if field in axes:
                    return f"sweep.axes.{field}[{idx[names.index(field)]}]"
                if field in cfg.fixed:
                    return f"fixed.{field}"
                return f"output.{field}" if field in extras else "fixed"

            text = one_line(e, where=key)
            if text.startswith("config: "):  # a rule across fields names the field it is about first, if any
                named, _, rest = text.removeprefix("config: ").partition(": ")
                text = f"{key(named)}: {rest}" if named in fields and rest else "fixed: " + text.removeprefix("config: ")
            raise SweepError(text) from None
        members = ensemble_targets(cfg, resolved)
        seeded = "knit_seed" in type(resolved).model_fields
        for k, fx in enumerate(members):
            # each member its own knit: its target, and its own perturbation of the stretched yarn
            params_k = resolved.model_dump() if fx is None else {
                **resolved.model_dump(), "fx": fx, **({"knit_seed": k} if seeded else {})}
            job = Job(scene=cfg.scene, params=params_k, output=cfg.output, ensemble_member=k,
                      fx_nominal=None if fx is None else resolved.fx)
            if job.id in seen:
                raise SweepError("sweep.axes: two jobs are identical (a value repeats)")
            seen.add(job.id)
            jobs.append(job)
    return jobs


def ensemble_targets(cfg: SweepConfig, resolved) -> list:
    """The fx of each member of a point's ensemble ([None]: no ensemble); refused without force control."""
    n = cfg.sweep.ensemble
    if n == 1:
        return [None]
    if getattr(resolved, "fx", None) is None:
        raise SweepError("sweep.ensemble: needs force control (fx): its members are knits stretched to targets "
                         f"{100 * cfg.sweep.ensemble_spread:g} % apart")
    return [resolved.fx * (1.0 + o) for o in target_offsets(n, cfg.sweep.ensemble_spread)]
