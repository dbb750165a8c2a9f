"""Paired ensembles: the options of an ensemble study, the targets of its members, a resumable CSV.

An ensemble samples one ladder's run-to-run scatter: force-control targets a fraction of a
percent apart (:func:`target_offsets`), each member's yarn displaced at random from its own seed
(``knit_seed``), each knit stretched once and laddered under each setting compared. A member that
stretched to the same knit as another (:func:`with_collapsed_members`) is said, not counted twice. Rows are kept in ``<out>/<name>.csv``, written atomically after every run,
and read back on a rerun so that finished runs are skipped.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from knitlad.io.atomic import atomic_path


def ensemble_arguments(p: argparse.ArgumentParser, tensions: list[float], members: int, out: str) -> None:
    """The options every ensemble study takes, with its own defaults."""
    p.add_argument("--size", type=int, default=16, help="knit size N for N x N")
    p.add_argument("--tensions", type=float, nargs="+", default=tensions, help="target f_x^ini values")
    p.add_argument("--members", type=int, default=members, help="knits per tension (targets 0.5 %% apart)")
    p.add_argument("--out", default=out)


ENSEMBLE_SPREAD = 0.005  # the members' targets are this far apart, relatively


def target_offsets(members: int, spread: float = ENSEMBLE_SPREAD) -> np.ndarray:
    """Relative offsets of the members' targets: ``spread`` (0.5 %) apart, centred on the nominal tension."""
    return spread * (np.arange(members) - (members - 1) / 2)


def resumed_rows(out: str | Path, name: str) -> tuple[Path, list[dict]]:
    """(the CSV of the study, the rows it already holds)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv = out / f"{name}.csv"
    return csv, pd.read_csv(csv).to_dict("records") if csv.exists() else []


def save_rows(csv: Path, rows: list[dict], key: tuple[str, ...] | None = None) -> None:
    """Write ``rows``; with ``key``, merged with the rows another process wrote to ``csv`` since (ours win on
    the same key), so that two studies sharing one file do not overwrite each other's rows."""
    df = pd.DataFrame(rows)
    if key is not None and csv.exists():
        theirs = pd.read_csv(csv)
        for name in key:
            for frame in (df, theirs):
                if name not in frame:
                    frame[name] = "plain" if name == "variant" else None
        df = pd.concat([theirs, df], ignore_index=True).drop_duplicates(subset=list(key), keep="last")
    with atomic_path(csv) as tmp:
        df.to_csv(tmp, index=False)


SAME_KNIT = ("fx_ini", "lx_over_l0", "ly_over_l0")  # a knit's identity as the summary records it


def with_collapsed_members(rows: list[dict]) -> list[dict]:
    """The summary's rows, each ensemble member's with ``same_knit_as``: the ensemble_member of another member of
    its point (``ensemble_point``) listed before it whose stretched knit is the same to the digit (f_x^ini, l_x/l0
    and l_y/l0), -1 if none. Such a member adds nothing to the point's scatter: its error bar would measure
    nothing."""
    seen: dict[tuple, int] = {}
    out = []
    for row in rows:
        if row.get("ensemble_point") is None or row.get("status") != "ok":
            out.append(row)
            continue
        earlier = seen.setdefault((row["ensemble_point"], *(row.get(k) for k in SAME_KNIT)), row["ensemble_member"])
        out.append({**row, "same_knit_as": earlier if earlier != row["ensemble_member"] else -1})
    return out
