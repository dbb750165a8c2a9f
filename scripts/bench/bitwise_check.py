"""Refactoring check: the positions of a 16 x 16 ladder after 3,000 steps past the cut, to the bit.

    python scripts/bench/bitwise_check.py --save runs/bitwise.npz      # before a change
    python scripts/bench/bitwise_check.py --compare runs/bitwise.npz   # after it: identical, or where it differs
    python scripts/bench/bitwise_check.py --twist --save runs/bitwise_twist.npz   # the yarns carrying twist
    python scripts/bench/bitwise_check.py --natural-curvature 0.1 --save runs/bitwise_k.npz   # framed DER

The knit is stretched to f_x^ini = 8 by force control (preset fast by default: 24 nodes per stitch), cut, and
stepped 3,000 times. A change that only moves code must leave every position and
velocity identical (same machine, same Numba version and threads). It imports only knitlad's public
names, so that a reference saved by one layout of the package compares with another.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from knitlad import CutConfig, cut, stretch


def ladder_after_3000_steps(twist: bool, natural_curvature: float = 0.0, preset: str = "fast") -> dict:
    cfg = CutConfig(n_x=16, n_y=16, fx=8.0, twist=twist or natural_curvature > 0, preset=preset,
                    natural_curvature=natural_curvature)
    knit = stretch(cfg.stretch_settings())
    run = cut(knit, cfg.dynamics_settings())
    run.sim.step(3000)
    return {"stretched": knit.knit.rods.state.x, "x": run.sim.state.x, "v": run.sim.state.v,
            "theta": run.sim.state.theta, "fx": knit.fx_ini, "dt": run.sim.dt}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = p.add_mutually_exclusive_group(required=True)
    group.add_argument("--save", help="write the reference (.npz)")
    group.add_argument("--compare", help="compare with a reference (.npz)")
    p.add_argument("--twist", action="store_true", help="the yarns carry twist (frame-free, straight at rest)")
    p.add_argument("--natural-curvature", type=float, default=0.0,
                   help="the yarn's memory K (> 0: twist on, framed DER)")
    p.add_argument("--preset", default="fast", choices=["fast", "default", "accurate"],
                   help="accuracy preset (fast: 24 nodes per stitch, explicit axial springs; default: 48, implicit)")
    args = p.parse_args()
    t = time.perf_counter()
    now = ladder_after_3000_steps(args.twist, args.natural_curvature, args.preset)
    if args.save:
        np.savez(args.save, **now)
        print(f"saved {args.save} ({time.perf_counter() - t:.0f} s)")
        return
    ref = np.load(args.compare)
    for key in ("stretched", "x", "v", "theta"):
        same = np.array_equal(now[key], ref[key])
        print(f"{key:10s} identical: {same}" + ("" if same else f"  (max |diff| {np.abs(now[key] - ref[key]).max():.3e})"))
    print(f"f_x^ini {now['fx']} (reference {float(ref['fx'])}), dt {now['dt']} (reference {float(ref['dt'])}); "
          f"{time.perf_counter() - t:.0f} s")


if __name__ == "__main__":
    main()
