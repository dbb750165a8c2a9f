"""The data dictionary of a sweep's summary table: every column, its unit and its meaning.

A sweep writes it beside ``summary.csv`` as ``summary_columns.csv`` (columns ``column``, ``unit``,
``meaning``), and ``knitlad columns [SCENE]`` prints it. The inputs' entries come from the scene's config
(each field's description ends with its unit in brackets: :mod:`knitlad.experiments.config`); the
results' from its registry entry (``Experiment.results``, :mod:`knitlad.studies.registry`), the columns every
row has from :data:`FRAME`, here. ``tests/studies/test_columns.py`` holds every column a summary can
have to an entry. Units: ``1`` a pure number, ``f0`` a tension per thread f_x = F_x/(n_y f0), ``l0`` a length
over the stitch length, ``c_b`` a velocity over the bending-wave speed, ``-`` text or a flag.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Literal, get_args, get_origin

# columns every row has, whatever its scene
FRAME = {
    "job_id": ("-", "the job's id: a hash of its resolved config (the same inputs, the same id)"),
    "scene": ("-", "the experiment the job ran: ladder (knitlad cut), cycle (protocol B), tensile, snag, resistance, "
                   "loop, stitch or diagram"),
    "fx_nominal": ("1", "an ensemble's point: the target f_x^ini its members' fx are spread around (sweep.ensemble)"),
    "ensemble_member": ("index", "which knit of its point's ensemble (targets 0.5 % apart, yarn displaced from seed "
                                 "knit_seed = this index)"),
    "ensemble_point": ("-", "the id of the point the member belongs to (its params less fx and knit_seed)"),
    "same_knit_as": ("index", "the member of the same point that stretched to the same knit (f_x^ini, l_x, l_y to "
                              "the digit): a collapsed member, its scatter measures nothing; -1: none"),
    "status": ("-", "pending (not run yet), ok, or failed"),
    "error": ("-", "why a failed job failed, in one line (empty otherwise)"),
    "knitlad_code": ("-", "the knitlad version and source hash that made the job's file"),
    "job_wall_s": ("s", "wall time of the whole job, the file's writing included"),
    "wall_s": ("s", "wall time of the run (the stages summed)"),
}

def unit_of(description: str) -> str:
    """The unit a config field's description ends with, in brackets ([-] a pure number, as ``1``)."""
    found = re.findall(r"\[([^\[\]]*)\]", description or "")
    if not found:
        return "-"
    unit = found[-1].strip()
    return "1" if unit == "-" else unit


def column_dictionary(scene: str) -> list[tuple[str, str, str]]:
    """(column, unit, meaning) of every column the summary of ``scene``'s jobs can have, in the table's order:
    the frame's, the inputs (the scene config's fields), the results (the scene's summary keys)."""
    from knitlad.studies.registry import EXPERIMENTS

    s = EXPERIMENTS[scene]
    rows = [("job_id", *FRAME["job_id"]), ("scene", *FRAME["scene"])]
    for name, field in s.config.model_fields.items():
        kinds = (field.annotation, *get_args(field.annotation))
        words = any(k in (bool, str) or get_origin(k) is Literal for k in kinds)  # a flag or a choice: no unit
        rows.append((name, "-" if words else unit_of(field.description), f"input: {field.description}"))
    rows += [(name, *FRAME[name]) for name in ("fx_nominal", "ensemble_member", "ensemble_point", "same_knit_as", "status",
                                                       "error", "knitlad_code")]
    for key in s.summary_keys:
        if key in s.config.model_fields:  # an input the result echoes (natural_curvature): one column
            continue
        unit, meaning = s.results.get(key) or FRAME[key]
        rows.append((key, unit, meaning))
    return rows


def write_column_dictionary(out_dir, scenes) -> Path:
    """``out_dir/summary_columns.csv``: the dictionary of ``scenes`` (scene, column, unit, meaning), atomically."""

    import pandas as pd

    from knitlad.io.atomic import atomic_path

    rows = [(scene, *row) for scene in sorted(set(scenes)) for row in column_dictionary(scene)]
    path = Path(out_dir) / "summary_columns.csv"
    with atomic_path(path) as tmp:
        pd.DataFrame(rows, columns=["scene", "column", "unit", "meaning"]).to_csv(tmp, index=False)
    return path
