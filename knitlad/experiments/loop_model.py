"""The single-loop laddering model (paper, Fig. 5b,c): how fast one loop lets go of the next.

Protocol (:class:`LoopRun`):

1. build the three rows of one column (:mod:`knitlad.fabric.scenes.loop`) at (l_x, l_y),
   the free row pulled at both ends by F = f_x f0;
2. relax at mu = 0 (FIRE) to the hooked equilibrium;
3. switch on mu, remove the lower row (t_0): nothing holds the loop any more and
   the tension draws it straight;
4. tau = t_cl - t_0, where t_cl is the instant the loop lets go of the upper
   row: the upper row stops threading it (its piercings of the loop's spanning
   surface, :func:`knitlad.fabric.topology.piercings`, drop from 2 to 0 and stay there).
   v_lad = l_y / tau. The paper's t_cl is the instant the two loops stop touching;
   that instant is also recorded (``tau_contact_s``: the last contact before the
   release) but it is ill-conditioned here: the freed loop whips, losing and
   regaining contact several times while still threaded, so it changes by up to
   25 % between 36 and 48 nodes per stitch, where the release time changes by
   less than 3 % (f_x = 2 to 16, mu = 0).

At mu = 0 the release is inertial and the paper finds v_lad/c_b = 0.34 sqrt(f_x);
friction slows it and makes v_lad(f_x) close to linear. Here the freed loop also
recoils (a bent rod with no natural curvature unbends), so at mu = 0
v_lad^2 = v_0^2 + beta^2 f_x, with beta close to the paper's 0.34 and v_0 about 0.5 to
0.6 c_b (README, "The single-loop model").
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import NamedTuple, Sequence

from knitlad.engine.contact import KNIT_CONTACT_FORCE_F0, KNIT_OVERLAP, ContactModel
from knitlad.fabric.observers import LetGo, TimeLimit
from knitlad.engine.deprecation import renamed_fields
from knitlad.engine.runloop import Observer, run_until
from knitlad.fabric.scenes.knit import KnitGeometry
from knitlad.fabric.scenes.loop import LoopScene, build_single_loop
from knitlad.engine.simulation import Simulation, small_scene_threads
from knitlad.engine.timestep import DEFAULT_SAFETY
from knitlad.fabric.topology import piercings
from knitlad.engine.units import NYLON, Material


def check_tension_and_friction(fx: float, mu: float) -> None:
    """A single-loop run needs a pulling tension and a non-negative friction coefficient."""
    if not fx > 0:
        raise ValueError(f"fx must be > 0, got {fx}")
    if mu < 0:
        raise ValueError(f"mu must be >= 0, got {mu}")


@renamed_fields({"lx_over_l0": "lx", "ly_over_l0": "ly", "nodes_per_stitch": "resolution"}, since="0.14.0")
@dataclass
class LoopSettings:
    """Inputs of one single-loop run. Lengths as l/l0, tension as f_x, SI otherwise.

    Built by :meth:`knitlad.experiments.config.LoopConfig.settings`, where the first six have their
    defaults and units; the rest are the model's own choices.
    """

    fx: float
    mu: float
    lx: float  # l_x/l0; wider, the loops of one column no longer overlap (0.39: none)
    ly: float  # l_y/l0
    resolution: int  # release time within 3 % of 48 nodes/stitch (24: up to 8 %, and f_x = 2 stays hooked)
    max_time_s: float  # releases take 50 to 150 us
    contact_force_f0: float = KNIT_CONTACT_FORCE_F0
    overlap_fraction: float = KNIT_OVERLAP
    observe_every_s: float = 0.5e-6  # contact checks
    topology_every_s: float = 1e-6  # threading checks (tau is resolved to this)
    confirm_s: float = 20e-6  # unthreaded this long: released
    dt_safety: float = DEFAULT_SAFETY  # time step as a fraction of the stability limit
    # global viscous drag on every node after the lower row is removed [1/s]; 0 is the physics.
    # With 2e4 /s the loop stays hooked (f_x = 8, mu = 0, 36 to 96 nodes per stitch): it gets
    # out only on the momentum the release gives it.
    drag_per_s: float = 0.0
    material: Material = NYLON

    def __post_init__(self) -> None:
        check_tension_and_friction(self.fx, self.mu)
        if not (self.drag_per_s >= 0 and math.isfinite(self.drag_per_s)):  # before the relaxation, not after
            raise ValueError(f"drag_per_s must be >= 0, got {self.drag_per_s!r}")


@dataclass
class LoopResult:
    settings: LoopSettings
    tau_s: float = math.inf  # release: the upper row stopped threading the loop (for good)
    tau_contact_s: float = math.inf  # the last contact between the loop and the upper row before that
    v_lad_over_cb: float = 0.0
    released: bool = False
    relax_converged: bool = False
    contacts_before: int = 0  # touching pairs between the loop and the upper row at t_0
    steps: int = 0
    nodes: int = 0
    wall_s: dict = field(default_factory=dict)

    def summary(self) -> dict:
        return {
            "fx": self.settings.fx,
            "mu": self.settings.mu,
            "tau_s": self.tau_s,
            "tau_contact_s": self.tau_contact_s,
            "v_lad_over_cb": self.v_lad_over_cb,
            "released": self.released,
            "relax_converged": self.relax_converged,
            "contacts_before": self.contacts_before,
            "steps": self.steps,
            "nodes": self.nodes,
            "wall_s": float(sum(self.wall_s.values())),
        }


class LoopReading(NamedTuple):
    """What a single loop's stop rule reads: is the loop still held (None: not read this time)."""

    held: bool | None


class LoopRun:
    """Drives one single-loop run; see the module docstring."""

    def __init__(self, settings: LoopSettings) -> None:
        self.s = settings
        m = settings.material
        l0 = m.stitch_length
        geometry = KnitGeometry(n_x=1, n_y=1, l_x=settings.lx * l0, l_y=settings.ly * l0,
                          resolution=settings.resolution, material=m, edge="tail")
        self.scene: LoopScene = build_single_loop(geometry, settings.fx * m.f0)
        contact = ContactModel.of_settings(settings, mu=0.0)
        self.sim = Simulation(self.scene.rods, contact=contact, safety=settings.dt_safety)
        self.result = LoopResult(settings, nodes=self.scene.rods.model.n_nodes)

    def relax(self) -> None:
        """FIRE to the hooked equilibrium under the end forces (mu = 0)."""
        t0 = time.perf_counter()
        f0 = self.s.material.f0
        info = self.sim.relax(force_tol_N=1e-4 * f0, max_steps=400_000)
        self.result.relax_converged = info["converged"]
        self.sim.state.v[:] = 0.0
        self.result.wall_s["relax"] = time.perf_counter() - t0

    def remove_lower_row(self) -> None:
        """Take the lower row far away (it is held, so it simply moves there)."""
        s, sc, start = self.sim.state, self.scene, self.sim.model.yarn_start
        nodes = slice(int(start[sc.lower]), int(start[sc.lower + 1]))
        s.x[nodes, 1] -= 10.0 * (s.x[:, 1].max() - s.x[:, 1].min())
        s.v[nodes] = 0.0

    def release(self, observers: Sequence[Observer] = ()) -> None:
        """Remove the row below and follow the loop until it lets go; ``observers`` see (t, this run, a
        :class:`LoopReading`) at every reading."""
        t0 = time.perf_counter()
        sc, res = self.scene, self.result
        self.sim.set_friction(self.s.mu)
        self.sim.set_drag(self.s.drag_per_s)
        res.contacts_before = self.sim.touching_pairs(sc.loop, sc.upper)
        if res.contacts_before == 0:
            raise RuntimeError("the loop does not touch the upper row after relaxation: nothing to release")
        self.remove_lower_row()
        s, start = self.sim.state, self.sim.model.yarn_start
        loop = slice(int(start[sc.loop]), int(start[sc.loop + 1]))
        upper = slice(int(start[sc.upper]), int(start[sc.upper + 1]))
        n_obs = max(1, int(round(self.s.observe_every_s / self.sim.dt_s)))
        every_topology = max(1, int(round(self.s.topology_every_s / self.s.observe_every_s)))
        seen = {"last_touch": 0.0, "readings": 0}

        def observe(t: float) -> LoopReading:
            seen["readings"] += 1
            if self.sim.touching_pairs(sc.loop, sc.upper) > 0:
                seen["last_touch"] = t
            if seen["readings"] % every_topology:
                return LoopReading(None)
            return LoopReading(bool(piercings(s.x[loop], s.x[upper])[0] > 0))  # still threaded

        let_go = LetGo(self.s.confirm_s, "unthreaded")
        _, rule, _ = run_until(self.sim, n_obs, observe, [let_go, TimeLimit(self.s.max_time_s)], observers, self)
        if rule is let_go:
            res.released = True
            res.tau_s = let_go.since - 0.5 * self.s.topology_every_s
            res.tau_contact_s = seen["last_touch"] + 0.5 * self.s.observe_every_s
            l_y = self.s.ly * self.s.material.stitch_length
            res.v_lad_over_cb = l_y / res.tau_s / self.s.material.c_b
        res.steps = self.sim.steps
        res.wall_s["release"] = time.perf_counter() - t0

    def run(self, observers: Sequence[Observer] = ()) -> LoopResult:
        with small_scene_threads():
            self.relax()
            self.release(observers)
        return self.result
