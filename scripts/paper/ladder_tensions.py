"""The paper's DER points: `knitlad cut` at f_x^ini = 1.58, 4, 8, 13.6, 15.67 (l_y/l0 = 0.25).

    python scripts/paper/ladder_tensions.py [--stitches 42] [--preset default] [--fx 1.58 4 8 13.6 15.67]
                                      [--twist] [--cut-args="--twist-inertia-factor 4"]

Prints a table beside the paper's values (DER, 42 x 42, mu = 0.4: v_lad/c_b =
0.176 at f_x^ini = 1.58 and 1.05 at 15.67; the points between are read off
Fig. 5a only roughly, so they are not printed).
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import tempfile

PAPER_V = {1.58: 0.176, 15.67: 1.05}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--stitches", default="42")
    p.add_argument("--preset", default="default", choices=["fast", "default", "accurate"])
    p.add_argument("--resolution", type=int, default=None, help="nodes per stitch (default: the preset's)")
    p.add_argument("--fx", type=float, nargs="+", default=[1.58, 4.0, 8.0, 13.6, 15.67])
    p.add_argument("--twist", action="store_true", help="the yarns carry twist (knitlad cut --twist)")
    p.add_argument("--cut-args", default="", help="further options of `knitlad cut`, as one string")
    args = p.parse_args()
    extra = (["--twist"] if args.twist else []) + shlex.split(args.cut_args)
    print(f"{'fx target':>9s} {'fx_ini':>7s} {'fx_fin':>7s} {'n_lad/n_y':>9s} {'v_lad/c_b':>9s} {'paper v':>8s} "
          f"{'l_x/l0':>7s} {'l_y/l0':>7s} {'wall s':>7s}  stop")
    for fx in args.fx:
        with tempfile.TemporaryDirectory() as out:
            proc = subprocess.run(
                [sys.executable, "-m", "knitlad.cli", "cut", "--fx", str(fx), "--stitches", args.stitches,
                 "--preset", args.preset, *(["--resolution", str(args.resolution)] if args.resolution else []),
                 "--out", out, "--json", *extra],
                capture_output=True, text=True,
            )
        if proc.returncode != 0:
            print(f"{fx:9.2f} failed: {proc.stderr.strip().splitlines()[-1] if proc.stderr else proc.returncode}")
            continue
        s = json.loads(proc.stdout.strip().splitlines()[-1])
        paper = PAPER_V.get(fx)
        print(f"{fx:9.2f} {s['fx_ini']:7.2f} {s['fx_fin']:7.2f} {s['n_lad_over_ny']:9.2f} {s['v_lad_over_cb']:9.3f} "
              f"{paper if paper is not None else float('nan'):8.3f} {s['lx_over_l0']:7.3f} {s['ly_over_l0']:7.3f} "
              f"{s['wall_s']:7.0f}  {s['stop_reason']}", flush=True)


if __name__ == "__main__":
    main()
