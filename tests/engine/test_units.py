import math

import pytest

from knitlad.engine import units
from knitlad.engine.units import NYLON, Material, Scales


def test_paper_scales_within_its_rounding():
    """Paper: B = 3.55e-8 N m^2, f0 = 14.8 mN, c_b = 30.6 m/s, d/l0 = 1/70."""
    assert NYLON.bending_stiffness == pytest.approx(3.55e-8, abs=0.005e-8)
    assert NYLON.f0 == pytest.approx(14.8e-3, abs=0.05e-3)
    assert NYLON.c_b == pytest.approx(30.6, abs=0.05)
    assert NYLON.stitch_length / NYLON.diameter == pytest.approx(70, abs=0.5)  # 69.6, "1/70" rounded
    assert math.isclose(NYLON.kappa0, 2 * math.pi / 9.74e-3)


def test_axial_wave_speed_of_the_notes():
    assert NYLON.axial_wave_speed == pytest.approx(1350, rel=0.01)


def test_dimensionless_round_trips():
    s = Scales(NYLON)
    F = s.force_from_tension(13.6, 42)
    assert F == pytest.approx(13.6 * 42 * NYLON.f0)
    assert s.tension_per_thread(F, 42) == pytest.approx(13.6)
    assert s.velocity_over_cb(s.velocity_from_cb(0.5)) == pytest.approx(0.5)
    assert s.length_over_l0(s.length_from_l0(0.25)) == pytest.approx(0.25)


def test_internal_units_read_naturally():
    """mm, mg, ms: force in mN, velocity in m/s."""
    assert units.FORCE == pytest.approx(1e-3)
    assert units.VELOCITY == pytest.approx(1.0)
    assert units.to_internal(NYLON.f0, units.FORCE) == pytest.approx(NYLON.f0 * 1e3)  # mN


@pytest.mark.parametrize("field, value", [("diameter", -1.0), ("young_modulus", 0.0), ("poisson_ratio", 0.7)])
def test_unphysical_material_is_refused(field, value):
    with pytest.raises(ValueError, match=field):
        Material(**{field: value})


def test_each_result_in_the_papers_units_has_its_si_twin_named_from_it():
    from knitlad.engine.units import si_twin

    assert si_twin("fx_ini") == ("force_ini_N", "N") and si_twin("cut_fx_fin") == ("cut_force_fin_N", "N")
    assert si_twin("fy") == ("force_y_N", "N") and si_twin("v_down_over_cb") == ("v_down_m_s", "m/s")
    assert si_twin("delta_l_own_over_l0") == ("delta_l_own_mm", "mm")
    assert si_twin("fx_thr_arrest_runs") is None and si_twin("lx_over_l0_at_fx0") is None
    assert si_twin("peak_force_N") is None and si_twin("n_lad_over_ny") is None


def test_the_si_twins_of_a_summary_scale_with_the_yarns_f0_c_b_and_l0():
    """A thicker yarn at a longer stitch: its f0, c_b and l0 differ from the Nylon's, and so does every twin;
    a result whose unit is not the paper's (a count, a flag) has none."""
    from dataclasses import replace

    from knitlad.engine.units import si_twins

    units_of = {"fx_ini": ("f0", ""), "v_lad_over_cb": ("c_b", ""), "lx_over_l0": ("l0", ""),
                "n_lad": ("cells", ""), "broke": ("-", "")}
    summary = {"fx_ini": 2.0, "v_lad_over_cb": 0.5, "lx_over_l0": 0.3, "n_lad": 7, "broke": True}
    for yarn in (NYLON, replace(NYLON, diameter=0.2e-3, stitch_length=12e-3)):
        twins = si_twins(summary, yarn, 16, units_of)
        assert twins == pytest.approx({"force_ini_N": 2.0 * 16 * yarn.f0, "v_lad_m_s": 0.5 * yarn.c_b,
                                       "lx_mm": 0.3 * yarn.stitch_length * 1e3})
    assert si_twins(summary, NYLON, 16, units_of)["force_ini_N"] != twins["force_ini_N"]
