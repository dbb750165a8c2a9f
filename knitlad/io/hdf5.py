"""HDF5 files of knitlad, each written atomically (:func:`knitlad.io.atomic.atomic_path`).

A laddering run (``ladder.h5``, a sweep's ``jobs/<id>.h5``)::

    /attrs              summary (f_x^ini, f_x^fin, n_lad/n_y, v_lad/c_b, mu, twist, ...), knitlad version,
                        the settings (JSON) and the scales (SI) of units.Scales.as_attributes
    /frames/positions   (n_frames, n_nodes, 3) float32 [m]; the first frame is the knit just cut, the last the stop
                        (every dataset carries its unit as the attribute "unit": RUN_UNITS)
    /frames/velocities  (n_frames, n_nodes, 3) float32 [m/s]
    /frames/laddered    (n_frames, n_y, n_x) bool: cells undone at that instant
    /frames/contact     (n_frames, n_nodes) uint8: 0 free, 1 touching another yarn, 2 sliding on it
    /frames/time        (n_frames,) [s]
    /fields/axial_strain, curvature   (n_frames, n_nodes) float32 [-], [1/m]
    /series/time        (n_obs,) [s] since the cut
    /series/front_up, front_down   ladder extent, the cells' first arrival [stitches]
    /series/front_y     the front's height on the laddering column's mid-line (v_lad's) [l0]
    /series/midline     (n_obs, n_y + 1) each course's height on the laddering column's mid-line [l0]
    /series/fx          tension per thread f_x
/series/fx_courses  (n_obs, n_y) each free course's own f_x (bottom to top)
    /series/laddering_column_cells  (n_obs, n_y) bool
    /ledger/<name>      (n_obs,) [J] the energy ledger at each observation (knitlad.engine.dissipation.EnergyLedger):
                        stored (stretching, bending, twisting, branches, contact, kinetic, external), put in
                        (support_work, obstacle_work, owner_changes), taken out (axial_dashpot, contact_dashpot, friction,
                        global_drag, material, air), start, residual, turnover; time_s [s]
    /stretch/relax_steps, box_lx_over_l0, fx   the stretch's tension readings (FIRE steps so far, box, f_x)
    /final/laddered     (n_y, n_x) bool: cells undone at the stop (n_lad)
    /final/ever         (n_y, n_x) bool: cells undone at any time after the cut
    /final/overlap      (n_y, n_x) each cell's overlap at the stop [l_y] (-inf: its yarn has gone)
    /final/taut         (n_y, n_x) bool: of the undone ones, the cells whose bar is taut at the stop
    /final/undone_at, gone_at   (n_y, n_x) when each cell first came undone, when its yarn left it [s] (NaN: never)
    /cells/centres      (n_y, n_x, 2) x, y of each cell at the cut [m]
    /topology/yarn_start, edges (ne, 2), node_course (n,): -1 and n_y for the held courses; attr cut_node

A trajectory of one's own scene (:func:`write_trajectory`) has ``/frames`` (no ``laddered``),
``/fields``, ``/topology`` (``node_course``: each node's yarn) and, with contact, the touching pairs:
    /contacts/offsets   (n_frames + 1,): frame k's pairs are rows offsets[k]:offsets[k + 1]
    /contacts/points, normal_force, friction_force   (n_pairs, 3) float32 [m], [N], [N] (on the first edge)
    /contacts/sliding   (n_pairs,) uint8: 1 at the Coulomb limit
and, with obstacles (``Plane``, ``Cylinder``), their shapes and where each was at every frame:
    /obstacles/kind     (k,) uint8: 0 a plane, 1 a cylinder
    /obstacles/direction, radius   (k, 3) the plane's normal or the cylinder's axis; (k,) [m] (0 for a plane)
    /obstacles/points   (n_frames, k, 3) [m] a point of each obstacle (its reference point, moved)

A stretched knit (:class:`knitlad.fabric.preparation.StretchedKnit`, ``stretched.h5``): its scalars
and settings as attributes, ``/model/*`` and ``/state/*`` (the arrays of
:class:`knitlad.engine.state.RodModel` and :class:`~knitlad.engine.state.RodState`, internal units)
and ``/knit/*`` (the course bookkeeping of :class:`knitlad.fabric.scenes.knit.KnitScene`).
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import io
import json
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import h5py
import numpy as np

from knitlad import __version__
from knitlad.io.atomic import atomic_path
from knitlad.io.kinds import TRAJECTORY_KIND, is_trajectory
from knitlad.io.provenance import code_identity, run_provenance
from knitlad.engine.dissipation import EnergyLedger
from knitlad.engine.units import Scales


def jsonable(obj):
    if dataclasses.is_dataclass(obj):
        return {f.name: jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, enum.Enum):
        return obj.value
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    return obj


def _set_attrs(f: h5py.File, attrs: dict) -> None:
    for key, value in attrs.items():
        f.attrs[key] = json.dumps(value) if isinstance(value, (list, dict)) else ("" if value is None else value)


def checksummed_dataset(group, name: str, data, compression: str | None = None) -> None:
    """A dataset with a checksum (fletcher32; read back by :func:`verify_datasets`); empty ones cannot carry one."""
    data = np.asarray(data)
    if data.size:
        group.create_dataset(name, data=data, compression=compression, fletcher32=True)
    else:
        group.create_dataset(name, data=data)


def _node_fields(group, frames: np.ndarray, edges: np.ndarray, compression) -> None:
    """Per node and frame: axial strain (against the edge lengths of the first frame, the knit
    at rest just cut) and curvature [1/m], float32 (for ParaView: knitlad.io.xdmf.write_xdmf)."""
    from knitlad.fabric.measure import node_strain_and_curvature

    rest = np.linalg.norm(frames[0][edges[:, 1]].astype(float) - frames[0][edges[:, 0]], axis=1)
    fields = [node_strain_and_curvature(np.asarray(x, dtype=float), edges, rest) for x in frames]
    checksummed_dataset(group, "axial_strain", np.array([s for s, _ in fields], dtype=np.float32), compression)
    checksummed_dataset(group, "curvature", np.array([c for _, c in fields], dtype=np.float32), compression)


def verify_datasets(path: str | Path) -> None:
    """Read every dataset of ``path`` back: a damaged one fails its checksum (OSError)."""
    with h5py.File(path, "r") as f:
        def read(name, obj):
            if isinstance(obj, h5py.Dataset):
                obj[()]
        f.visititems(read)


@contextmanager
def atomic_hdf5(path: str | Path) -> Iterator[h5py.File]:
    """An HDF5 file built in memory, then written whole to a temporary file renamed onto ``path``.

    A full disk or a file-size limit is then one OSError of a plain write, and the temporary file
    goes (:func:`knitlad.io.atomic.atomic_path`); when HDF5 itself met the failed writes of a file
    on disk, it printed a traceback per object it closed and could crash the process.
    """
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        yield f
    with atomic_path(path) as tmp:
        tmp.write_bytes(buffer.getbuffer())


class RunFileError(ValueError):
    """A run file that cannot be drawn: unreadable, damaged, or missing what a picture needs."""


RUN_ATTRIBUTES = ("settings_json", "scale_l0_m", "scale_d_m", "box_lx_over_l0", "ly_over_l0")
RUN_DATASETS = ("frames/positions", "frames/time", "frames/laddered", "topology/edges", "topology/node_course",
                "cells/centres", "series/time", "series/fx")
TRAJECTORY_ATTRIBUTES = ("settings_json", "scale_d_m")
TRAJECTORY_DATASETS = ("frames/positions", "frames/time", "topology/edges", "topology/node_course")


def check_run_file(path: str | Path) -> None:
    """Refuse, in one line, a run file (``ladder.h5``, a sweep job's file) that renders, movies and plots
    cannot draw: not HDF5 or truncated, a dataset failing its checksum, an attribute or a dataset
    missing, no frame, or frames whose positions, times and laddered cells disagree in number."""
    try:
        verify_datasets(path)
    except OSError as e:
        reason = "a dataset fails its checksum" if "checksum" in str(e).lower() or "filter" in str(e).lower() \
            else "not a readable HDF5 file (truncated or damaged)"
        raise RunFileError(f"{path}: {reason}") from None
    with h5py.File(path, "r") as f:
        own = is_trajectory(f)
        attributes, datasets = (TRAJECTORY_ATTRIBUTES, TRAJECTORY_DATASETS) if own else (RUN_ATTRIBUTES, RUN_DATASETS)
        missing = [a for a in attributes if a not in f.attrs] + [d for d in datasets if d not in f]
        if missing:
            raise RunFileError(f"{path}: no {', '.join(missing)} (written without frames, by an older knitlad, or "
                               "damaged)")
        counts = {name: f[f"frames/{name}"].shape[0] for name in ("positions", "time", "laddered")[:2 if own else 3]}
        if counts["positions"] == 0:
            raise RunFileError(f"{path}: no frame to draw")
        if len(set(counts.values())) > 1:
            raise RunFileError(f"{path}: the frames disagree in number ({', '.join(f'{k} {v}' for k, v in counts.items())})")


def attributes_checksum(f: h5py.File) -> str:
    """sha256 of every file attribute but the checksum itself, in name order (datasets carry their own)."""
    blob = json.dumps({k: repr(f.attrs[k]) for k in sorted(f.attrs) if k != "attrs_sha256"})
    return hashlib.sha256(blob.encode()).hexdigest()


def _write_run_attrs(f: h5py.File, settings, material) -> None:
    f.attrs["knitlad_version"] = __version__
    f.attrs["knitlad_code"] = code_identity()
    for key, value in run_provenance().items():  # when, where, and with what the file was made
        f.attrs[f"provenance_{key}"] = value
    f.attrs["settings_json"] = json.dumps(jsonable(settings), default=str)
    for key, value in Scales(material).as_attributes().items():
        f.attrs[f"scale_{key}"] = value


def _extra_datasets(f: h5py.File, datasets: dict | None) -> None:
    """``{"group/name": array}`` written as checksummed datasets."""
    for name, data in (datasets or {}).items():
        group, _, leaf = name.rpartition("/")
        checksummed_dataset(f.require_group(group or "/"), leaf, data)


def write_ladder_result(path: str | Path, result, compression: str | None = "gzip", attrs: dict | None = None,
                        datasets: dict | None = None) -> Path:
    """Write one run (:class:`knitlad.experiments.laddering.LadderResult`); ``attrs`` adds file attributes (a sweep's job
    record), ``datasets`` more datasets by path (``{"cycle/readings": array}``: the loading before the cut)."""
    path = Path(path)
    with atomic_hdf5(path) as f:
        _extra_datasets(f, datasets)
        _set_attrs(f, result.summary())
        _set_attrs(f, attrs or {})
        _write_run_attrs(f, result.settings, result.settings.material)
        if result.frames:
            g = f.create_group("frames")
            checksummed_dataset(g, "positions", np.stack(result.frames), compression)
            checksummed_dataset(g, "time", result.frame_times_s)
            if result.frame_velocities:
                checksummed_dataset(g, "velocities", np.stack(result.frame_velocities), compression)
            if result.frame_laddered:
                checksummed_dataset(g, "laddered", np.stack(result.frame_laddered), compression)
            if result.frame_contact:
                checksummed_dataset(g, "contact", np.stack(result.frame_contact), compression)
            if result.edges is not None:
                _node_fields(f.require_group("fields"), np.stack(result.frames), result.edges, compression)
        g = f.create_group("series")
        checksummed_dataset(g, "time", result.times_s)
        checksummed_dataset(g, "front_up", result.front_up)
        checksummed_dataset(g, "front_down", result.front_down)
        if getattr(result, "midline", None) is not None:
            checksummed_dataset(g, "front_y", np.asarray(result.front_y, dtype=float))
            checksummed_dataset(g, "midline", np.asarray(result.midline, dtype=float))
        checksummed_dataset(g, "fx", result.fx_series)
        if result.fx_course_series is not None:
            checksummed_dataset(g, "fx_courses", np.asarray(result.fx_course_series, dtype=float))
        if result.column_history:
            checksummed_dataset(g, "laddering_column_cells", result.column_history)
        if result.energy_series:
            g = f.create_group("ledger")
            for name, values in result.energy_series.items():
                checksummed_dataset(g, name, np.asarray(values, dtype=float))
        if result.final_laddered is not None:
            checksummed_dataset(f.require_group("final"), "laddered", result.final_laddered)
        if getattr(result, "final_taut", None) is not None:
            checksummed_dataset(f.require_group("final"), "taut", result.final_taut)
        for name, array in (("ever", "ever_laddered"), ("overlap", "final_overlap"), ("gone_at", "gone_at")):
            if getattr(result, array, None) is not None:
                checksummed_dataset(f.require_group("final"), name, getattr(result, array))
        if result.undone_at is not None:
            checksummed_dataset(f.require_group("final"), "undone_at", result.undone_at)
            f["final"].attrs["cut_row"] = result.cut_row
            f["final"].attrs["cut_column"] = getattr(result, "cut_column", -1)
        if result.stretch_tension is not None:
            g = f.require_group("stretch")
            for k, name in enumerate(("relax_steps", "box_lx_over_l0", "fx")):
                checksummed_dataset(g, name, result.stretch_tension[:, k])
        g = f.require_group("topology")
        checksummed_dataset(g, "yarn_start", result.yarn_start)
        for name in ("node_course", "edges"):
            if getattr(result, name) is not None:
                checksummed_dataset(g, name, getattr(result, name))
        g.attrs["cut_node"] = result.cut_node
        if result.cell_centres is not None:
            checksummed_dataset(f.require_group("cells"), "centres", result.cell_centres)
        _mark_units(f)
    return path


# the unit of every dataset of a run file, written beside it as its attribute "unit" ("1": a pure
# number, a flag or an index; f0: f_x = F_x / (n_y f0), per thread; l0: the stitch length)
RUN_UNITS = {
    "frames/positions": "m", "frames/velocities": "m/s", "frames/laddered": "1", "frames/contact": "1",
    "frames/time": "s", "fields/axial_strain": "1", "fields/curvature": "1/m", "series/time": "s",
    "series/front_up": "stitches", "series/front_down": "stitches", "series/fx": "f0", "series/fx_courses": "f0",
    "series/front_y": "l0", "series/midline": "l0",
    "final/ever": "1", "final/overlap": "l_y", "final/gone_at": "s",
    "series/laddering_column_cells": "1", "stretch/relax_steps": "1", "stretch/box_lx_over_l0": "l0",
    "stretch/fx": "f0", "final/laddered": "1", "final/taut": "1", "final/undone_at": "s", "cells/centres": "m",
    "topology/yarn_start": "1",
    "topology/edges": "1", "topology/node_course": "1", "contacts/offsets": "1", "contacts/points": "m",
    "contacts/normal_force": "N", "contacts/friction_force": "N", "contacts/sliding": "1",
    "obstacles/kind": "1", "obstacles/direction": "1", "obstacles/radius": "m", "obstacles/points": "m",
    "cycle/readings": "cycle, leg (1 loading, 0 hold, -1 unloading), s, l0 (the box's l_x), f0 (f_x)",
    "snag/pull": "m", "snag/force": "N",
    "resistance/tensions": ("per cut: target f_x^ini (f0), f_x^ini (f0), n_lad/n_y (1), released cells / n_y (1), "
                            "v_lad/c_b (1), f_x^fin of the crossed courses (f0), reached an edge course (1/0)"),
    "tensile/readings": ("leg (1 loading, 0 hold, -1 unloading), s, l0 (the box's l_x, l_y), l0 (the knit's l_x, "
                         "l_y), f0 (f_x per course, f_y per column)"),
    # the energy ledger at each observation (knitlad.engine.dissipation.EnergyLedger)
    **{f"ledger/{name}": "J" for name in (*EnergyLedger.STORED, *EnergyLedger.DISSIPATED, "support_work",
                                          "obstacle_work", "owner_changes", "start", "stored", "dissipated", "work_in", "residual",
                                          "turnover")},
    "ledger/time_s": "s",
}


def write_trajectory(path: str | Path, recorder, material=None, compression: str | None = "gzip",
                     xdmf: bool = True) -> Path:
    """The frames of a :class:`knitlad.fabric.observers.TrajectoryRecorder` as a run file is written (``/frames``,
    ``/fields``, ``/topology``; ``node_course`` holds each node's yarn), with units, checksums, the code's
    identity and the material's scales; with ``xdmf`` the XDMF beside it for ParaView. Returns ``path``."""
    from knitlad.engine.units import Material

    if not recorder.positions:
        raise ValueError("no frame recorded: call the recorder (or pass it as observe=) first")
    path = Path(path)
    frames = np.stack(recorder.positions)
    with atomic_hdf5(path) as f:
        _write_run_attrs(f, {"kind": TRAJECTORY_KIND}, material or Material())
        g = f.create_group("frames")
        checksummed_dataset(g, "positions", frames, compression)
        checksummed_dataset(g, "velocities", np.stack(recorder.velocities), compression)
        checksummed_dataset(g, "contact", np.stack(recorder.contact), compression)
        checksummed_dataset(g, "time", np.array(recorder.times))
        _node_fields(f.create_group("fields"), frames, recorder.edges, compression)
        g = f.create_group("topology")
        checksummed_dataset(g, "edges", recorder.edges)
        checksummed_dataset(g, "yarn_start", recorder.yarn_start)
        checksummed_dataset(g, "node_course", recorder.node_yarn)
        if recorder.pairs:
            _contact_pairs(f.create_group("contacts"), recorder.pairs)
        if getattr(recorder, "obstacle_shapes", None) is not None:
            g = f.create_group("obstacles")
            for name, value in recorder.obstacle_shapes.items():
                checksummed_dataset(g, name, value)
            checksummed_dataset(g, "points", np.stack(recorder.obstacle_points))
            g["kind"].attrs["meaning"] = OBSTACLE_CODES
        _mark_units(f)
    if xdmf:
        from knitlad.io.xdmf import write_xdmf

        write_xdmf(path)
    return path


def _contact_pairs(g: h5py.Group, frames: list) -> None:
    """The touching pairs of every frame, concatenated: frame k's rows are offsets[k]:offsets[k + 1]."""
    counts = [len(p.overlap_m) for p in frames]
    checksummed_dataset(g, "offsets", np.concatenate([[0], np.cumsum(counts)]).astype(np.int64))
    for name, column in (("points", "points_m"), ("normal_force", "normal_N"), ("friction_force", "friction_N")):
        rows = [getattr(p, column).astype(np.float32) for p in frames]
        checksummed_dataset(g, name, np.concatenate(rows) if sum(counts) else np.zeros((0, 3), np.float32))
    checksummed_dataset(g, "sliding", np.concatenate([p.sliding.astype(np.uint8) for p in frames]))


CONTACT_CODES = "0 free, 1 touching another yarn, 2 sliding on it (at the Coulomb limit)"
OBSTACLE_CODES = "0 a plane (direction: its normal, the yarn's side), 1 a cylinder (direction: its axis)"


def _mark_units(f: h5py.File) -> None:
    """Each dataset of a run file gets its unit (RUN_UNITS) as the attribute "unit"; the contact states their
    codes' meaning as the attribute "meaning"."""
    for name, unit in RUN_UNITS.items():
        if name in f:
            f[name].attrs["unit"] = unit
    if "frames/contact" in f:
        f["frames/contact"].attrs["meaning"] = CONTACT_CODES


def write_cycle_result(path: str | Path, cycle, ladder, config: dict, compression: str | None = "gzip",
                       attrs: dict | None = None) -> Path:
    """Protocol B's file (:class:`knitlad.experiments.cycling.CycleResult`): its summary as ``cycle_*`` attributes, the
    config, the readings (``cycle/readings``) and, if a copy was cut (``ladder``), the ladder's run file."""
    attrs = {**{f"cycle_{k}": v for k, v in cycle.summary().items()}, **(attrs or {}),
             "cycle_config_json": json.dumps(config, default=str)}
    data = {"cycle/readings": cycle.readings}
    if ladder is None:
        return write_record(path, attrs, datasets=data)
    return write_ladder_result(path, ladder, compression=compression, attrs=attrs, datasets=data)


def scale_attributes(material) -> dict:
    """The paper's scales of ``material`` as file attributes (``scale_f0_N``, ...): in every output file."""
    from knitlad.engine.units import Scales

    return {f"scale_{k}": v for k, v in Scales(material).as_attributes().items()}


def write_tensile_result(path: str | Path, result, config: dict, attrs: dict | None = None) -> Path:
    """The tensile test's file (:class:`knitlad.experiments.tensile.TensileResult`): its readings
    (``tensile/readings``), its summary as ``tensile_*`` attributes, the config and the scales."""
    return write_record(path, {**{f"tensile_{k}": v for k, v in result.summary().items()},
                               **scale_attributes(result.material), "config_json": json.dumps(config), **(attrs or {})},
                        datasets={"tensile/readings": result.readings})


def write_snag_result(path: str | Path, result, material, config: dict, compression: str | None = "gzip",
                      attrs: dict | None = None) -> Path:
    """A snag's file (:class:`knitlad.experiments.snag.SnagResult`): the pull-out curve (``snag/pull`` [m],
    ``snag/force`` [N]), its summary as ``snag_*`` attributes, the config, the scales and, after a break,
    the ladder's run file."""
    summary = result.summary()
    # the summary twice: prefixed (the file's own record) and as the sweep's summary columns, which a
    # rerun reads back from the file
    attrs = {**{f"snag_{k}": v for k, v in summary.items()}, **summary, **scale_attributes(material),
             "snag_config_json": json.dumps(config, default=str), **(attrs or {})}
    data = {"snag/pull": result.pull_m, "snag/force": result.force_N}
    if result.ladder is None:
        return write_record(path, attrs, datasets=data)
    return write_ladder_result(path, result.ladder, compression=compression, attrs=attrs, datasets=data)


def write_resistance_result(path: str | Path, result, material, config: dict, compression: str | None = "gzip",
                            attrs: dict | None = None) -> Path:
    """A ladder-resistance test's file (:class:`knitlad.experiments.resistance.ResistanceResult`): its summary as
    ``resistance_*`` attributes, the cut series (``resistance/tensions``), the snag's pull-out curve, the config,
    the scales and the run file of the ladder the report shows (``knitlad render`` draws it)."""
    summary = result.summary()
    attrs = {**{f"resistance_{k}": v for k, v in summary.items()}, **summary, **scale_attributes(material),
             "resistance_config_json": json.dumps(config, default=str), **(attrs or {})}
    data = {"resistance/tensions": result.table(), "snag/pull": result.snag.pull_m, "snag/force": result.snag.force_N}
    ladder = result.pictured()
    if ladder is None:
        return write_record(path, attrs, datasets=data)
    return write_ladder_result(path, ladder, compression=compression, attrs=attrs, datasets=data)


def write_record(path: str | Path, attrs: dict, datasets: dict | None = None) -> Path:
    """A file holding attributes (a failed sweep job: its config, status and error) and any ``datasets``
    by path, atomically."""
    path = Path(path)
    with atomic_hdf5(path) as f:
        _extra_datasets(f, datasets)
        _set_attrs(f, attrs)
        _mark_units(f)
        f.attrs["knitlad_version"] = __version__
        f.attrs["knitlad_code"] = code_identity()
    return path


def read_attrs(path: str | Path) -> dict:
    """The file attributes as plain Python values (JSON-encoded lists and dicts decoded)."""
    out = {}
    with h5py.File(path, "r") as f:
        for key, value in f.attrs.items():
            if isinstance(value, bytes):
                value = value.decode()
            if isinstance(value, str) and value[:1] in "[{":
                try:
                    value = json.loads(value)
                except ValueError:
                    pass
            elif isinstance(value, np.generic):
                value = value.item()
            out[key] = value
    return out


def run_settings(attrs: dict) -> dict:
    """The flat settings of a run file (stretch and dynamics together), also of files whose
    settings were one flat mapping."""
    settings = attrs.get("settings_json") or {}
    if isinstance(settings, str):
        settings = json.loads(settings)
    if "stretch" in settings:
        return {**renamed_settings(settings["stretch"]), **settings["dynamics"]}
    return renamed_settings(settings)




# what a knit stretched before a setting existed was stretched with (the tiled start came later: they were affine)
STRETCHED_BEFORE = {"stretch_start": "affine", "natural_curvature": 0.0, "sagitta_radius": 0.0, "contact_law": "linear",
                    "memory_peak_ratio": None, "pattern": "jersey", "pattern_band": None, "memory_band": None,
                    "bars": "held"}


def renamed_settings(settings: dict) -> dict:
    """Stored settings under today's names: a file written before the settings took their config's names
    (0.14.0) reads as one written now (their geometry too: its nodes_per_stitch is the stretch's)."""
    from knitlad.fabric.preparation import RENAMED_STRETCH_SETTINGS

    return {RENAMED_STRETCH_SETTINGS.get(key, key): value for key, value in settings.items()}


# ------------------------------------------------------------------ stretched knits
_KNIT_SCALARS = ("box_lx", "box_ly", "fx_ini", "lx_over_l0", "ly_over_l0", "fx_within_tolerance", "relax_steps",
                 "peak_overlap_over_d", "dt_s", "wall_s")


def write_stretched_knit(path: str | Path, knit) -> Path:
    """Write a :class:`knitlad.fabric.preparation.StretchedKnit` so that :func:`read_stretched_knit` gives it back exactly."""
    path = Path(path)
    k = knit.knit
    with atomic_hdf5(path) as f:
        _write_run_attrs(f, knit.settings, knit.settings.material)
        f.attrs["geometry_json"] = json.dumps(jsonable(k.geometry))
        f.attrs["H"] = k.H
        f.attrs["rods_twist"] = bool(k.rods.twist)
        f.attrs["rods_framed"] = bool(k.rods.framed)
        for name in _KNIT_SCALARS:
            f.attrs[name] = getattr(knit, name)
        for group, arrays in (("model", k.rods.model), ("state", k.rods.state)):
            g = f.create_group(group)
            for name, value in arrays._asdict().items():
                checksummed_dataset(g, name, value)
        checksummed_dataset(f, "tension_history", knit.tension_history)
        g = f.create_group("knit")
        for name in ("courses", "bars", "node_t", "left_end", "right_end", "course_span", "left_share", "right_share"):
            checksummed_dataset(g, name, getattr(k, name))
        f.attrs["attrs_sha256"] = attributes_checksum(f)
    return path


def read_stretched_knit(path: str | Path):
    """The :class:`knitlad.fabric.preparation.StretchedKnit` of a file of :func:`write_stretched_knit`."""
    from knitlad.fabric.preparation import StretchedKnit, StretchSettings
    from knitlad.fabric.scenes.knit import KnitGeometry, KnitScene
    from knitlad.engine.state import RodModel, Rods, RodState
    from knitlad.engine.units import Material

    with h5py.File(path, "r") as f:
        if "attrs_sha256" in f.attrs and f.attrs["attrs_sha256"] != attributes_checksum(f):
            raise OSError(f"{path}: its attributes fail their checksum (edited or damaged)")
        settings = renamed_settings(json.loads(f.attrs["settings_json"]))
        material = Material(**settings.pop("material"))
        settings = {**STRETCHED_BEFORE, **settings}
        for band in ("pattern_band", "memory_band"):  # JSON has lists, the frozen settings tuples
            if settings.get(band) is not None:
                settings[band] = tuple(settings[band])
        geometry = renamed_settings(json.loads(f.attrs["geometry_json"]))
        geometry["material"] = material
        if geometry.get("band") is not None:
            geometry["band"] = tuple(geometry["band"])
        stored = {name: f["model"][name][()] for name in RodModel._fields if name in f["model"]}
        # knits stored before cuts kept their pieces one yarn for the contact were never cut
        stored.setdefault("yarn_parent", np.arange(stored["yarn_start"].shape[0] - 1, dtype=np.int64))
        stored.setdefault("rail_friction", np.zeros(stored["rail_node"].shape[0]))  # and before clip friction
        model = RodModel(**stored)
        state = RodState(**{name: f["state"][name][()] for name in RodState._fields})
        g = f["knit"]
        twist = bool(f.attrs.get("rods_twist", False))
        # knits stored before 0.5.1 did not say whether they are framed; theirs was the model's natural curvature
        framed = bool(f.attrs["rods_framed"]) if "rods_framed" in f.attrs else twist and bool(np.any(model.kappa_bar))
        knit = KnitScene(geometry=KnitGeometry(**geometry), rods=Rods(model, state, twist, framed), H=float(f.attrs["H"]),
                         courses=[int(c) for c in g["courses"][()]], bars=[int(b) for b in g["bars"][()]],
                         node_t=g["node_t"][()], left_end=g["left_end"][()], right_end=g["right_end"][()],
                         # knits stored before the continuous edge: each course its yarn, every end its own
                         **{name: g[name][()] for name in ("course_span", "left_share", "right_share") if name in g})
        scalars = {name: f.attrs[name].item() if isinstance(f.attrs[name], np.generic) else f.attrs[name]
                   for name in _KNIT_SCALARS}
        scalars["tension_history"] = f["tension_history"][()].reshape(-1, 3) if "tension_history" in f else np.zeros((0, 3))
    scalars["fx_within_tolerance"] = bool(scalars["fx_within_tolerance"])
    scalars["relax_steps"] = int(scalars["relax_steps"])
    return StretchedKnit(settings=StretchSettings(material=material, **settings), knit=knit, **scalars)


def write_arrays(path: str | Path, arrays: dict[str, np.ndarray], attrs: dict | None = None) -> Path:
    """Named arrays (``"group/name"``, e.g. a :meth:`knitlad.engine.simulation.Simulation.checkpoint`) and
    ``attrs`` in one HDF5 file, atomically, each dataset with its checksum. Returns ``path``."""
    path = Path(path)
    with atomic_hdf5(path) as f:
        for name, value in arrays.items():
            if np.ndim(value):
                checksummed_dataset(f, name, value)
            else:  # a scalar cannot be chunked, so it carries no checksum
                f.create_dataset(name, data=value)
        _set_attrs(f, attrs or {})
        f.attrs["knitlad_version"] = __version__
    return path


def read_arrays(path: str | Path) -> tuple[dict[str, np.ndarray], dict]:
    """The arrays and attributes of a :func:`write_arrays` file; OSError if a checksum fails."""
    arrays: dict[str, np.ndarray] = {}
    with h5py.File(path, "r") as f:
        def read(name, obj):
            if isinstance(obj, h5py.Dataset):
                arrays[name] = obj[()]
        f.visititems(read)
        return arrays, dict(f.attrs)
