"""knitlad/experiments/yarn.py and the configs' yarn and knit: a textile engineer's yarn and stitch length made into
the model's material, d/l0 and stretch, with the paper's scales following the yarn."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest
import yaml
from pydantic import ValidationError

import knitlad as kl
from knitlad.experiments.config import CutConfig, StitchConfig
from knitlad.experiments.yarn import PAPER_NYLON, Yarn, YarnError, read_yarn

ROOT = Path(__file__).resolve().parents[2]
NYLON_FILE = ROOT / "configs" / "yarns" / "nylon_paper.yaml"
THICKER = dict(diameter_mm=0.2, linear_density_tex=30.0, young_modulus_GPa=2.5, breaking_force_N=10.0)


def test_the_papers_yarn_file_is_the_papers_nylon():
    yarn = read_yarn(NYLON_FILE)
    labels = ("name", "source")
    assert yarn.model_dump(exclude=labels) == PAPER_NYLON.model_dump(exclude=labels)
    m = yarn.material(9.74e-3)
    assert m.f0 == pytest.approx(kl.NYLON.f0, rel=1e-12) and m.c_b == pytest.approx(kl.NYLON.c_b, rel=1e-12)
    assert m.f0 == pytest.approx(14.8e-3, rel=0.01) and m.c_b == pytest.approx(30.6, rel=0.01)  # the paper's


def test_a_yarns_scales_follow_its_diameter_density_and_rigidity():
    """f0 = B kappa0^2 and c_b = kappa0 sqrt(B/rho_L), kappa0 = 2 pi/l0, B = E pi d^4/64 unless given (paper, main
    text); rho_L from tex (1 tex = 1e-6 kg/m) or from the density, rho pi d^2/4."""
    l0 = 12e-3
    m = Yarn(**THICKER).material(l0)
    kappa0 = 2 * math.pi / l0
    b = 2.5e9 * math.pi * 0.2e-3**4 / 64
    assert m.f0 == pytest.approx(b * kappa0**2, rel=1e-12)
    assert m.c_b == pytest.approx(kappa0 * math.sqrt(b / 30e-6), rel=1e-12)
    soft = Yarn(**THICKER, bending_rigidity_N_m2=b / 10).material(l0)  # a multifilament: B below the solid rod's
    assert soft.bending_stiffness == b / 10 and soft.stretching_stiffness == m.stretching_stiffness
    assert soft.f0 == pytest.approx(m.f0 / 10) and soft.twisting_stiffness == pytest.approx(b / 10 / 1.4)
    dense = Yarn(**{**THICKER, "linear_density_tex": None}, density_kg_m3=1140.0).material(l0)
    assert dense.line_density == pytest.approx(1140.0 * math.pi * 0.2e-3**2 / 4)


@pytest.mark.parametrize("change, says", [
    ({"linear_density_tex": None}, "give linear_density_tex or density_kg_m3"),
    ({"density_kg_m3": 1140.0}, "give linear_density_tex or density_kg_m3"),
    ({"diameter_mm": -1}, "diameter_mm"),
    ({"colour": "red"}, "colour"),
    ({"torsional_rigidity_N_m2": 1e-8, "poisson_ratio": 0.4}, "not both"),
])
def test_a_bad_yarn_file_is_one_line_naming_the_file_and_the_field(tmp_path, change, says):
    data = {k: v for k, v in {**THICKER, **change}.items() if v is not None}
    path = tmp_path / "y.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(YarnError) as e:
        read_yarn(path)
    assert str(path) in str(e.value) and says in str(e.value) and "\n" not in str(e.value)


def test_a_yarn_file_that_is_no_yarn_file_is_refused(tmp_path):
    for text, says in (("- a list\n", "a mapping"), ("a: [\n", "not a YAML text"), ("x" * 70_000, "larger than")):
        path = tmp_path / "y.yaml"
        path.write_text(text)
        with pytest.raises(YarnError, match=says):
            read_yarn(path)
    with pytest.raises(YarnError, match="a folder"):
        read_yarn(tmp_path)


def test_the_stitch_length_sets_d_over_l0_and_the_yarn_its_friction():
    cfg = CutConfig(n_x=6, n_y=6, fx=4, yarn=str(NYLON_FILE), stitch_length_mm=12.0)
    assert cfg.d_over_l0 == pytest.approx(0.14 / 12.0) and cfg.material().stitch_length == pytest.approx(12e-3)
    assert cfg.mu == 0.4  # the yarn's friction
    assert CutConfig(n_x=6, n_y=6, fx=4, yarn=THICKER | {"friction": 0.3}, stitch_length_mm=12.0).mu == 0.3
    assert CutConfig(n_x=6, n_y=6, fx=4, yarn=THICKER | {"friction": 0.3}, stitch_length_mm=12.0, mu=0.5).mu == 0.5
    # the paper's Nylon at another stitch length; without either, the paper's own knit
    assert CutConfig(n_x=6, n_y=6, fx=4, stitch_length_mm=14.0).material() == dataclasses.replace(
        kl.NYLON, stitch_length=14e-3)
    assert CutConfig(n_x=6, n_y=6, fx=4).material() == kl.NYLON


@pytest.mark.parametrize("settings, says", [
    ({"fx": 4, "stitch_length_mm": 1.0}, "stitch_length_mm: a yarn of 0.14 mm at 1 mm per stitch is d/l0 = 0.14"),
    ({"fx": 4, "yarn": THICKER}, "stitch_length_mm: a yarn needs its knit's stitch length"),
    ({"fx": 4, "stitch_length_mm": 10.0, "d_over_l0": 0.02}, "give one of them"),
    ({"fx": 4, "yarn": "/no/such/yarn.yaml", "stitch_length_mm": 10.0}, "yarn: /no/such/yarn.yaml: cannot read"),
    ({"lx": 0.3, "wales_per_cm": 3.0}, "wales_per_cm: 3 per cm at a stitch length of 9.74 mm is lx"),
    ({"fx": 4, "wales_per_cm": 3.0}, "wales_per_cm: sets lx"),
])
def test_a_knit_that_cannot_be_built_or_is_given_twice_is_refused_naming_the_field(settings, says):
    with pytest.raises(ValidationError) as e:
        CutConfig(n_x=6, n_y=6, **settings)
    assert says in str(e.value)


def test_wales_and_courses_per_cm_are_the_stretch_and_follow_a_new_stitch_length():
    cfg = CutConfig(n_x=6, n_y=6, stitch_length_mm=10.0, wales_per_cm=2.5, courses_per_cm=3.6)
    assert (cfg.lx, cfg.ly) == pytest.approx((0.4, 1 / 3.6))
    longer = cfg.replace(stitch_length_mm=12.5)  # the same counts per cm of a longer stitch: less stretched
    assert (longer.lx, longer.ly) == pytest.approx((0.32, 0.8 / 3.6))
    assert longer.d_over_l0 == pytest.approx(0.14 / 12.5)


def test_a_new_yarn_in_replace_brings_its_friction_unless_the_run_set_one():
    a = CutConfig(n_x=6, n_y=6, fx=4, yarn=THICKER | {"friction": 0.3}, stitch_length_mm=12.0)
    b = a.replace(yarn=THICKER | {"friction": 0.6})
    assert b.mu == 0.6
    assert a.replace(mu=0.2).replace(yarn=THICKER | {"friction": 0.6}).mu == 0.2


def test_a_resolved_config_validates_again_to_itself():
    """A sweep's job is its resolved config: its dump (d_over_l0, mu, lx made from the yarn and knit) must
    validate to the same config."""
    cfg = CutConfig(n_x=6, n_y=6, yarn=str(NYLON_FILE), stitch_length_mm=11.0, wales_per_cm=2.5)
    assert CutConfig.model_validate(cfg.model_dump()) == cfg


def test_the_periodised_stitchs_tension_is_the_same_in_f0_for_a_yarn_k_times_stiffer():
    """Dimensional analysis: at fixed l_x/l0, l_y/l0 and d/l0 the stitch's statics depend on its rigidities only
    through f0 = B kappa0^2 (the contact's stiffness is given in f0). A yarn with E and B both 4 times the Nylon's
    carries the same f_x, so 4 times the force in newtons; a yarn and stitch both 1.5 times longer (the same d/l0)
    the same f_x too. Any path that took the Nylon's scales instead of the yarn's breaks it."""
    from knitlad.fabric.stitch_model import StitchRun

    def run(yarn, l0_mm):
        cfg = StitchConfig(lx=0.36, ly=0.25, preset="fast", yarn=yarn, stitch_length_mm=l0_mm)
        return StitchRun(cfg.settings()).run(), cfg.material()

    nylon = PAPER_NYLON.model_dump()
    base, m = run(nylon, 9.74)
    stiff, m4 = run({**nylon, "young_modulus_GPa": 4 * 1.88}, 9.74)
    big, m15 = run({**nylon, "diameter_mm": 0.21}, 9.74 * 1.5)
    assert m4.f0 == pytest.approx(4 * m.f0) and m15.f0 != pytest.approx(m.f0)
    assert base.fx > 0.5  # a stretched stitch: a tension to compare
    assert stiff.fx == pytest.approx(base.fx, rel=2e-3) and stiff.fy == pytest.approx(base.fy, rel=2e-3, abs=2e-3)
    assert big.fx == pytest.approx(base.fx, rel=2e-3)


def test_scales_of_a_yarn_on_the_command_line(tmp_path):
    from tests.conftest import knitlad

    path = tmp_path / "thick.yaml"
    path.write_text(yaml.safe_dump(THICKER))
    p = knitlad("scales", "--yarn", str(path), "--stitch-length-mm", "12")
    assert p.returncode == 0, p.stderr
    printed = dict(line.split() for line in p.stdout.strip().splitlines())
    assert float(printed["f0_N"]) == pytest.approx(Yarn(**THICKER).material(12e-3).f0, rel=1e-5)
    assert float(printed["d_over_l0"]) == pytest.approx(0.2 / 12, rel=1e-5)


def test_a_cut_with_a_bad_yarn_file_is_one_line_and_starts_nothing(tmp_path):
    from tests.conftest import knitlad, one_line_error

    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump({**THICKER, "diameter_mm": 0}))
    line = one_line_error(knitlad("cut", "--stitches", "6", "--fx", "4", "--yarn", str(path), "--stitch-length-mm",
                                  "12", "--out", str(tmp_path / "o")))
    assert line.startswith("knitlad: error: --yarn:") and "diameter_mm" in line
    assert not (tmp_path / "o").exists()


def test_a_sweep_takes_a_yarn_file_and_its_jobs_carry_the_yarn_itself(tmp_path):
    """A job is its resolved config: the yarn's values, not its file's path (which may change under it)."""
    from knitlad.studies.sweep import load_sweep

    path = tmp_path / "thick.yaml"
    path.write_text(yaml.safe_dump(THICKER))
    sweep = tmp_path / "s.yaml"
    sweep.write_text(yaml.safe_dump({"scene": "ladder", "fixed": {"n_x": 6, "n_y": 6, "yarn": str(path),
                                                                  "stitch_length_mm": 12.0},
                                     "sweep": {"axes": {"fx": [2.0, 4.0]}}}))
    _, jobs = load_sweep(sweep)
    assert len(jobs) == 2 and jobs[0].params["yarn"]["diameter_mm"] == 0.2
    assert jobs[0].scene_config().material().f0 == pytest.approx(Yarn(**THICKER).material(12e-3).f0)


def test_a_ladder_of_another_yarn_reports_its_results_in_newtons_and_metres_per_second(tmp_path):
    """The same knit in l0 (d/l0 = 1/70) of a yarn 0.2 mm thick: the file's scales are the yarn's, and the summary's
    SI columns are the paper's units times them: F_x = f_x n_y f0, per cm of the width n_x l_x, v = (v/c_b) c_b."""
    import json

    import h5py

    from tests.conftest import knitlad

    path = tmp_path / "thick.yaml"
    path.write_text(yaml.safe_dump(THICKER))
    p = knitlad("cut", "--stitches", "6", "--preset", "fast", "--lx", "0.40", "--yarn", str(path),
                "--stitch-length-mm", "14", "--max-time-ms", "1", "--out", str(tmp_path / "o"), "--json")
    assert p.returncode == 0, p.stderr
    s = json.loads(p.stdout.strip().splitlines()[-1])
    m = Yarn(**THICKER).material(14e-3)
    assert s["force_ini_N"] == pytest.approx(s["fx_ini"] * 6 * m.f0, rel=1e-9)
    assert s["force_ini_N_per_cm"] == pytest.approx(s["force_ini_N"] / (6 * s["lx_over_l0"] * 1.4), rel=1e-9)
    assert s["l0_mm"] == pytest.approx(14.0) and s["lx_mm"] == pytest.approx(14.0 * s["lx_over_l0"])
    if s["v_lad_over_cb"] is not None:  # JSON's null: no front to fit in 1 ms
        assert s["v_lad_m_s"] == pytest.approx(s["v_lad_over_cb"] * m.c_b, rel=1e-9)
    else:
        assert s["v_lad_m_s"] is None
    with h5py.File(tmp_path / "o" / "ladder.h5") as f:
        assert f.attrs["scale_f0_N"] == pytest.approx(m.f0, rel=1e-12)
        assert f.attrs["scale_c_b_m_per_s"] == pytest.approx(m.c_b, rel=1e-12)
