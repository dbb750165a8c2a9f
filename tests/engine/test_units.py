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
