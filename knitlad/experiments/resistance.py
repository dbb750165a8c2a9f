"""A virtual ladder-resistance test of a knit design: a snag, then the paper's cut at a series of tensions.

No standard test measures how far a run propagates; snag tests (mace, bean bag) stop at the snag. This one
takes a knit design (its pattern, a run-stop band, its yarn's d/l0 and friction) through:

1. **the snag** (:func:`knitlad.experiments.snag.snag`): a pin pulls the central loop out of the knit
   stretched to f_x^ini = ``fx`` until the yarn breaks (its pull-out curve, the break, the ladder after it);
2. **the cut at each tension** of ``tensions`` (the paper's experiment, :mod:`knitlad.experiments.laddering`):
   the damage n_lad/n_y and the cells released into loaded courses, v_lad/c_b and f_x^fin against f_x^ini;
3. **the threshold**, bracketed by the series: the highest tension at which the cut does not ladder and the
   lowest at which it does. A run ladders when it undoes ``LADDERING_ONSET_CELLS`` cells or more (0.1 n_y of
   the paper's 42 x 42 knit: docs/paper_claims.md, the onset criterion of the threshold study).

Settings: :class:`knitlad.experiments.config.ResistanceConfig` (``knitlad resistance``, sweep scene
``resistance``). The report (:func:`knitlad.viz.plots.resistance_report`) puts the design, the snag curve, the
damage and velocity against tension, the threshold and a picture of the ladder where it stopped on one page.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from knitlad.experiments.laddering import LadderResult, analyse, cut, propagate, require_tension
from knitlad.experiments.snag import SnagResult, snag
from knitlad.fabric.preparation import StretchedKnit

LADDERING_ONSET_CELLS = 4.2  # a cut ladders when it undoes this many cells or more (0.1 n_y on 42 x 42)
ONSET_WHOLE_CELLS = math.ceil(LADDERING_ONSET_CELLS)  # cells are whole: 5 or more
HELD, GAVE_WAY, AT_LEAST = "held", "gave way", "gave way (reached an edge: a lower bound)"


@dataclass
class ResistanceResult:
    """The snag and the cut series of one design; ``design`` names it (pattern, band, d/l0, mu, size, preset)."""

    design: dict
    snag: SnagResult
    tensions: tuple[float, ...]  # the cut series' targets f_x^ini, ascending
    cuts: list[LadderResult] = field(default_factory=list)
    wall_s: float = 0.0

    def laddered(self) -> list[bool]:
        """Whether each cut laddered (``LADDERING_ONSET_CELLS``)."""
        return [c.n_lad >= LADDERING_ONSET_CELLS for c in self.cuts]

    def threshold_bracket(self) -> tuple[float, float]:
        """(highest f_x^ini that did not ladder, lowest that did), NaN where the series has none: the
        threshold lies between, if the series is monotonic (the summary says when it is not)."""
        held = [c.fx_ini for c, lad in zip(self.cuts, self.laddered()) if not lad]
        ran = [c.fx_ini for c, lad in zip(self.cuts, self.laddered()) if lad]
        return (max(held) if held else math.nan, min(ran) if ran else math.nan)

    def arrest_threshold(self) -> dict:
        """f_x^thr as the paper defines it: the mean f_x^fin of the cuts that laddered and arrested, with its scatter
        (:func:`knitlad.fabric.measure.arrest_threshold`)."""
        from knitlad.fabric.measure import arrest_threshold

        return arrest_threshold([c.fx_ini for c in self.cuts], [c.fx_fin for c in self.cuts], self.laddered(),
                                [c.stop_reason.startswith("no cell changed") for c in self.cuts])

    def verdicts(self) -> list[str]:
        """Each cut's answer to "does it hold?", by :meth:`rule`: held, gave way, or gave way as far as an edge
        course (its damage a lower bound: a larger knit would have laddered further)."""
        out = []
        for c in self.cuts:
            if not self.gave_way(c):
                out.append(HELD)
            else:
                out.append(AT_LEAST if c.reached_edge else GAVE_WAY)
        return out

    def gave_way(self, c: LadderResult) -> bool:
        """The design gave way under cut ``c``: with a run-stop band, a cell undone beyond the band from the cut
        (the ladder crossed it); without one, the cut laddered (:data:`LADDERING_ONSET_CELLS`)."""
        band_row = self.design.get("band_row", -1)
        if band_row is None or band_row < 0 or c.final_laddered is None:
            return c.n_lad >= LADDERING_ONSET_CELLS
        undone_courses = np.flatnonzero(np.asarray(c.final_laddered).any(axis=1))
        end = band_row + self.design.get("band_courses", 1)
        beyond = undone_courses >= end if band_row > c.cut_row else undone_courses < band_row
        return bool(beyond.any())

    def holds_up_to(self) -> float:
        """The highest f_x^ini whose cut held with every lower one holding too (NaN: the lowest gave way)."""
        held = math.nan
        for c, verdict in zip(self.cuts, self.verdicts()):
            if verdict != HELD:
                break
            held = c.fx_ini
        return held

    def rule(self) -> str:
        """The rule of :meth:`verdicts`, in words."""
        if self.design.get("band_row", -1) is not None and self.design.get("band_row", -1) >= 0:
            return ("a cut gives way when its ladder crosses the band: a cell undone beyond it, seen from the cut, "
                    "at the stop")
        return (f"a cut gives way when it undoes {ONSET_WHOLE_CELLS} cells or more at the stop (more than 0.1 n_y of "
                "the paper's 42 x 42 knit)")

    def pictured(self) -> LadderResult | None:
        """The ladder the report shows: the highest tension's cut that laddered, else the snag's."""
        ran = [c for c, lad in zip(self.cuts, self.laddered()) if lad]
        return ran[-1] if ran else self.snag.ladder

    def table(self) -> np.ndarray:
        """(len(tensions), 7): target f_x^ini, f_x^ini, n_lad/n_y, released cells / n_y, v_lad/c_b,
        f_x^fin of the crossed courses, whether a ladder reached an edge course (1/0)."""
        return np.array([[t, c.fx_ini, c.n_lad_over_ny, c.damage_record()["n_lad_released_over_ny"],
                          c.v_lad_over_cb, c.fx_fin_crossed, float(c.reached_edge)]
                         for t, c in zip(self.tensions, self.cuts)], dtype=float).reshape(-1, 7)

    def summary(self) -> dict:
        """One row: the design, the snag (peak force, break, what its ladder did), the threshold bracket (and
        whether the series is monotonic), and the damage and velocity at the lowest and highest tension."""
        lo, hi = self.threshold_bracket()
        lad = self.laddered()
        snag_row = self.snag.summary()
        out = {**{f"design_{k}": v for k, v in self.design.items()},
               "snag_peak_force_N": snag_row["peak_force_N"], "snag_broke": snag_row["broke"],
               "snag_pull_at_break_mm": snag_row["pull_at_break_mm"], "snag_n_lad_over_ny": snag_row["n_lad_over_ny"],
               "snag_v_down_over_cb": snag_row.get("v_down_over_cb", math.nan),
               "snag_fx_ini": snag_row["fx_ini"],
               "fx_thr_below": lo, "fx_thr_above": hi,
               **{name: self.arrest_threshold()[k] for name, k in (
                   ("fx_thr_arrest", "fx_thr"), ("fx_thr_arrest_sd", "fx_thr_sd"), ("fx_thr_arrest_runs", "runs"))},
               "monotonic": all(not a or b for a, b in zip(lad, lad[1:])),
               "verdicts": "; ".join(f"{t:g}: {v}" for t, v in zip(self.tensions, self.verdicts())),
               "holds_up_to": self.holds_up_to(),
               "tensions": len(self.cuts)}
        if self.cuts:
            first, last = self.cuts[0], self.cuts[-1]
            out.update(n_lad_over_ny_lowest=first.n_lad_over_ny, n_lad_over_ny_highest=last.n_lad_over_ny,
                       v_lad_over_cb_highest=last.v_lad_over_cb, fx_fin_crossed_highest=last.fx_fin_crossed)
        out["wall_s"] = self.wall_s
        return out


def run_resistance(cfg, stretch_for: Callable, progress=None) -> ResistanceResult:
    """The test of the design ``cfg`` (:class:`~knitlad.experiments.config.ResistanceConfig`); ``stretch_for``
    maps a config to its stretched knit (a sweep's cache, or a plain stretch), so the snag and the cut at the
    same tension share one. ``progress(stage, fraction)``: the stages are named snag and cut f_x."""
    t0 = time.perf_counter()
    design = {"pattern": cfg.pattern, "band": cfg.band if cfg.band_row is not None else "none",
              "band_row": -1 if cfg.band_row is None else cfg.band_row, "band_courses": cfg.band_courses,
              "d_over_l0": cfg.d_over_l0, "mu": cfg.mu,
              "n_x": cfg.n_x, "n_y": cfg.n_y, "preset": cfg.preset, "resolution": cfg.resolution}
    knit: StretchedKnit = stretch_for(cfg)
    snagged = snag(knit, cfg.dynamics_settings(), cfg.snag_settings(),
                   (lambda stage, f: progress("snag", f)) if progress else None)
    result = ResistanceResult(design, snagged, tuple(sorted(cfg.tensions)))
    for k, fx in enumerate(result.tensions):
        one = cfg.replace(fx=fx, lx=None)
        knit = stretch_for(one)
        require_tension(knit)
        report = (lambda stage, f, k=k: progress(f"cut {k + 1}/{len(result.tensions)}", f)) if progress else None
        result.cuts.append(analyse(propagate(cut(knit, one.dynamics_settings()), progress=report)))
    result.wall_s = time.perf_counter() - t0
    return result
