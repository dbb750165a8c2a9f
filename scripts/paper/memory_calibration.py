"""The memory K as the paper measured it: a course freed of the knit, laid flat, its outline's curvature.

    python scripts/paper/memory_calibration.py [--K 0.05 0.25 1] [--preset fast] [--csv FILE]

The paper (appendix "Natural curvature") pulls a thread out of the fabric, photographs it lying on a
plane and reads (kbar/kappa0)^2 along its outline: about 1 on average, about 3.5 at most over four
stitches. Here, for each K (knitlad's mean of (kappa_bar/kappa0)^2 over the yarn, `--natural-curvature`):
a 4 x 4 knit with that memory is stretched to f_x^ini 4, a middle course is freed of its holds and of
contact and relaxed (FIRE, twist on), and its relaxed shape is read three ways: the 3-D mean of
(kappa/kappa0)^2 (which should give K back), and the outline laid flat on its best plane
(knitlad.fabric.shape_memory.flattened_curvature): mean and maximum of (kappa/kappa0)^2, the maximum as
the paper's "at most over four stitches" (the course spans four). Prints a markdown table.
"""

from __future__ import annotations

import argparse

import numpy as np
import pandas as pd

import knitlad as kl
from knitlad.experiments.config import CutConfig
from knitlad.fabric.shape_memory import flattened_curvature, positional_curvature
from knitlad.fabric.preparation import stretch
from knitlad.engine.simulation import Simulation


GRAVITY = 9.81  # m/s^2
PLANE_MU = 0.4  # the thread on the table: Nylon on a smooth surface, as yarn on yarn


def laid_on_plane(sim: Simulation, nodes: np.ndarray, mu: float = PLANE_MU, max_time_s: float = 0.2) -> np.ndarray:
    """The freed course ``nodes`` of the relaxed ``sim`` dropped under gravity onto a table (a ``kl.Plane`` with
    friction ``mu``) below its best-fitting plane, and left to come to rest there, as the paper's thread lay for
    its photograph; the rest of the knit held out of the way. Returns the course's resting positions [internal],
    projected on the table: the photograph's outline. Gravity (rho_L g = 0.16 mN/m) is weak beside the yarn's
    bending over a stitch (its bending length (B / rho_L g)^(1/3) is 61 mm, 6 l0): the thread rests on a few points
    and keeps its shape out of the table's plane, which the photograph (the projection) flattens."""
    x = sim.state.x
    course = x[nodes]
    centre = course.mean(axis=0)
    normal = np.linalg.svd(course - centre, full_matrices=False)[2][2]
    normal = normal if normal[2] >= 0 else -normal
    r = float(sim.model.radius[nodes].mean())
    below = float(np.min((course - centre) @ normal)) - r - 1e-3 * r
    point_m = tuple((centre + below * normal) * kl.units.LENGTH)
    m = sim.model
    held = np.ones(m.n_nodes, dtype=bool)
    held[nodes] = False
    rods = sim.rods.copy().replace_model(held=held, v_prescribed=np.zeros_like(m.v_prescribed))
    table = kl.Plane(stiffness=10.0, mu=mu, point_m=point_m, normal=tuple(normal))
    on_table = Simulation(rods, contact=None, obstacles=[table])
    weight = np.zeros((m.n_nodes, 3))
    weight[nodes] = -GRAVITY * m.mass[nodes, None] * kl.units.MASS * normal
    on_table.set_external_forces(weight)
    node_weight = float(np.linalg.norm(weight[nodes], axis=1).mean())
    on_table.settle(force_tol_N=0.05 * node_weight, max_time_s=max_time_s, damping_per_s=200.0, check_every_s=5e-3)
    rest = on_table.state.x[nodes]
    return rest - np.outer((rest - centre - below * normal) @ normal, normal)


def freed_course(K: float, preset: str, fx: float = 4.0, peak_ratio: float | None = None):
    """(the relaxed course's node positions [internal], hinge (kappa/kappa0)^2 in 3-D, kappa0 [1/internal], the
    relaxed simulation, the course's nodes)."""
    cfg = CutConfig(n_x=4, n_y=4, fx=fx, natural_curvature=K, preset=preset, memory_peak_ratio=peak_ratio)
    knit = stretch(cfg.stretch_settings())
    rods, material = knit.knit.rods, cfg.stretch_settings().material
    m = rods.model
    course = knit.knit.courses[1]
    hinges = np.flatnonzero(m.node_yarn[m.edge_a[m.hinge_e1]] == course)
    free = rods.copy().replace_model(held=np.zeros_like(m.held), v_prescribed=np.zeros_like(m.v_prescribed))
    sim = Simulation(free, contact=None)
    if not sim.relax(force_tol_N=1e-7, max_steps=600_000)["converged"]:
        raise RuntimeError(f"K = {K}: the freed course did not relax")
    x = sim.state.x
    k3 = positional_curvature(rods, x, hinges, material)
    nodes = np.flatnonzero(m.node_yarn == course)
    return x[nodes], k3, material.kappa0 * kl.units.LENGTH, sim, nodes


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--K", type=float, nargs="+", default=[0.05, 0.25, 1.0])
    p.add_argument("--preset", default="fast")
    p.add_argument("--csv", default=None)
    p.add_argument("--peak-ratio", type=float, default=None, help="memory_peak_ratio of the memory (default: none)")
    p.add_argument("--table", action="store_true", help="also lay the course on a table under gravity (laid_on_plane)")
    args = p.parse_args()
    rows = []
    for K in args.K:
        x, k3, kappa0, sim, nodes = freed_course(K, args.preset, peak_ratio=args.peak_ratio)
        k2 = (flattened_curvature(x) / kappa0) ** 2
        row = {"K": K, "memory_peak_ratio": args.peak_ratio, "mean_3d": k3.mean(), "max_3d": k3.max(),
               "mean_flat": k2.mean(), "max_flat": k2.max(), "max_over_mean_flat": k2.max() / k2.mean()}
        if args.table:
            kt = (flattened_curvature(laid_on_plane(sim, nodes)) / kappa0) ** 2
            row.update(mean_table=kt.mean(), max_table=kt.max())
        rows.append(row)
        print(f"K {K}: done", flush=True)
    df = pd.DataFrame(rows)
    if args.csv:
        df.to_csv(args.csv, index=False, float_format="%.4g")
    print(f"\n{args.preset} preset, 4 x 4 knit stretched to f_x 4, a middle course freed and relaxed "
          f"(memory_peak_ratio {args.peak_ratio}):\n")
    table = "mean_table" in df
    print("| K (knitlad) | 3-D mean (kappa/kappa0)^2 | 3-D max | best plane: mean | best plane: max | flat max/mean |"
          + (" on a table: mean | on a table: max |" if table else ""))
    print("|---|---|---|---|---|---|" + ("---|---|" if table else ""))
    for r in df.itertuples():
        print(f"| {r.K:g} | {r.mean_3d:.3f} | {r.max_3d:.2f} | {r.mean_flat:.3f} | {r.max_flat:.2f} | "
              f"{r.max_over_mean_flat:.2f} |" + (f" {r.mean_table:.3f} | {r.max_table:.2f} |" if table else ""))
    print("| paper (thread laid flat) | | | about 1 | about 3.5 | about 3.5 |" + (" about 1 | about 3.5 |" if table else ""))


if __name__ == "__main__":
    main()
