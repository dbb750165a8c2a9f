"""knitlad.io: atomic writes, checksummed datasets, the summary table and the stretched knit's file."""

from __future__ import annotations

import h5py
import numpy as np
import pandas as pd
import pytest

from knitlad.io.atomic import atomic_path
from knitlad.io.hdf5 import atomic_hdf5, checksummed_dataset, read_attrs, verify_datasets, write_record
from knitlad.io.summary import read_summary, write_summary


def test_an_atomic_write_that_fails_leaves_neither_a_file_nor_a_temporary(tmp_path):
    with pytest.raises(RuntimeError):
        with atomic_path(tmp_path / "out.txt") as tmp:
            tmp.write_text("half")
            raise RuntimeError("crash")
    assert list(tmp_path.iterdir()) == []
    with atomic_path(tmp_path / "out.txt") as tmp:
        tmp.write_text("whole")
    assert (tmp_path / "out.txt").read_text() == "whole" and len(list(tmp_path.iterdir())) == 1


def test_a_flipped_byte_in_a_checksummed_dataset_is_found(tmp_path):
    path = tmp_path / "d.h5"
    with atomic_hdf5(path) as f:
        checksummed_dataset(f, "x", np.arange(4096, dtype=np.float64))
    verify_datasets(path)
    with h5py.File(path, "r") as f:
        offset = f["x"].id.get_offset()
    if offset is None:  # a chunked layout keeps no single offset: flip inside the file's body instead
        offset = path.stat().st_size // 2
    data = bytearray(path.read_bytes())
    data[offset + 100] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(OSError):
        verify_datasets(path)


def test_attributes_read_back_as_python_values(tmp_path):
    path = write_record(tmp_path / "r.h5", {"status": "ok", "fx_ini": 4.5, "v_fit_stitches": [2, 6], "n": 3})
    attrs = read_attrs(path)
    assert attrs["status"] == "ok" and attrs["fx_ini"] == 4.5 and attrs["v_fit_stitches"] == [2, 6]
    assert attrs["knitlad_version"] and attrs["knitlad_code"]


def test_the_summary_reads_back_as_written(tmp_path):
    rows = [{"job_id": "a", "status": "ok", "fx_ini": 1.5, "error": ""},
            {"job_id": "b", "status": "failed", "fx_ini": float("nan"), "error": "boom"}]
    write_summary(tmp_path, rows)
    df = read_summary(tmp_path)
    assert list(df.job_id) == ["a", "b"] and df.fx_ini[0] == 1.5 and pd.isna(df.fx_ini[1])
    assert df.error[1] == "boom"


def test_a_stretched_knit_reads_back_to_the_bit(tmp_path):
    from knitlad.experiments.config import CutConfig
    from knitlad.io.hdf5 import read_stretched_knit, write_stretched_knit
    from knitlad.fabric.preparation import stretch

    knit = stretch(CutConfig(n_x=4, n_y=6, lx=0.36, preset="fast", resolution=12, steps_per_increment=5).stretch_settings())
    back = read_stretched_knit(write_stretched_knit(tmp_path / "k.h5", knit))
    for a, b in zip(knit.knit.rods.state, back.knit.rods.state):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(knit.knit.rods.model, back.knit.rods.model):
        np.testing.assert_array_equal(a, b)
    assert back.fx_ini == knit.fx_ini


def test_a_stretched_knit_written_under_the_settings_old_names_reads_as_today(tmp_path):
    """Up to 0.13 the stretch's settings had names of their own (lx_over_l0, fx_target, nodes_per_stitch, start,
    ...) and older files lack later settings: such a file reads back with the config's names, the missing
    settings as the knit was then stretched, and the same knit."""
    import dataclasses
    import json

    import h5py

    from knitlad.experiments.config import CutConfig
    from knitlad.fabric.preparation import stretch
    from knitlad.io.hdf5 import attributes_checksum, read_stretched_knit, write_stretched_knit

    knit = stretch(CutConfig(n_x=4, n_y=6, lx=0.36, preset="fast", resolution=12, steps_per_increment=5,
                             stretch_start="affine").stretch_settings())
    path = write_stretched_knit(tmp_path / "k.h5", knit)
    old = {"lx": "lx_over_l0", "fx": "fx_target", "ly": "ly_over_l0", "resolution": "nodes_per_stitch",
           "stretch_start": "start"}
    with h5py.File(path, "r+") as f:
        settings = json.loads(f.attrs["settings_json"])
        for later in ("sagitta_radius", "contact_law", "pattern", "bars", "pattern_band", "memory_band"):
            del settings[later]
        f.attrs["settings_json"] = json.dumps({old.get(k, k): v for k, v in settings.items()})
        geometry = json.loads(f.attrs["geometry_json"])
        f.attrs["geometry_json"] = json.dumps({old.get(k, k): v for k, v in geometry.items()})
        f.attrs["attrs_sha256"] = attributes_checksum(f)
    back = read_stretched_knit(path)
    assert dataclasses.asdict(back.settings) == dataclasses.asdict(knit.settings)
    assert back.knit.geometry == knit.knit.geometry
    np.testing.assert_array_equal(back.knit.rods.state.x, knit.knit.rods.state.x)


def test_outputs_name_the_commit_of_the_checkout_they_came_from():
    """io.provenance: run from a git checkout, the code identity is version+commit (the commit git names)."""
    import subprocess
    from pathlib import Path

    from knitlad import __version__
    from knitlad.io.provenance import code_commit, code_identity

    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        pytest.skip("not a git checkout")
    head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short=12", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
    assert code_commit().startswith(head)
    assert code_identity().startswith(f"{__version__}+{head}")


def test_a_markdown_table_has_a_header_a_rule_and_floats_to_three_digits():
    import pandas as pd

    from knitlad.io.summary import markdown_table

    text = markdown_table(pd.DataFrame({"band": ["rib", "none"], "n_lad_over_ny": [0.75, 1.166666]}))
    assert text.splitlines() == ["| band | n_lad_over_ny |", "|---|---|", "| rib | 0.75 |", "| none | 1.17 |"]
