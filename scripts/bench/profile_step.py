"""Profile: where one laddering step's time goes, part by part.

    python scripts/bench/profile_step.py [--fx 13.6] [--stitches 42] [--preset default]
                                   [--twist on] [--threads 2] [--warm-steps 2000]
                                   [--implicit-axial] [--banded-solve]

Stretches the knit, cuts it and runs ``--warm-steps`` steps (so the ladder runs and the
cut ends whip), then times each part of a step on that state, as the median of repeated
calls: the whole step, the yarns' elastic forces (twist-free or framed), the parts of the
framed path, the contact pair forces, the per-node kicks and drifts, and a contact-list
rebuild. The reference frames are transported between two states one step apart, so
every call rotates them as a real step does.

``--banded-solve`` also times what a linearly implicit bending step adds at the least: a Cholesky
factorisation and a solve of (M + dt^2 K) dv = r per yarn, K banded as the bending Hessian (three
coordinates per node, neighbours two nodes away: half-bandwidth 8), the yarns in parallel. The assembly of
the Hessian and any coupling of the yarns by contact come on top (docs/performance.md).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np
from numba import njit, prange

from knitlad.experiments.config import CutConfig
from knitlad.engine.kernels.contact import GAPS_KNOWN, STALE, contact_forces, refresh_contacts
from knitlad.engine.kernels.elastic import (
    edge_vectors,
    framed_bending_twisting_forces,
    straight_bending_twisting_forces,
    stretching_forces,
)
from knitlad.engine.kernels.frames import (
    material_frames,
    reference_twist_by_holonomy,
    transport_reference_frames,
    update_reference_twist,
)
from knitlad.engine.kernels.integrate import (
    _drift,
    elastic_forces_by_yarn,
    framed_forces_by_yarn,
    half_kick,
    implicit_stretching_by_yarn,
    straight_twisting_forces_by_yarn,
    verlet_steps,
)
from knitlad.engine.kernels.options import PARALLEL_OPTS
from knitlad.experiments.laddering import cut
from knitlad.fabric.preparation import stretch
from knitlad.engine.simulation import numba_threads


@njit(**PARALLEL_OPTS)
def stretch_by_yarn(m, s, w):
    for y in prange(w.yarn_edges.shape[0] - 1):
        e0, e1 = w.yarn_edges[y], w.yarn_edges[y + 1]
        edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen, e0, e1)
        stretching_forces(w.e, w.elen, s.v, m.edge_a, m.edge_b, m.rest_length, m.EA, m.stretch_damping, w.force, e0, e1)


@njit(**PARALLEL_OPTS)
def transport_by_yarn(m, s, w, x):
    for y in prange(w.yarn_edges.shape[0] - 1):
        e0, e1 = w.yarn_edges[y], w.yarn_edges[y + 1]
        edge_vectors(x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen, e0, e1)
        transport_reference_frames(w.e, w.elen, s.tangent, s.ref_u, e0, e1)


@njit(**PARALLEL_OPTS)
def edges_by_yarn(m, w, x):
    for y in prange(w.yarn_edges.shape[0] - 1):
        e0, e1 = w.yarn_edges[y], w.yarn_edges[y + 1]
        edge_vectors(x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen, e0, e1)


@njit(**PARALLEL_OPTS)
def twist_by_yarn(m, s, w):
    for y in prange(w.yarn_edges.shape[0] - 1):
        update_reference_twist(s.tangent, s.ref_u, m.hinge_e0, m.hinge_e1, s.ref_twist, w.yarn_hinges[y],
                               w.yarn_hinges[y + 1])


@njit(**PARALLEL_OPTS)
def holonomy_by_yarn(m, s, w, x):
    """The reference twist by holonomy, from the stored tangents to those of ``x`` (tangents not stored)."""
    for y in prange(w.yarn_edges.shape[0] - 1):
        edge_vectors(x, m.edge_a, m.edge_b, m.edge_shift, w.e, w.elen, w.yarn_edges[y], w.yarn_edges[y + 1])
        reference_twist_by_holonomy(s.tangent, w.e, w.elen, m.hinge_e0, m.hinge_e1, s.ref_twist, w.yarn_hinges[y],
                                    w.yarn_hinges[y + 1])


@njit(**PARALLEL_OPTS)
def straight_bending_by_yarn(m, s, w):
    for y in prange(w.yarn_edges.shape[0] - 1):
        straight_bending_twisting_forces(
            w.e, w.elen, s.tangent, m.edge_a, m.edge_b, m.hinge_e0, m.hinge_e1, m.B_over_l, m.GJ_over_l, s.ref_twist,
            m.twist_bar, s.theta, w.force, w.torque, w.yarn_hinges[y], w.yarn_hinges[y + 1])


@njit(**PARALLEL_OPTS)
def frames_by_yarn(s, w):
    for y in prange(w.yarn_edges.shape[0] - 1):
        material_frames(s.tangent, s.ref_u, s.theta, w.d1, w.d2, w.yarn_edges[y], w.yarn_edges[y + 1])


@njit(**PARALLEL_OPTS)
def framed_bending_by_yarn(m, s, w):
    for y in prange(w.yarn_edges.shape[0] - 1):
        framed_bending_twisting_forces(
            w.e, w.elen, w.d1, w.d2, m.edge_a, m.edge_b, m.hinge_e0, m.hinge_e1,
            m.B_over_l, m.GJ_over_l, m.kappa_bar, s.ref_twist, m.twist_bar, s.theta, w.force, w.torque,
            w.yarn_hinges[y], w.yarn_hinges[y + 1],
        )


BAND = 8  # half-bandwidth of the bending Hessian in dofs: 3 coordinates, neighbours two nodes away


@njit(**PARALLEL_OPTS)
def banded_cholesky_by_yarn(band, yarn_dof, factor, rhs):
    """Per yarn (dofs [yarn_dof[y], yarn_dof[y+1])): ``band[i, k]`` holds A[i, i-k] (k = 0..BAND) of an SPD
    band matrix. ``factor``: overwrite it with its Cholesky factor L first; then solve L L^T x = rhs in place."""
    for y in prange(yarn_dof.shape[0] - 1):
        lo, hi = yarn_dof[y], yarn_dof[y + 1]
        b = band.shape[1] - 1
        if factor:
            for j in range(lo, hi):
                s = band[j, 0]
                for k in range(1, min(b, j - lo) + 1):
                    s -= band[j, k] * band[j, k]
                d = math.sqrt(s)
                band[j, 0] = d
                for i in range(j + 1, min(hi, j + b + 1)):
                    s = band[i, i - j]
                    for k in range(max(lo, i - b), j):
                        s -= band[i, i - k] * band[j, j - k]
                    band[i, i - j] = s / d
        for i in range(lo, hi):  # L z = r
            s = rhs[i]
            for k in range(max(lo, i - b), i):
                s -= band[i, i - k] * rhs[k]
            rhs[i] = s / band[i, 0]
        for i in range(hi - 1, lo - 1, -1):  # L^T x = z
            s = rhs[i]
            for k in range(i + 1, min(hi, i + b + 1)):
                s -= band[k, k - i] * rhs[k]
            rhs[i] = s / band[i, 0]


def banded_system(yarn_start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An SPD band matrix (M + dt^2 K, K the straight rod's bending stencil 1, -4, 6, -4, 1 in each coordinate
    with a weaker coupling of the coordinates, at dt^2 K / M = 20) of the yarns' sizes, and the yarns' dof
    offsets. The solve's cost does not depend on the values; the values only keep it positive definite."""
    n = 3 * int(yarn_start[-1])
    band = np.zeros((n, BAND + 1))
    stiff = 20.0
    band[:, 0] = 1.0 + 6.0 * stiff + 0.5
    band[:, 3] = -4.0 * stiff
    band[:, 6] = 1.0 * stiff
    for k in (1, 2, 4, 5, 7, 8):
        band[:, k] = 0.5 / 12.0
    return band, 3 * yarn_start.astype(np.int64)


def median_ms(fn, repeats: int = 30) -> float:
    fn()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1e3 * statistics.median(times)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fx", type=float, default=13.6)
    p.add_argument("--stitches", type=int, default=42)
    p.add_argument("--preset", default="default", choices=["fast", "default", "accurate"])
    p.add_argument("--twist", default="on", choices=["off", "on"])
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--warm-steps", type=int, default=2000)
    p.add_argument("--implicit-axial", action="store_true", help="the axial springs implicit (implicit_axial)")
    p.add_argument("--banded-solve", action="store_true", help="also time a banded Cholesky factor and solve per "
                   "yarn, the least a linearly implicit bending step adds")
    args = p.parse_args()
    cfg = CutConfig(n_x=args.stitches, n_y=args.stitches, fx=args.fx, preset=args.preset, twist=args.twist == "on",
                    implicit_axial=args.implicit_axial)
    settings = cfg.settings()
    with numba_threads(args.threads):
        run = cut(stretch(settings.stretch), settings.dynamics)
        sim = run.sim
        sim.step(args.warm_steps)
        m, s, w, c, dt, tw = sim.model, sim.state, sim.work, sim.contacts, sim.dt, sim.twist_mode
        print(f"{m.n_nodes} nodes, {m.edge_a.shape[0]} edges, twist mode {tw}, {c.n_pairs[0]} candidate pairs, "
              f"dt {sim.dt_s:.3e} s, {args.threads} threads")
        rows = []

        def steps(n=20):
            sim.compute_forces()
            verlet_steps(m, s, w, c, dt, n, tw, True, sim.damping, sim.axial_mode)

        rows.append(("step (20 steps, per step)", median_ms(steps, 10) / 20))
        x_a = s.x.copy()
        steps(1)
        x_b = s.x.copy()
        flip = [x_a, x_b]

        def transport():
            flip.reverse()
            transport_by_yarn(m, s, w, flip[0])

        rows.append(("edge vectors", median_ms(lambda: edges_by_yarn(m, w, s.x))))
        rows.append(("edge vectors + stretching", median_ms(lambda: stretch_by_yarn(m, s, w))))
        rows.append(("implicit axial springs (a tridiagonal solve per yarn)", median_ms(
            lambda: implicit_stretching_by_yarn(m, s, w, dt))))
        rows.append(("twist-free elastic (stretch + bend)", median_ms(lambda: elastic_forces_by_yarn(m, s, w, True, s.v, dt))))
        if tw:
            rows.append(("straight twisting path (frame-free)", median_ms(
                lambda: straight_twisting_forces_by_yarn(m, s, w, True, s.v, dt))))
            rows.append(("  edge vectors + reference twist by holonomy", median_ms(
                lambda: holonomy_by_yarn(m, s, w, flip[0]))))
            rows.append(("  isotropic bending and twisting (the holonomy in the pass)", median_ms(
                lambda: straight_bending_by_yarn(m, s, w))))
            rows.append(("framed elastic (all of the framed path)", median_ms(lambda: framed_forces_by_yarn(m, s, w, True, s.v, dt))))
            rows.append(("  edge vectors + transport of the frames", median_ms(transport)))
            rows.append(("  reference twist", median_ms(lambda: twist_by_yarn(m, s, w))))
            rows.append(("  material frames", median_ms(lambda: frames_by_yarn(s, w))))
            rows.append(("  framed bending and twisting", median_ms(lambda: framed_bending_by_yarn(m, s, w))))
        for spin in ([tw, 0] if tw else [0]):
            name = "contact pair forces" + (" with the friction couple" if spin else "")
            rows.append((name, median_ms(
                lambda: contact_forces(s.x, s.v, s.omega, spin, m.mass, m.edge_a, m.edge_b, m.edge_shift, c, dt,
                                       w.force, w.torque, s.v, s.omega, False, w.ledger))))

        def every_pair_tested():
            c.status[GAPS_KNOWN] = 0  # as at the first evaluation after a rebuild: no pair skipped by its gap
            contact_forces(s.x, s.v, s.omega, 0, m.mass, m.edge_a, m.edge_b, m.edge_shift, c, dt, w.force, w.torque,
                           s.v, s.omega, False, w.ledger)

        rows.append(("contact pair forces, every pair's distance tested", median_ms(every_pair_tested)))
        rows.append(("half kick", median_ms(lambda: half_kick(m, s, w, 0.0, tw))))
        rows.append(("drift", median_ms(lambda: _drift(m, s, 0.0, tw))))

        lookahead = c.params.lookahead_steps * dt

        def rebuild():  # as the run calls it: with the velocities, so with the fast edges' pass
            c.status[STALE] = 1
            refresh_contacts(s.x, m.edge_a, m.edge_b, m.edge_shift, c, s.v, lookahead)

        rows.append(("contact-list rebuild (one, with the fast edges' pass)", median_ms(rebuild, 10)))
        if args.banded_solve:
            band, yarn_dof = banded_system(m.yarn_start)
            rhs = np.ones(band.shape[0])
            work = band.copy()

            def factor_and_solve():
                work[...] = band
                banded_cholesky_by_yarn(work, yarn_dof, True, rhs)

            banded_cholesky_by_yarn(work, yarn_dof, True, rhs)
            check = rhs.copy()  # the factor reproduces the system: A x = 1 to round-off
            rhs[:] = 1.0
            factor_and_solve()
            assert np.allclose(rhs, check)
            rows.append(("banded Cholesky of (M + dt^2 K), factor + solve per yarn", median_ms(factor_and_solve)))
            rows.append(("  its solve alone (a Jacobian kept from an earlier step)", median_ms(
                lambda: banded_cholesky_by_yarn(work, yarn_dof, False, rhs))))
            rows.append(("  its copy of the band (part of the factor + solve above)", median_ms(
                lambda: work.__setitem__(Ellipsis, band))))
        rows.append(("displacement check (no rebuild)", median_ms(
            lambda: refresh_contacts(s.x, m.edge_a, m.edge_b, m.edge_shift, c, s.v, lookahead))))
    width = max(len(r[0]) for r in rows)
    for name, ms in rows:
        print(f"{name:<{width}}  {ms:7.3f} ms")


if __name__ == "__main__":
    main()
