"""Benchmark: `knitlad cut` on a full knit; wall time per stage and node-steps/s.

    python scripts/bench_cut.py [--fx 13.6] [--stitches 42] [--resolution 24]

Runs the CLI in a subprocess (as a user would, compile time included on a cold
cache) and prints the summary's timing fields.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fx", type=float, default=13.6)
    p.add_argument("--stitches", default="42")
    p.add_argument("--resolution", type=int, default=24)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as out:
        t = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "knitlad.cli", "cut", "--fx", str(args.fx), "--stitches", args.stitches,
             "--resolution", str(args.resolution), "--out", out, "--json"],
            capture_output=True, text=True,
        )
        total = time.perf_counter() - t
    if proc.returncode != 0:
        sys.exit(proc.stderr)
    s = json.loads(proc.stdout.strip().splitlines()[-1])
    node_steps = s["nodes"] * (s["steps"] + s["relax_steps"])
    print(f"knit {args.stitches}, {args.resolution} nodes/stitch: {s['nodes']} nodes")
    print(f"  stretch + relax : {s['wall_stretch_s']:8.1f} s  ({s['relax_steps']} FIRE steps)")
    print(f"  cut + propagate : {s['wall_propagate_s']:8.1f} s  ({s['steps']} steps)")
    print(f"  process total   : {total:8.1f} s  (includes start-up and compilation)")
    print(f"  node-steps/s    : {node_steps / s['wall_s']:.3e}")
    print(f"  f_x^ini {s['fx_ini']:.2f}, f_x^fin {s['fx_fin']:.2f}, n_lad/n_y {s['n_lad_over_ny']:.2f}, "
          f"v_lad/c_b {s['v_lad_over_cb']:.3f}, stop: {s['stop_reason']}")


if __name__ == "__main__":
    main()
