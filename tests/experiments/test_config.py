"""knitlad.experiments.config: the one declaration of each setting, its checks and its presets."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

import dataclasses

from knitlad.experiments.config import (CutConfig, CycleConfig, DiagramConfig, LoopConfig, SnagConfig, StitchConfig,
                                        TensileConfig, in_si, one_line)
from knitlad.fabric.presets import LADDER_PRESETS


def test_a_preset_fills_what_is_not_given_and_a_given_value_wins():
    cfg = CutConfig(fx=4.0, preset="accurate")
    assert cfg.resolution == LADDER_PRESETS["accurate"]["resolution"]
    assert CutConfig(fx=4.0, preset="accurate", resolution=64).resolution == 64


def test_replace_validates_as_a_new_config_does():
    cfg = CutConfig(fx=4.0)
    assert cfg.replace(mu=0.8).mu == 0.8
    with pytest.raises(ValidationError) as info:
        cfg.replace(mu=-1.0)
    assert one_line(info.value).startswith("mu:")


@pytest.mark.parametrize("fields, says", [
    ({"fx": 4.0, "lx": 0.38}, "not both"),
    ({}, "give fx"),
    ({"fx": 4.0, "natural_curvature": 1.0, "twist": False}, "carries twist"),
    ({"fx": 4.0, "memory_peak_ratio": 3.5}, "memory_peak_ratio"),
    ({"fx": 4.0, "memory_peak_ratio": 0.5, "natural_curvature": 1.0}, "memory_peak_ratio"),
    ({"fx": 4.0, "no_such_field": 1}, "no_such_field"),
    ({"fx": 4.0, "band": "curvature"}, "band_row"),
    ({"fx": 4.0, "band": "curvature", "band_row": 30, "twist": False}, "carries twist"),
    ({"fx": 4.0, "band": "curvature", "band_row": 30, "stretch_start": "affine"}, "tiled"),
    ({"fx": 4.0, "band": "curvature", "band_row": 30, "band_curvature": 0}, "band_curvature"),
])
def test_a_bad_config_is_one_line_naming_what_is_wrong(fields, says):
    with pytest.raises(ValidationError) as info:
        CutConfig(**fields)
    line = one_line(info.value)
    assert says in line and "\n" not in line


def test_natural_curvature_turns_twist_on_and_reaches_the_stretch_with_its_shape():
    cfg = CutConfig(fx=4.0, natural_curvature=1.0, memory_peak_ratio=3.5)
    s = cfg.stretch_settings()
    assert cfg.twist and s.natural_curvature == 1.0 and s.memory_peak_ratio == 3.5
    assert cfg.dynamics_settings().mu == cfg.mu


def test_a_curvature_band_turns_twist_on_and_reaches_the_stretch_not_the_friction():
    cfg = CutConfig(fx=4.0, band="curvature", band_row=30, band_courses=3, band_curvature=2.0)
    assert cfg.twist and not cfg.knitted_band and cfg.stretch_start == "tiled"
    assert cfg.stretch_settings().memory_band == (30, 3, 2.0)
    assert cfg.dynamics_settings().friction_band is None
    assert CutConfig(fx=4.0, band_row=30).stretch_settings().memory_band is None


def test_replacing_the_preset_brings_its_settings_and_keeps_those_given():
    cfg = CutConfig(fx=4.0, dt_safety=0.2)
    fast = cfg.replace(preset="fast")
    assert fast.resolution == LADDER_PRESETS["fast"]["resolution"] != cfg.resolution
    assert fast.dt_safety == 0.2
    assert fast.replace(preset="default").model_dump() == cfg.model_dump()


def test_each_preset_brings_its_time_step_factor_and_a_given_one_stays():
    """The accurate preset steps at 0.7 x its (shorter) stability limit, the others at 0.35 (paired studies:
    docs/accuracy.md, docs/performance.md); a factor given by the user is kept through a change of preset."""
    assert [CutConfig(fx=4.0, preset=p).dt_safety for p in ("fast", "default", "accurate")] == [0.35, 0.35, 0.7]
    assert CutConfig(fx=4.0, preset="accurate").replace(preset="default").dt_safety == 0.35
    assert CutConfig(fx=4.0, preset="accurate", dt_safety=0.35).dt_safety == 0.35
    assert CutConfig(fx=4.0, dt_safety=0.2).replace(preset="accurate").dt_safety == 0.2


def _settings_types(cfg) -> list:
    """The settings dataclasses a config makes (the laddering's halves and the experiment's own)."""
    made = {"settings": cfg.settings()} if not isinstance(cfg, CutConfig) else {
        "stretch": cfg.stretch_settings(), "dynamics": cfg.dynamics_settings()}
    for own in ("cycle_settings", "tensile_settings", "snag_settings"):
        if hasattr(cfg, own):
            made[own] = getattr(cfg, own)()
    return [type(s) for s in made.values()]


@pytest.mark.parametrize("cfg", [
    CutConfig(fx=4.0), CycleConfig(fx=0.68, lx_max=0.5), TensileConfig(fx=1.0, lx_max=0.5), SnagConfig(fx=2.0),
    LoopConfig(), LoopConfig(geometry="periodic"), StitchConfig(), DiagramConfig()], ids=lambda c: type(c).__name__)
def test_each_setting_has_one_name_from_the_config_to_the_settings(cfg):
    """Every field of a config reaches the settings dataclasses under its own name (in SI: ``max_time_ms`` as
    ``max_time_s``), but the few it declares COMPOSED; and every field of those settings without a default of the
    model's own is one of the config's: a setting is declared once, with its default, and keeps its name."""
    fields = {f.name: f for kind in _settings_types(cfg) for f in dataclasses.fields(kind)}
    unreached = {name for name in type(cfg).model_fields if in_si(name, 0.0)[0] not in fields}
    if isinstance(cfg, LoopConfig) and cfg.geometry != "tails":
        unreached.discard("lx")  # the periodic rows take their width from f_x (LoopConfig.geometry_fields)
    assert unreached <= set(type(cfg).COMPOSED) <= set(type(cfg).model_fields)
    declared = {in_si(name, 0.0)[0] for name in type(cfg).model_fields}
    required = {name for name, f in fields.items()
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    composed_into = {"material", "pattern_band", "memory_band", "friction_band", "contact_counting", "lx"}
    assert required - declared <= composed_into
