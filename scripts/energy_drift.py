"""Energy bookkeeping of the contact without any damping (the hard cases).

Two undamped, frictionless scenes, each at three time steps and with each contact
counting ("union", the default, and "all_pairs", conservative):

* ``ladder``: a 6 x 8 jersey (16 nodes/stitch) stretched to f_x^ini = 13.6 (FIRE,
  mu = 0), then cut and left to ladder with no dashpot anywhere and mu = 0;
  the total energy (kinetic + elastic + contact) is sampled every 0.1 ms for 2 ms.
  The held course ends do not move, so no external work is done.
* ``weave``: the pressed plain weave of ``tests/validation/test_hard_cases.py``
  (crossings 3 % of d into each other at t = 0), every 0.05 ms for 0.4 ms.

Velocity Verlet on a conservative force keeps the energy error bounded and
shrinking with dt; a drift that does not fall with dt comes from the force
field itself (here: the once-per-minimum union counting, see the README).

    python scripts/energy_drift.py [--scenes ladder weave] [--safety 0.7 0.35 0.175] [--counting union all_pairs]
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import knitlad as kl  # noqa: E402
from knitlad.contact import COUNTING, ContactModel  # noqa: E402
from knitlad.config import CutConfig  # noqa: E402
from knitlad.protocol import cut, stretch  # noqa: E402
from knitlad.scenes.weave import plain_weave  # noqa: E402
from knitlad.simulation import energy_history  # noqa: E402


def undamped_contact(counting: str, material=kl.NYLON) -> ContactModel:
    return ContactModel.for_force(20 * material.f0, material.diameter, friction=0.0,
                                  damping_ratio=0.0, tangential_damping_ratio=0.0, counting=counting)


def ladder_energy(safety: float, counting: str, samples: int = 20, every_s: float = 0.1e-3) -> dict:
    cfg = CutConfig(preset="fast", n_x=6, n_y=8, resolution=16, fx=13.6, mu=0.0, dt_safety=safety, contact_damping_ratio=0.0,
                    stretch_damping_ratio=0.0, contact_counting=counting)
    knit = stretch(cfg.stretch_settings())  # FIRE with its own dashpots; the settings above take effect at the cut
    sim = cut(knit, cfg.dynamics_settings()).sim
    sim.state.v[:] = 0.0
    return sample(sim, samples, every_s) | {"fx_ini": knit.fx_ini}


def weave_energy(safety: float, counting: str, samples: int = 8, every_s: float = 0.05e-3) -> dict:
    d = kl.NYLON.diameter
    rods = plain_weave(4, 1.0e-3, nodes_per_spacing=8, amplitude=0.47 * d).build(stretch_damping_ratio=0.0)
    return sample(kl.Simulation(rods, contact=undamped_contact(counting), safety=safety), samples, every_s)


def sample(sim: kl.Simulation, samples: int, every_s: float) -> dict:
    t0 = time.perf_counter()
    total, kinetic = energy_history(sim, samples, every_s)
    e0 = total[0]
    return {
        "dt_s": sim.dt_s,
        "drift_over_total": float(np.max(np.abs(total[1:] / e0 - 1.0))),
        "drift_over_peak_kinetic": float(np.max(np.abs(total[1:] - e0)) / max(kinetic[1:].max(), 1e-300)),
        "final_over_total": float(total[-1] / e0 - 1.0),
        "wall_s": time.perf_counter() - t0,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", nargs="+", default=["ladder", "weave"], choices=["ladder", "weave"])
    p.add_argument("--safety", type=float, nargs="+", default=[0.7, 0.35, 0.175],
                   help="time steps as fractions of the stability limit")
    p.add_argument("--counting", nargs="+", default=["union", "all_pairs"], choices=list(COUNTING))
    args = p.parse_args()
    runs = {"ladder": ladder_energy, "weave": weave_energy}
    print("| scene | counting | dt factor | dt [s] | max abs(E/E0 - 1) | max abs(E - E0) / peak kinetic | "
          "E/E0 - 1 at the end |")
    print("|---|---|---|---|---|---|---|")
    for scene in args.scenes:
        for counting in args.counting:
            for safety in args.safety:
                r = runs[scene](safety, counting)
                print(f"| {scene} | {counting} | {safety} | {r['dt_s']:.2e} | {r['drift_over_total']:.2e} | "
                      f"{r['drift_over_peak_kinetic']:.2e} | {r['final_over_total']:+.2e} |", flush=True)


if __name__ == "__main__":
    main()
