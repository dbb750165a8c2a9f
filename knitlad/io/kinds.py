"""What a knitlad HDF5 file holds, read from its ``settings_json`` attribute: a laddering run (``ladder.h5``)
or a trajectory of one's own scene (``io.hdf5.write_trajectory``). The writers, the ParaView file and the
renders ask here."""

from __future__ import annotations

import json

import h5py

TRAJECTORY_KIND = "trajectory of one's own scene"  # settings_json of a write_trajectory file


def is_trajectory(f: h5py.File) -> bool:
    """Whether an open run file is a trajectory of one's own scene (:func:`write_trajectory`), not a laddering run."""
    try:
        return json.loads(f.attrs.get("settings_json", "{}")).get("kind") == TRAJECTORY_KIND
    except (ValueError, AttributeError):
        return False
