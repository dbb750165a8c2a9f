"""knitlad/engine/deprecation.py: a renamed name works, with a DeprecationWarning, for at least a version
(CHANGELOG.md); round 4 found the 0.14.0 keyword arguments refused with a TypeError instead."""

from __future__ import annotations

import dataclasses

import pytest

from knitlad.engine.deprecation import renamed_arguments
from knitlad.engine.units import NYLON
from knitlad.experiments.config import CutConfig


def test_a_renamed_keyword_argument_warns_and_works_and_both_names_at_once_are_refused():
    @renamed_arguments({"old": "new"}, since="0.0.1")
    def f(new=0):
        return new

    with pytest.warns(DeprecationWarning, match=r"f\(old=...\) is deprecated since 0.0.1: use new="):
        assert f(old=3) == 3
    with pytest.raises(TypeError, match="not both"):
        f(old=3, new=4)


def test_the_cells_functions_take_their_old_keyword_names_of_0_14():
    """stitch_tensions and build_width (CHANGELOG 0.14.0; the zero-tension searches: the test below)."""
    from knitlad.fabric.preparation import build_width
    from knitlad.fabric.stitch_model import stitch_tensions

    with pytest.warns(DeprecationWarning, match="nodes_per_stitch"):
        old = stitch_tensions(0.38, 0.25, nodes_per_stitch=12, sagitta_radius=0.0)
    assert old.fx == stitch_tensions(0.38, 0.25, resolution=12, sagitta_radius=0.0).fx
    with pytest.warns(DeprecationWarning, match="lx_over_l0"):
        assert stitch_tensions(lx_over_l0=0.38, ly=0.25, resolution=12, sagitta_radius=0.0).fx == old.fx
    with pytest.warns(DeprecationWarning, match="ly_over_l0"):
        assert build_width(ly_over_l0=0.25, material=NYLON) == build_width(0.25, NYLON)


def test_the_searches_for_the_zero_tension_width_take_their_old_keyword_names(monkeypatch):
    """zero_tension_lx and unloaded_width, on a stand-in stitch whose f_x vanishes at l_x 0.3."""
    from types import SimpleNamespace

    from knitlad.fabric import preparation, stitch_model

    seen = []

    def stand_in(lx, ly, **kwargs):
        seen.append(kwargs)
        return SimpleNamespace(fx=lx - 0.3)

    monkeypatch.setattr(stitch_model, "stitch_tensions", stand_in)
    with pytest.warns(DeprecationWarning, match="nodes_per_stitch"):
        assert stitch_model.zero_tension_lx(0.25, nodes_per_stitch=12) == pytest.approx(0.3, abs=1e-3)
    assert seen[-1] == {"resolution": 12}
    monkeypatch.setattr(preparation, "zero_tension_lx", lambda ly, **kwargs: seen.append(kwargs) or 0.3)
    with pytest.warns(DeprecationWarning, match="ly_over_l0"):
        assert preparation.unloaded_width(ly_over_l0=0.27, resolution=13, material=NYLON) == 0.3


def test_dataclasses_replace_takes_an_old_field_name():
    """dataclasses.replace(settings, nodes_per_stitch=24) warned, then raised 'not both'."""
    settings = CutConfig(fx=4.0, n_x=4, n_y=4).stretch_settings()
    with pytest.warns(DeprecationWarning, match="nodes_per_stitch"):
        changed = dataclasses.replace(settings, nodes_per_stitch=24)
    assert changed.resolution == 24 and changed.lx == settings.lx and changed.fx == settings.fx
