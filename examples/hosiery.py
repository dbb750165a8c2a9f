"""Your own yarn and knit: a sheer-hosiery monofilament (20 den nylon 6,6, configs/yarns/nylon_mono_20den.yaml)
knitted at 2.5 mm per stitch and worn at 10.5 wales and 16 courses per cm, laddered from one cut loop.

    python examples/hosiery.py            # its scales, then a 12 x 12 ladder (fast preset, about 10 s)

docs/own_yarn.md walks through the same fabric on the command line: its tensile curve in N per 5 cm, its ladder
at the wearing stretch in N/cm and m/s, and whether a rib band holds the ladder.
"""

from __future__ import annotations

from pathlib import Path

from knitlad import CutConfig, run_ladder
from knitlad.experiments.yarn import read_yarn

YARN = Path(__file__).resolve().parents[1] / "configs" / "yarns" / "nylon_mono_20den.yaml"


def worn_stocking(stitches: int = 12, **changes) -> CutConfig:
    """The stocking as worn: the yarn at 2.5 mm per stitch, stretched to 10.5 wales and 16 courses per cm."""
    return CutConfig(n_x=stitches, n_y=stitches, preset="fast", yarn=read_yarn(YARN), stitch_length_mm=2.5,
                     wales_per_cm=10.5, courses_per_cm=16, **changes)


def ladder(stitches: int = 12, **changes) -> dict:
    """The ladder of one cut loop: the summary row, in the paper's units and in N, N/cm and m/s."""
    return run_ladder(worn_stocking(stitches, **changes).settings()).summary()


if __name__ == "__main__":
    cfg = worn_stocking()
    m = cfg.material()
    print(f"{read_yarn(YARN).name}: d/l0 = {cfg.d_over_l0:.4f}, f0 = {m.f0 * 1e3:.2f} mN, c_b = {m.c_b:.1f} m/s, "
          f"breaking force {m.breaking_force:.2f} N")
    s = ladder()
    print(f"worn at l_x = {s['lx_mm']:.3f} mm, l_y = {s['ly_mm']:.3f} mm: F_x = {s['force_ini_N_per_cm']:.3f} N/cm "
          f"(f_x^ini = {s['fx_ini']:.2f})")
    print(f"one cut loop undoes {s['n_lad']} cells (n_lad/n_y = {s['n_lad_over_ny']:.2f}); the ladder runs at "
          f"{s['v_lad_m_s']:.1f} m/s (v_lad/c_b = {s['v_lad_over_cb']:.3f}); {s['stop_reason']}")
