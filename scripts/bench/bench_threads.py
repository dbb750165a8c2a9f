"""Benchmark: laddering steps per second against Numba's threading layer and thread count,
on a quiet machine and with a second process busy on one core.

    python scripts/bench/bench_threads.py [--stitches 16] [--preset default] [--steps 3000]
                                    [--layers omp workqueue] [--threads 1 2] [--repeats 3]

Each measurement is a fresh process (a threading layer is chosen once per process): it
reads a stretched knit (made once, kept in --knit), cuts it, steps 500 steps to warm up,
then times --steps steps, with the thread governor of ``Simulation.step`` on or off. "loaded" runs a pure-Python busy loop beside it for the whole
measurement, the way a second run or a browser takes a core. Prints the median node-steps/s
of --repeats measurements and each one's ratio to one thread of the same layer alone.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

WORKER = """
import json, sys, time
import numba
from knitlad.experiments.config import CutConfig
from knitlad.io.hdf5 import read_stretched_knit
from knitlad.experiments.laddering import cut
knit = read_stretched_knit(sys.argv[1])
cfg = CutConfig(n_x=knit.settings.n_x, n_y=knit.settings.n_y, fx=4.0, preset=sys.argv[2])
run = cut(knit, cfg.dynamics_settings())
if sys.argv[4] == "off":  # the thread governor never probes: the count given is the count used
    run.sim.threads.until_probe = 10**12
run.sim.step(500)
t = time.perf_counter()
run.sim.step(int(sys.argv[3]))
wall = time.perf_counter() - t
print(json.dumps({"rate": run.sim.state.x.shape[0] * int(sys.argv[3]) / wall, "layer": numba.threading_layer()}))
"""

BUSY = "while True: pass"


def make_knit(path: Path, stitches: int, preset: str) -> None:
    from knitlad.experiments.config import CutConfig
    from knitlad.io.hdf5 import write_stretched_knit
    from knitlad.fabric.preparation import stretch

    if not path.exists():
        cfg = CutConfig(n_x=stitches, n_y=stitches, fx=4.0, preset=preset)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_stretched_knit(path, stretch(cfg.stretch_settings()))


def measure(knit: Path, preset: str, steps: int, layer: str, threads: int, loaded: bool, governor: str) -> float:
    name, _, policy = layer.partition("+")  # omp+passive: OpenMP's threads sleep at barriers instead of spinning
    env = {**os.environ, "NUMBA_THREADING_LAYER": name, "NUMBA_NUM_THREADS": str(threads)}
    if policy:
        env["OMP_WAIT_POLICY"] = policy.upper()
    busy = subprocess.Popen([sys.executable, "-c", BUSY]) if loaded else None
    try:
        out = subprocess.run([sys.executable, "-c", WORKER, str(knit), preset, str(steps), governor], env=env, check=True,
                             capture_output=True, text=True)
    finally:
        if busy:
            busy.kill()
            busy.wait()
    return json.loads(out.stdout.strip().splitlines()[-1])["rate"]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--stitches", type=int, default=16)
    p.add_argument("--preset", default="default", choices=["fast", "default", "accurate"])
    p.add_argument("--steps", type=int, default=3000)
    p.add_argument("--layers", nargs="+", default=["omp", "omp+passive", "workqueue"],
                   help="Numba threading layers; omp+passive sets OMP_WAIT_POLICY=PASSIVE")
    p.add_argument("--threads", nargs="+", type=int, default=[1, 2])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--governor", nargs="+", default=["off", "on"], choices=["off", "on"],
                   help="the thread governor of Simulation.step (off: the given count throughout)")
    p.add_argument("--knit", type=Path, default=Path("runs/bench/knit{n}_{preset}.h5"))
    args = p.parse_args()
    knit = Path(str(args.knit).format(n=args.stitches, preset=args.preset))
    make_knit(knit, args.stitches, args.preset)
    print(f"{time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores, {args.stitches} x {args.stitches}, preset "
          f"{args.preset}, {args.steps} steps; node-steps/s, median of {args.repeats}")
    print("| layer | threads | governor | quiet | loaded | loaded / quiet | loaded / 1 thread quiet |")
    print("|---|---|---|---|---|---|---|")
    for layer in args.layers:
        one = None
        for threads in args.threads:
            for governor in (args.governor if threads > 1 else ["off"]):
                rates = {}
                for loaded in (False, True):
                    rates[loaded] = statistics.median(
                        measure(knit, args.preset, args.steps, layer, threads, loaded, governor)
                        for _ in range(args.repeats))
                one = one or (rates[False] if threads == 1 else None)
                base = f"{rates[True] / one:.2f}" if one else "-"
                print(f"| {layer} | {threads} | {governor} | {rates[False]:.3e} | {rates[True]:.3e} | "
                      f"{rates[True] / rates[False]:.2f} | {base} |", flush=True)


if __name__ == "__main__":
    main()
