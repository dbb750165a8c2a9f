"""Side by side with PyElastica: the same Nylon rod problem, each code at its largest stable time step.

The problem: the paper's Nylon monofilament (d = 0.14 mm, rho_L = 15.8 mg/m,
E = 1.88 GPa), a straight horizontal rod of N elements of length 0.4 mm (the
knit's element at 24 nodes per stitch), clamped at its first element, released
from rest under gravity and followed for T = 2 ms. No damping in either code.

For each code and each N the script reports the time step used, node-steps/s,
the wall time to reach T, and the deviation between the two solutions at T
(largest distance between corresponding nodes over the largest displacement).
For N = 1000 both are also compared with a reference: knitlad with 4 times
finer elements and half its time step (the error of each code, so the speed
ratio is read at equal accuracy).

Time steps: knitlad runs at its own stability bound (``safety=1``, the largest
step it accepts: a Gershgorin bound, below the true limit); PyElastica
(PositionVerlet, the stepper of its examples) at 0.95 x its empirical limit,
found by bisection (a run of 4000 steps that stays finite and bounded).

Both codes run on one thread in the same process. PyElastica is not a knitlad
dependency: when ``import elastica`` fails, the script makes its own
environment ``.venv-pyelastica`` (pyelastica + this checkout) and reruns there.

    python scripts/bench/bench_pyelastica.py [--elements 1000 3000 10000] [--time-ms 2]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]  # the repository (this file: scripts/bench/)
BENCH_ENV = ROOT / ".venv-pyelastica"

# the paper's Nylon monofilament, SI
DIAMETER = 0.14e-3
LINE_DENSITY = 15.8e-6
YOUNG = 1.88e9
POISSON = 0.4  # knitlad's Material default; only PyElastica's shear modulus uses it
GRAVITY = 9.81
ELEMENT = 0.4e-3


def ensure_pyelastica() -> None:
    """Rerun this script in an environment that has PyElastica, making it if needed."""
    try:
        import elastica  # noqa: F401
        return
    except ImportError:
        pass
    py = BENCH_ENV / "bin" / "python"
    if os.environ.get("KNITLAD_BENCH_REEXEC"):
        sys.exit("PyElastica is still not importable in the benchmark environment; see the pip output above")
    if not py.exists():
        print(f"making {BENCH_ENV} with pyelastica (once) ...", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(BENCH_ENV)], check=True)
        subprocess.run([str(py), "-m", "pip", "install", "-q", "pyelastica", "-e", str(ROOT)], check=True)
    env = dict(os.environ, KNITLAD_BENCH_REEXEC="1")
    os.execve(str(py), [str(py), *sys.argv], env)


# --------------------------------------------------------------------------- knitlad
def knitlad_rod(n_elements: int, element: float, dt_factor: float = 1.0):
    import knitlad as kl
    from knitlad.engine import units

    pts = np.zeros((n_elements + 1, 3))
    pts[:, 0] = np.arange(n_elements + 1) * element
    scene = kl.Scene(kl.NYLON)
    rod = scene.add_yarn(pts)
    scene.hold(rod, [0, 1])  # the first element clamped, as PyElastica's OneEndFixedBC
    state = scene.build(twist=False, stretch_damping_ratio=0.0)
    state.f_ext[:, 1] = -state.mass * (GRAVITY * units.TIME**2 / units.LENGTH)
    sim = kl.Simulation(state, safety=1.0)
    sim.dt *= dt_factor
    return sim


def run_knitlad(n_elements: int, duration_s: float, element: float = ELEMENT, dt_factor: float = 1.0):
    from knitlad.engine.kernels.integrate import verlet_steps

    sim = knitlad_rod(n_elements, element, dt_factor)
    x0 = sim.positions_m().copy()
    steps = int(np.ceil(duration_s / sim.dt_s))
    sim.dt = duration_s / steps / 1e-3  # land exactly on T (internal ms)
    warm = knitlad_rod(8, element)
    verlet_steps(warm.state, warm.work, warm.contacts, warm.dt, 2, warm.twist, 0.0)  # compile outside the clock
    t = time.perf_counter()
    sim.step(steps)
    wall = time.perf_counter() - t
    return {"dt": sim.dt_s, "steps": steps, "wall": wall, "x": sim.positions_m(), "x0": x0}


# --------------------------------------------------------------------------- PyElastica
def pyelastica_rod(n_elements: int, element: float):
    import elastica as ea

    class Rod(ea.BaseSystemCollection, ea.Constraints, ea.Forcing):
        pass

    radius = DIAMETER / 2
    density = LINE_DENSITY / (np.pi * radius**2)
    system = Rod()
    rod = ea.CosseratRod.straight_rod(
        n_elements, np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]),
        n_elements * element, radius, density, youngs_modulus=YOUNG, shear_modulus=YOUNG / (2 * (1 + POISSON)),
    )
    system.append(rod)
    system.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,))
    system.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, -GRAVITY, 0.0]))
    system.finalize()
    return system, rod, ea.PositionVerlet()


def pyelastica_stable(dt: float, element: float, steps: int = 4000) -> bool:
    system, rod, stepper = pyelastica_rod(200, element)
    t = 0.0
    for _ in range(steps):
        t = stepper.step(system, t, dt)
    x = rod.position_collection
    free_fall = 0.5 * GRAVITY * t**2
    return bool(np.all(np.isfinite(x)) and np.max(np.abs(x[1])) < 10 * free_fall + 1e-9 and np.ptp(x[2]) < 1e-9)


def pyelastica_limit(element: float) -> float:
    lo, hi = 1e-9, 1e-5
    while hi / lo > 1.02:
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if pyelastica_stable(mid, element) else (lo, mid)
    return lo


def run_pyelastica(n_elements: int, duration_s: float, dt_max: float, element: float = ELEMENT):
    system, rod, stepper = pyelastica_rod(n_elements, element)
    x0 = rod.position_collection.T.copy()
    steps = int(np.ceil(duration_s / dt_max))
    dt = duration_s / steps
    warm_system, _, warm_stepper = pyelastica_rod(8, element)
    warm_stepper.step(warm_system, 0.0, dt)
    t_sim = 0.0
    t = time.perf_counter()
    for _ in range(steps):
        t_sim = stepper.step(system, t_sim, dt)
    wall = time.perf_counter() - t
    return {"dt": dt, "steps": steps, "wall": wall, "x": rod.position_collection.T.copy(), "x0": x0}


# --------------------------------------------------------------------------- comparison
def deviation(a: dict, b: dict) -> float:
    """Largest distance between corresponding nodes at T over the largest displacement."""
    scale = np.max(np.linalg.norm(a["x"] - a["x0"], axis=1))
    return float(np.max(np.linalg.norm(a["x"] - b["x"], axis=1)) / scale)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--elements", type=int, nargs="+", default=[1000, 3000, 10000])
    p.add_argument("--time-ms", type=float, default=2.0)
    args = p.parse_args()
    ensure_pyelastica()
    from importlib.metadata import version

    import numba

    import knitlad

    numba.set_num_threads(1)
    T = args.time_ms * 1e-3
    print(f"knitlad {knitlad.__version__}, PyElastica {version('pyelastica')}, numba {numba.__version__}, "
          "one thread each")
    print(f"Nylon rod, elements of {ELEMENT * 1e3} mm, clamped, under gravity, T = {args.time_ms} ms, no damping")
    dt_pe = 0.95 * pyelastica_limit(ELEMENT)
    print(f"PyElastica empirical stable limit {dt_pe / 0.95:.3e} s -> runs at {dt_pe:.3e} s")
    header = f"{'N':>6} {'code':>10} {'dt [s]':>10} {'steps':>7} {'wall [s]':>9} {'node-steps/s':>13} {'deviation':>10}"
    print(header)
    ratios = []
    for n in args.elements:
        k = run_knitlad(n, T)
        pe = run_pyelastica(n, T, dt_pe)
        dev = deviation(k, pe)
        for name, r in (("knitlad", k), ("PyElastica", pe)):
            rate = (n + 1) * r["steps"] / r["wall"]
            print(f"{n:6d} {name:>10} {r['dt']:10.3e} {r['steps']:7d} {r['wall']:9.2f} {rate:13.3e} {dev:10.2e}")
        ratios.append(pe["wall"] / k["wall"])
        print(f"{n:6d}   time to T: PyElastica / knitlad = {ratios[-1]:.1f}", flush=True)
        if n == args.elements[0]:
            ref = run_knitlad(4 * n, T, ELEMENT / 4, dt_factor=0.5)
            ref["x"], ref["x0"] = ref["x"][::4], ref["x0"][::4]
            print(f"{n:6d}   error against knitlad x4 elements, dt/2: knitlad {deviation(ref, k):.2e}, "
                  f"PyElastica {deviation(ref, pe):.2e}", flush=True)
    print(f"speed-up at equal simulated time: {', '.join(f'{r:.1f}' for r in ratios)}")


if __name__ == "__main__":
    main()
