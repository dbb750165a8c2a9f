"""Speed of the reduced models (goals: one single-loop run < 10 s, one stitch relaxation < 5 s).

    python scripts/bench/bench_reduced.py [--repeat 3]

Compiles first (not timed), then times `knitlad loop` runs (f_x = 4 and 16, mu = 0.4) and
`knitlad stitch` relaxations (l_x/l0 = 0.30, 0.35, 0.40 at l_y/l0 = 0.25), in this process.
"""

from __future__ import annotations

import argparse
import time

from knitlad.experiments.config import LoopConfig
from knitlad.experiments.loop_model import LoopRun
from knitlad.experiments.config import StitchConfig
from knitlad.fabric.stitch_model import StitchRun


def timed(make, repeat: int) -> tuple[float, object]:
    best, result = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        result = make()
        best = min(best, time.perf_counter() - t)
    return best, result


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args()
    t = time.perf_counter()
    LoopRun(LoopConfig(fx=4.0, mu=0.4, max_time_ms=2e-2).settings()).run()
    StitchRun(StitchConfig(lx=0.30).settings()).run()
    print(f"compile / cache load: {time.perf_counter() - t:.1f} s")
    for fx in (4.0, 16.0):
        wall, r = timed(lambda: LoopRun(LoopConfig(fx=fx, mu=0.4).settings()).run(), args.repeat)
        steps = r.steps
        print(f"single loop f_x = {fx:4.1f}, mu = 0.4: {wall:6.3f} s (goal < 10 s), {steps} steps, "
              f"{r.nodes} nodes, {r.nodes * steps / wall:.3g} node-steps/s, released = {r.released}")
    for lx in (0.30, 0.35, 0.40):
        wall, r = timed(lambda: StitchRun(StitchConfig(lx=lx, ly=0.25).settings()).run(), args.repeat)
        print(f"stitch l_x/l0 = {lx:.2f}: {wall:6.3f} s (goal < 5 s), {r.relax_steps} FIRE steps, f_x = {r.fx:.3f}")


if __name__ == "__main__":
    main()
