"""The data dictionary of a sweep's summary table: every column, its unit and its meaning.

A sweep writes it beside ``summary.csv`` as ``summary_columns.csv`` (columns ``column``, ``unit``,
``meaning``), and ``knitlad columns [SCENE]`` prints it. The inputs' entries come from the scene's config
(each field's description ends with its unit in brackets: :mod:`knitlad.experiments.config`); the
results' are said here, once per scene. ``tests/studies/test_columns.py`` holds every column a summary can
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
    "ensemble_member": ("index", "which knit of its point's ensemble (targets 0.5 % apart)"),
    "status": ("-", "pending (not run yet), ok, or failed"),
    "error": ("-", "why a failed job failed, in one line (empty otherwise)"),
    "knitlad_code": ("-", "the knitlad version and source hash that made the job's file"),
    "job_wall_s": ("s", "wall time of the whole job, the file's writing included"),
    "wall_s": ("s", "wall time of the run (the stages summed)"),
}

LADDER = {
    "fx_ini": ("f0", "f_x^ini: the tension per thread of the stretched knit, just before the cut"),
    "fx_fin": ("f0", "f_x^fin: the mean tension at the stop (over the last half arrest window); after an arrest the "
                     "paper's Fig. 3f, else (reached_edge, or the time limit) the tension of that moment"),
    "fx_fin_crossed": ("f0", "f_x at the stop of the courses the ladder crossed (with an undone cell)"),
    "fx_fin_intact": ("f0", "f_x at the stop of the courses it did not cross"),
    "n_lad": ("cells", "cells undone after the cut"),
    "n_lad_over_ny": ("1", "n_lad/n_y: the damage, in columns of the knit's height (paper Fig. 3e)"),
    "v_lad_over_cb": ("c_b", "v_lad/c_b: the upward front's slope from stitch v_fit_first to v_fit_last (NaN: the "
                             "front ran fewer than 3 stitches; stop_reason says why)"),
    "lx_over_l0": ("l0", "l_x/l0 measured on the stretched knit (not the box's: box_lx_over_l0)"),
    "ly_over_l0": ("l0", "l_y/l0 measured on the stretched knit"),
    "ladders_up": ("1", "ladders the cut started upwards (from loops (1) and (4)/(5) of the paper's Fig. 2d)"),
    "ladders_down": ("1", "ladders it started downwards (from loops (2)/(3))"),
    "first_down_ms": ("ms", "when the first downward ladder started after the cut (NaN: none did)"),
    "second_up_ms": ("ms", "when the second upward ladder started (NaN: none did)"),
    "hindered": ("-", "the paper's hindered laddering: one ladder up and two or more down"),
    "n_lad_cut_row": ("cells", "undone cells of the cut's own course (its yarn is cut: they free no length into a "
                      "loaded course)"),
    "n_lad_immediate": ("cells", "other cells undone within 0.1 ms of the cut (its recoil, not the ladder's run)"),
    "n_lad_released": ("cells", "the rest of n_lad: cells the ladder released into loaded courses (Eq. 1's count)"),
    "n_lad_released_over_ny": ("1", "n_lad_released / n_y: the damage Eq. 1 predicts, like for like"),
    "n_lad_released_taut": ("cells", "of n_lad_released, the cells whose bar is taut at the stop (head 0.75 l_y "
                                     "below the sinkers): each released l0 - l_x, as Eq. 1 counts"),
    "n_lad_released_taut_over_ny": ("1", "n_lad_released_taut / n_y"),
    "box_lx_over_l0": ("l0", "the box's l_x/l0: the held ends' spacing over n_x l0"),
    "fx_within_tolerance": ("-", "force control: f_x^ini came within fx_tolerance of the target"),
    "peak_overlap_over_d": ("1", "the deepest yarn-yarn overlap at any step, over d"),
    "reached_edge": ("-", "the ladder reached an edge course: damage and f_x^fin are lower bounds"),
    "stop_reason": ("-", "why the run stopped: an arrest, an edge course, max_time_ms, or stop_after_stitches"),
    "laddering_column": ("index", "the column beside the cut whose front was followed"),
    "v_fit_stitches": ("stitches", "[first, last] stitches of the velocity fit, as text (v_fit_first, v_fit_last)"),
    "v_fit_first": ("stitches", "the first stitch of the velocity fit (the paper: 2)"),
    "v_fit_last": ("stitches", "the last stitch of the velocity fit (the paper: 10; fewer on a small knit)"),
    "energy_start_J": ("J", "the energy the knit stored just after the cut (elastic, contacts, kinetic)"),
    "energy_end_J": ("J", "the energy it stored at the stop"),
    "dissipated_friction_J": ("J", "energy friction took out (sliding, the tangential dashpot, springs reset)"),
    "dissipated_contact_dashpot_J": ("J", "energy the contacts' normal dashpots took out (numerical)"),
    "dissipated_axial_dashpot_J": ("J", "energy the axial dashpots took out (numerical; with implicit axial "
                                        "springs also their damping of axial waves)"),
    "dissipated_material_J": ("J", "energy the yarn's viscoelasticity took out (loss_factor > 0)"),
    "dissipated_air_J": ("J", "energy the air took out (air_drag)"),
    "dissipated_global_drag_J": ("J", "energy the global drag took out (drag_per_s > 0)"),
    "dissipated_fracture_J": ("J", "elastic energy stored in the segments a break cut away (0: no yarn broke)"),
    "owner_changes_J": ("J", "energy the union contact counting created (or, < 0, destroyed) where a contact passed "
                             "from one edge to its neighbour: booked so the ledger closes; 0 counting all pairs"),
    "ledger_residual": ("1", "the energy ledger's residual over the energy turned over: the integrator's error "
                             "(docs/dissipation.md)"),
    "nan_reasons": ("-", "why each result that is NaN is NaN: 'column: reason; ...' (empty: none is)"),
    "nodes": ("1", "nodes of the knit"),
    "steps": ("1", "time steps of the laddering"),
    "relax_steps": ("1", "FIRE steps of the stretch and its relaxation"),
    "stretch_reused": ("-", "the stretched knit came from the sweep's cache"),
    "wall_stretch_s": ("s", "wall time of the stretch"),
    "wall_propagate_s": ("s", "wall time of the laddering"),
}

CYCLE = {
    "fx_ini": ("f0", "f_x^ini: the tension at Delta x_max of the last cycle, where the copy is cut"),
    "lx_over_l0": ("l0", "l_x/l0 measured there"),
    "ly_over_l0": ("l0", "l_y/l0 measured there"),
    "lx_max": ("l0", "the box's l_x/l0 at Delta x_max"),
    "fx_thr": ("f0", "the threshold f_x^thr at which delta l is read (NaN: not read)"),
    "delta_l_over_l0": ("l0", "delta l/l0: the uncut twin's shortening from f_x^ini to f_x^thr (Eq. 1)"),
    "predicted_damage": ("1", "Eq. 1's n_lad/n_y = delta l/(l0 - l_x)"),
    "fx_thr_own": ("f0", "the paper's f_thr: the tension at the bars once the cut copy's ladder stopped (its f_x^fin)"),
    "delta_l_own_over_l0": ("l0", "delta l/l0 read down to fx_thr_own (Eq. 1 as the paper reads it)"),
    "predicted_damage_own": ("1", "Eq. 1's n_lad/n_y from delta_l_own_over_l0"),
    "cut_n_lad_over_ny": ("1", "the cut copy's damage n_lad/n_y"),
    "cut_fx_fin": ("f0", "the cut copy's f_x^fin"),
    "cut_fx_fin_crossed": ("f0", "the cut copy's f_x at the stop of the courses its ladder crossed"),
    "cut_reached_edge": ("-", "the cut copy's ladder reached an edge course"),
    "cut_ladders_up": ("1", "ladders the cut started upwards"),
    "cut_ladders_down": ("1", "ladders the cut started downwards"),
    "cut_second_up_ms": ("ms", "when the second upward ladder started (NaN: none did)"),
    "cut_hindered": ("-", "hindered laddering (one ladder up, two or more down)"),
    "cut_n_lad_cut_row": ("cells", "the cut copy's undone cells of the cut course"),
    "cut_n_lad_immediate": ("cells", "the cut copy's other cells undone within 0.1 ms of the cut"),
    "cut_n_lad_released": ("cells", "the cut copy's cells released into loaded courses (Eq. 1's count)"),
    "cut_n_lad_released_over_ny": ("1", "cut_n_lad_released / n_y: the damage to set beside Eq. 1, like for like"),
    "cut_n_lad_released_taut": ("cells", "of cut_n_lad_released, the cells whose bar is taut at the stop"),
    "cut_n_lad_released_taut_over_ny": ("1", "cut_n_lad_released_taut / n_y"),
    "hold_converged": ("-", "the last hold at Delta x_max settled within hold_ms"),
    "nan_reasons": ("-", "why delta l and the predicted damage are NaN, if they are ('column: reason; ...')"),
    "cut_nan_reasons": ("-", "why a result of the cut copy's ladder is NaN ('column: reason; ...')"),
}

LOOP = {
    "tau_s": ("s", "tau: the time the loop took to let go after the lower row was removed"),
    "tau_contact_s": ("s", "the time until its last contact with the row above broke"),
    "v_lad_over_cb": ("c_b", "l_y/(tau c_b): the single loop's laddering velocity (paper Fig. 5c)"),
    "released": ("-", "the loop let go within max_time_ms"),
    "relax_converged": ("-", "the relaxation before the release converged"),
    "contacts_before": ("1", "touching pairs between the loop and the row above before the release"),
    "steps": ("1", "time steps of the run"),
    "nodes": ("1", "nodes of the scene"),
    "lx_over_l0": ("l0", "l_x/l0 at the start"),
    "lx_end_over_l0": ("l0", "l_x/l0 at the end"),
    "climb_over_ly": ("1", "how far the loop's head rose, over l_y"),
}

STITCH = {
    "fx": ("f0", "f_x of the periodised stitch (its tension per thread along the course)"),
    "fy": ("f0", "f_y, along the wale"),
    "converged": ("-", "the relaxation reached its force tolerance"),
    "max_overlap_over_d": ("1", "the deepest yarn-yarn overlap, over d"),
    "relax_steps": ("1", "FIRE steps of the relaxation"),
}

DIAGRAM = {
    "lx_over_l0_at_fx0": ("l0", "the width l_x/l0 at which the relaxed periodised stitch carries f_x = 0 at ly (the "
                                "configuration diagram's curve)"),
}

TENSILE = {
    "fx_start": ("f0", "f_x per course at the start (the knit stretched at mu = 0)"),
    "fy_start": ("f0", "f_y per column at the start"),
    "fx_top": ("f0", "f_x after the hold at the top of the loading"),
    "fy_top": ("f0", "f_y after the hold at the top"),
    "lx_top_over_l0": ("l0", "the knit's own l_x/l0 there (measured on its free courses)"),
    "ly_top_over_l0": ("l0", "the knit's own l_y/l0 there"),
    "fx_end": ("f0", "f_x after the unloading (or at the top without one)"),
    "fy_end": ("f0", "f_y after the unloading"),
    "coupling": ("1", "the loading's change of the transverse tension over the pulled one (d f_y/d f_x pulling "
                      "along x, d f_x/d f_y along y; NaN biaxial): the Poisson coupling at fixed bars"),
    "dissipated_per_stitch": ("f0 l0", "the work friction took per stitch over the closed path, the integral of "
                                       "f_x dl_x + f_y dl_y (NaN without the unloading)"),
    "hold_converged": ("-", "the hold at the top settled within hold_ms"),
}

SNAG = {
    "snag_row": ("1", "the hooked loop's course"),
    "snag_column": ("1", "the hooked loop's column"),
    "broke": ("-", "the yarn broke before the pin's max_pull_mm"),
    "peak_force_N": ("N", "the largest force the yarn held the pin back with (the pull-out curve's peak)"),
    "pull_at_break_mm": ("mm", "the pin's travel when the yarn broke (NaN: no break)"),
    "break_tension_N": ("N", "the broken segment's tension at the break"),
    "break_row": ("1", "the course of the first break (-1: none)"),
    "break_column": ("1", "the column of the first break (-1: none)"),
    "pin_work_J": ("J", "the work the pin did on the knit until the break (or the pull's end)"),
    "friction_before_break_J": ("J", "what friction took during the pull"),
    "ladder_released_J": ("J", "the stored energy the ladder released, from the break to its stop"),
    "fx_ini": ("f0", "f_x of the stretched knit before the snag"),
    "n_lad_over_ny": ("1", "the ladder's undone cells over n_y, counted from the break"),
    "v_lad_over_cb": ("c_b", "the ladder's velocity (fit over stitches 2 to 10 above the break)"),
    "v_down_over_cb": ("c_b", "the downward front's velocity (fit over stitches 2 to 10 below the break): a broken "
                              "head frees the course below first"),
    "fx_fin": ("f0", "f_x after the ladder arrested"),
    "reached_edge": ("-", "the ladder reached an edge course"),
}

RESISTANCE = {
    "design_pattern": ("-", "the knit's pattern"),
    "design_band": ("-", "the run-stop band: friction, rib or garter (none: no band)"),
    "design_d_over_l0": ("1", "the yarn's diameter over the stitch length"),
    "design_mu": ("1", "the yarn-yarn friction coefficient"),
    "snag_peak_force_N": ("N", "the snag's largest pull-out force"),
    "snag_broke": ("-", "the yarn broke before the pin's max_pull_mm"),
    "snag_pull_at_break_mm": ("mm", "the pin's travel when the yarn broke (NaN: no break)"),
    "snag_n_lad_over_ny": ("1", "the snag's ladder: undone cells over n_y, counted from the break"),
    "snag_v_down_over_cb": ("c_b", "the snag's ladder: its downward front's velocity"),
    "fx_thr_below": ("f0", "the highest f_x^ini of the series whose cut did not ladder (NaN: every one did)"),
    "fx_thr_above": ("f0", "the lowest f_x^ini of the series whose cut laddered (NaN: none did)"),
    "monotonic": ("-", "no cut laddered below a tension whose cut held"),
    "n_lad_over_ny_lowest": ("1", "the damage of the cut at the lowest tension"),
    "n_lad_over_ny_highest": ("1", "the damage of the cut at the highest tension"),
    "v_lad_over_cb_highest": ("c_b", "the ladder's velocity at the highest tension"),
    "fx_fin_crossed_highest": ("f0", "f_x^fin of the courses the ladder crossed, at the highest tension"),
}

RESULTS = {"ladder": LADDER, "cycle": CYCLE, "tensile": TENSILE, "snag": SNAG, "resistance": RESISTANCE, "loop": LOOP,
           "stitch": STITCH, "diagram": DIAGRAM}


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
    from knitlad.studies.registry import SCENES

    s = SCENES[scene]
    rows = [("job_id", *FRAME["job_id"]), ("scene", *FRAME["scene"])]
    for name, field in s.config.model_fields.items():
        kinds = (field.annotation, *get_args(field.annotation))
        words = any(k in (bool, str) or get_origin(k) is Literal for k in kinds)  # a flag or a choice: no unit
        rows.append((name, "-" if words else unit_of(field.description), f"input: {field.description}"))
    rows += [(name, *FRAME[name]) for name in ("fx_nominal", "ensemble_member", "status", "error", "knitlad_code")]
    results = RESULTS[scene]
    for key in s.summary_keys:
        if key in s.config.model_fields:  # an input the result echoes (natural_curvature): one column
            continue
        unit, meaning = results.get(key) or FRAME[key]
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
