"""knitlad.experiments.snag: a pin pulls a loop out until the yarn breaks, and the ladder follows."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import knitlad as kl
from knitlad.engine import units
from knitlad.experiments.config import SnagConfig
from knitlad.experiments.snag import SnagSettings, loop_head_node, pin_behind_head, snag


@pytest.fixture(scope="module")
def knit_6x6():
    cfg = kl.CutConfig(n_x=6, n_y=6, fx=4.0, preset="fast", max_time_ms=2.0)
    return cfg, kl.stretch(cfg.stretch_settings())


def snag_settings(**fields) -> SnagSettings:
    """The snag's settings as the command line makes them: the config's defaults and ``fields``."""
    return SnagConfig(n_x=6, n_y=6, fx=4.0, **fields).snag_settings()


@pytest.mark.slow
def test_a_snag_breaks_the_hooked_head_at_its_strength_and_a_ladder_runs(knit_6x6):
    """A worn spot of 0.1 N in the hooked head: the pull-out force rises, the yarn breaks in that loop at
    that tension (within one reading's growth), the pin's work during the pull closes the ledger to 1 %,
    and the ladder from the break undoes cells and relaxes the knit (f_x^fin below f_x^ini)."""
    cfg, knit = knit_6x6
    result = snag(knit, cfg.dynamics_settings(), snag_settings(snag_speed=3.0, weak_point_force=0.1))
    first = result.breaks[0]
    assert result.broke and first.tension_N == pytest.approx(0.1, rel=0.05)
    assert (result.break_row, result.break_column) == (result.row, result.column) == (3, 3)
    assert result.force_N.max() > 0.1  # the two legs of the hook hold the pin back
    ledger = result.energy_pull
    assert result.pin_work_J > ledger["friction"] > 0
    assert abs(ledger["residual"]) < 0.01 * ledger["turnover"]
    ladder = result.ladder
    assert ladder.n_lad > 0 and ladder.fx_fin < ladder.fx_ini
    summary = result.summary()
    assert summary["ladder_released_J"] > 0 and summary["pull_at_break_mm"] > 0


def test_a_strong_yarn_holds_the_snag_and_no_ladder_starts(knit_6x6):
    """At the Nylon's own strength (7.9 N) a 0.3 mm pull breaks nothing: no ladder, NaN observables."""
    cfg, knit = knit_6x6
    result = snag(knit, cfg.dynamics_settings(), snag_settings(snag_speed=3.0, max_pull_mm=0.3))
    assert not result.broke and result.ladder is None
    assert result.pull_m[-1] >= 0.3e-3 and result.pin_work_J > 0
    assert math.isnan(result.summary()["n_lad_over_ny"])


def test_the_pin_sits_behind_the_head_clear_of_the_knit(knit_6x6):
    """The pin starts behind the hooked head's apex, touching nothing, shorter than a stitch is wide."""
    cfg, knit = knit_6x6
    pin = pin_behind_head(knit, 3, 3, 0.2e-3, 1.0, 0.4)
    x = knit.knit.rods.state.x * units.LENGTH
    apex = x[loop_head_node(knit, 3, 3)]
    assert pin.point_m[2] < apex[2] and 0 < pin.length_m < knit.box_lx * knit.settings.material.stitch_length
    along = np.clip(x[:, 0] - pin.point_m[0], -0.5 * pin.length_m, 0.5 * pin.length_m)
    gap = np.linalg.norm(x - (np.asarray(pin.point_m) + along[:, None] * np.array([1.0, 0, 0])), axis=1)
    assert gap.min() > pin.radius_m + 0.5 * knit.settings.material.diameter


def test_a_bad_snag_is_refused_naming_the_field():
    with pytest.raises(ValueError, match="snag_speed"):
        dataclasses.replace(snag_settings(), snag_speed=0.0)
    with pytest.raises(ValueError, match="snag_row"):
        SnagConfig(n_x=6, n_y=6, snag_row=6)


def test_a_snag_leaves_the_stretched_knit_as_it_was(knit_6x6):
    """The stretched knit is a value: a snag runs on a copy, so one stretch serves many snags (a sweep's)."""
    cfg, knit = knit_6x6
    before = knit.knit.rods.state.x.copy()
    snag(knit, cfg.dynamics_settings(), snag_settings(snag_speed=3.0, max_pull_mm=0.1))
    np.testing.assert_array_equal(knit.knit.rods.state.x, before)


def test_the_downward_velocity_is_the_slope_of_the_downward_front_over_stitches_2_to_the_last_below_the_break():
    """A front one stitch further down every 10 us, the break at course 8 (7 courses below it): the fit over
    stitches 2 to 7 gives l_y / 10 us."""
    from types import SimpleNamespace

    from knitlad.experiments.snag import downward_velocity

    times = np.arange(12) * 1e-5
    ladder = SimpleNamespace(settings=SimpleNamespace(stretch=SimpleNamespace(material=kl.NYLON)), cut_row=8,
                             ly_over_l0=0.25, times_s=list(times), front_down=[min(k, 7) for k in range(12)])
    expected = 0.25 * kl.NYLON.stitch_length / 1e-5 / kl.NYLON.c_b
    assert downward_velocity(ladder) == pytest.approx(expected, rel=1e-9)
    short = SimpleNamespace(**{**vars(ladder), "front_down": [min(k, 3) for k in range(12)]})
    assert np.isnan(downward_velocity(short))
