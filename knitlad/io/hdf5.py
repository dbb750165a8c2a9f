"""HDF5 output of a laddering run, written atomically (temporary file, then rename).

Layout::

    /attrs              summary (f_x^ini, f_x^fin, n_lad/n_y, v_lad/c_b, ...), knitlad version,
                        the settings (JSON) and the scales (SI) of units.Scales.as_attributes
    /frames/positions   (n_frames, n_nodes, 3) float32 [m]
    /frames/time        (n_frames,) [s]
    /series/time        (n_obs,) [s] since the cut
    /series/front_up, front_down   ladder extent [stitches]
    /series/fx          tension per thread f_x
    /series/laddering_column_cells  (n_obs, n_y) bool
    /final/laddered     (n_y, n_x) bool
    /topology/yarn_start
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import h5py
import numpy as np

from knitlad import __version__
from knitlad.units import Scales


def _jsonable(obj):
    if dataclasses.is_dataclass(obj):
        return {f.name: _jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    return obj


def _set_attrs(f: h5py.File, attrs: dict) -> None:
    for key, value in attrs.items():
        f.attrs[key] = json.dumps(value) if isinstance(value, (list, dict)) else ("" if value is None else value)


def write_ladder_result(
    path: str | Path, result, yarn_start: np.ndarray, compression: str | None = "gzip", attrs: dict | None = None
) -> Path:
    """Write one run to ``path`` atomically; ``attrs`` adds file attributes (a sweep's job record)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    settings = result.settings
    with h5py.File(tmp, "w") as f:
        _set_attrs(f, result.summary())
        _set_attrs(f, attrs or {})
        f.attrs["knitlad_version"] = __version__
        f.attrs["settings_json"] = json.dumps(_jsonable(settings), default=str)
        for key, value in Scales(settings.material).as_attributes().items():
            f.attrs[f"scale_{key}"] = value
        if result.frames:
            g = f.create_group("frames")
            g.create_dataset("positions", data=np.stack(result.frames), compression=compression)
            g.create_dataset("time", data=np.array(result.frame_times_s))
        g = f.create_group("series")
        g.create_dataset("time", data=np.array(result.times_s))
        g.create_dataset("front_up", data=np.array(result.front_up))
        g.create_dataset("front_down", data=np.array(result.front_down))
        g.create_dataset("fx", data=np.array(result.fx_series))
        if result.column_history:
            g.create_dataset("laddering_column_cells", data=np.array(result.column_history))
        if result.final_laddered is not None:
            f.create_dataset("final/laddered", data=result.final_laddered)
        f.create_dataset("topology/yarn_start", data=yarn_start)
    os.replace(tmp, path)
    return path


def write_record(path: str | Path, attrs: dict) -> Path:
    """A file holding attributes only (a failed sweep job: its config, status and error), atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    with h5py.File(tmp, "w") as f:
        _set_attrs(f, attrs)
        f.attrs["knitlad_version"] = __version__
    os.replace(tmp, path)
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
