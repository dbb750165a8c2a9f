"""Benchmark: `knitlad cut` on a full knit, per preset and with twist off and on.

    python scripts/bench/bench_cut.py [--fx 13.6] [--stitches 42] [--presets default accurate]
                                [--twist off on] [--axial explicit implicit] [--threads 2]
                                [--load quiet loaded]

For each run: wall time per stage (stretch, cut + propagate), steps, node-steps/s of
the dynamics, and that rate over the rate of a lean stretch + bend kernel (one
straight-at-rest rod, ``scripts/bench/bench_rod.py``) timed in the same process on one
thread, so the figures compare across machines. The first run of a fresh clone
also pays Numba's compilation (printed apart: a warm-up run on a 6 x 6 knit first).
"""

from __future__ import annotations

import argparse
import itertools
import subprocess
import sys
import time
from pathlib import Path

from knitlad.experiments.config import CutConfig
from knitlad.experiments.laddering import run_ladder
from knitlad.engine.simulation import numba_threads


def _lean_kernel():
    """``build`` and ``measure`` of ``bench_rod.py`` beside this file (a script, not a module of the package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_rod", Path(__file__).with_name("bench_rod.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.build, module.measure


build, measure = _lean_kernel()


def lean_rate() -> float:
    """node-steps/s of the lean stretch + bend kernel on one thread (20,000 nodes)."""
    with numba_threads(1):
        return measure(build(20_000), 1_000)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fx", type=float, default=13.6)
    p.add_argument("--stitches", type=int, default=42)
    p.add_argument("--presets", nargs="+", default=["default", "accurate"], choices=["fast", "default", "accurate"])
    p.add_argument("--twist", nargs="+", default=["off", "on"], choices=["off", "on"])
    p.add_argument("--axial", nargs="+", default=["preset"], choices=["preset", "explicit", "implicit"],
                   help="the axial springs of the dynamics (implicit_axial; preset: the preset's)")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--load", nargs="+", default=["quiet"], choices=["quiet", "loaded"],
                   help="loaded: a second process busy on one core during the run (a pure-Python loop)")
    args = p.parse_args()
    t = time.perf_counter()
    with numba_threads(args.threads):
        for preset in args.presets:
            run_ladder(CutConfig(n_x=6, n_y=6, fx=4.0, twist=True, max_time_ms=0.2, preset=preset).settings())
            run_ladder(CutConfig(n_x=6, n_y=6, fx=4.0, max_time_ms=0.2, preset=preset).settings())
    print(f"warm-up (compilation on a fresh clone): {time.perf_counter() - t:.1f} s")
    lean = lean_rate()
    print(f"lean stretch + bend kernel, 1 thread: {lean:.3e} node-steps/s\n")
    print(f"| {args.stitches} x {args.stitches}, f_x {args.fx:g} | machine | twist | axial | nodes | stretch [s] | cut + propagate [s] "
          "| total [s] | steps | node-steps/s | / lean | f_x^ini | v_lad/c_b | n_lad/n_y | f_x^fin |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for preset, twist, axial, load in itertools.product(args.presets, args.twist, args.axial, args.load):
        cfg = CutConfig(n_x=args.stitches, n_y=args.stitches, fx=args.fx, preset=preset, twist=twist == "on",
                        implicit_axial=None if axial == "preset" else axial == "implicit")
        busy = subprocess.Popen([sys.executable, "-c", "while True: pass"]) if load == "loaded" else None
        try:
            with numba_threads(args.threads):
                r = run_ladder(cfg.settings())
        finally:
            if busy:
                busy.kill()
        stretch_s, propagate_s = r.wall_s["stretch"], r.wall_s["propagate"]
        rate = r.nodes * r.steps / propagate_s
        print(f"| {preset} ({cfg.resolution}) | {load} | {twist} | {'implicit' if cfg.implicit_axial else 'explicit'} | {r.nodes} | {stretch_s:.1f} | "
              f"{propagate_s:.1f} | {stretch_s + propagate_s:.1f} | {r.steps} | {rate:.3e} | {rate / lean:.2f} | "
              f"{r.fx_ini:.2f} | {r.v_lad_over_cb:.3f} | {r.n_lad_over_ny:.2f} | {r.fx_fin:.2f} |", flush=True)


if __name__ == "__main__":
    main()
