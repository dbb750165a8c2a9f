"""The public driver: run :class:`~knitlad.engine.state.Rods` (a model and its state) in time or to equilibrium.

Units at the edges: methods whose names end in ``_si`` or take ``*_s`` / ``*_N``
arguments speak SI; the state itself is in internal units (:mod:`knitlad.engine.units`).
"""

from __future__ import annotations

import math
import warnings
import os
import time
from contextlib import contextmanager
from typing import Callable, Sequence

import numba
import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import (
    ContactModel,
    ContactPairs,
    Contacts,
    ContactStats,
    carry_friction_history,
    check_friction_coefficient,
    contact_time_step,
    make_contacts,
)
from knitlad.engine.checkpoint import Checkpointing
from knitlad.engine.dissipation import AirDrag, DissipationControl, MaterialDamping
from knitlad.engine.fracture import Fracture
from knitlad.engine.kernels.contact import GAPS_KNOWN, PAIRS_NEEDED, PEAK_OVERLAP, STALE, refresh_contacts, touching_pairs_among
from knitlad.engine.kernels.integrate import (
    AXIAL_EXPLICIT,
    AXIAL_IMPLICIT,
    DASHPOTS_HALF_STEP,
    DASHPOTS_PREDICTED,
    TWIST_FRAMED,
    TWIST_OFF,
    TWIST_STRAIGHT,
    compute_forces,
    fire_relax,
    first_bad_node,
    follow_images,
    half_kick,
    rail_forces,
    verlet_steps,
)
from knitlad.engine.obstacles import Obstacle, ObstacleReadout, obstacle_state, obstacle_time_step
from knitlad.engine.quasistatic import QuasiStatics
from knitlad.engine.state import Rods, Workspace, finite_vectors
from knitlad.engine.timestep import (
    DEFAULT_SAFETY,
    TimeStepLimits,
    UnstableTimeStep,
    critical_time_steps,
    step_count,
)


class MovingSupportWarning(UserWarning):
    """A reaction force read while held nodes move under a drag: biased (``Simulation.reaction_bias_N``)."""


class SimulationBlowUp(RuntimeError):
    """The state became non-finite or a node outran the axial wave speed."""


@contextmanager
def numba_threads(n: int):
    """Run the enclosed kernels on ``n`` Numba threads, then restore the previous count.

    A scene of a few hundred nodes runs 30x faster on one thread than on two when
    the other core is busy (measured: the single-loop run, 0.15 s against 7.5 s),
    because the threads of the parallel kernels wait for each other every step.
    """
    before = numba.get_num_threads()
    numba.set_num_threads(max(1, min(n, numba.config.NUMBA_NUM_THREADS)))
    try:
        yield
    finally:
        numba.set_num_threads(before)


def small_scene_threads():
    """The thread budget of a small scene (a stitch, a single loop, rows of loops: a few thousand nodes at
    most): one Numba thread, for the reason :func:`numba_threads` gives. Every reduced model runs under it."""
    return numba_threads(1)


def idle_cpu_ticks(cpus: tuple[int, ...]) -> tuple[int, int] | None:
    """(idle, total) clock ticks so far of the processors ``cpus``, from /proc/stat (Linux); None elsewhere."""
    try:
        with open("/proc/stat") as f:
            lines = f.read().splitlines()
    except OSError:
        return None
    idle = total = 0
    wanted = {f"cpu{c}" for c in cpus}
    for line in lines:
        fields = line.split()
        if fields and fields[0] in wanted:
            ticks = [int(v) for v in fields[1:]]
            idle += ticks[3] + (ticks[4] if len(ticks) > 4 else 0)  # idle and iowait
            total += sum(ticks[:8])
    return (idle, total) if total else None


class ThreadGovernor:
    """Chooses, as a run goes, between the Numba threads it was given and one thread: whichever steps faster.

    A parallel step meets its threads at barriers several times; when another process holds one of
    two cores, each barrier waits for a descheduled thread: a 16 x 16 run went from 5.45 s to 48 s,
    and a chunk of an 8 x 8 run from 0.045 s on one thread to 15 s on two (docs/performance.md). So a run
    starts on one thread and tries its threads only when the processors it may use were idle
    for at least half a core per extra thread during the last chunk (/proc/stat; where that cannot be
    read, it tries anyway). It times every chunk, keeps the faster count, and tries again more
    rarely each time the choice holds (after 1 chunk, then 2, 4, ... 256, and at least 20 times
    as many chunks as the probe was slower, so that probing costs 5 % at most; a chunk twice as slow
    as the one before it, as when another process starts, tries the other count next). A probe of one
    thread is put off by one chunk, again and again, while the other processes use less than a quarter
    of a core (/proc/stat's busy time less this process's CPU time, over the chunk before it): with
    nobody to share the cores with, it could only cost (two such probes took 3 % of a 42 x 42 run), and
    once another process runs, it comes at once (only a count chosen over one thread by the timings is
    spared its probes: the first chunk runs on one thread, since on a small scene one thread may be the
    faster even on a quiet machine). Results do not
    change: every kernel gives the same bits on any number of threads (the contact pairs are
    evaluated in blocks fixed when the buffers are made, and summed in pair order), and a probe is
    a whole chunk, so the chunks (whose fused half-kicks round differently from two halves) fall
    where they would.
    """

    FIRST_INTERVAL, LAST_INTERVAL = 1, 256
    QUIET_OTHERS = 0.25  # cores the other processes may use for a probe of one thread to be skipped
    MIN_TICKS = 20  # clock ticks (all processors) a chunk must span for its reading of the others to count

    def __init__(self) -> None:
        self.seconds_per_step: dict[int, float] = {}
        self.current = 1
        self.interval = self.FIRST_INTERVAL
        self.until_probe = self.FIRST_INTERVAL
        self.idle_cores: float | None = None  # idle processors during the last chunk (None: unknown)
        self.other_cores: float | None = None  # the cores other processes used then (None: unknown)
        self._cpu_s = 0.0  # this process's CPU time at the start of the chunk
        self.cpus = tuple(sorted(os.sched_getaffinity(0))) if hasattr(os, "sched_getaffinity") else ()
        self._ticks = None

    def plan(self, allowed: int) -> int:
        """The number of threads for the next chunk, ``allowed`` at most."""
        if allowed <= 1:
            self._ticks = None
            return 1
        self.current = min(self.current, allowed)
        # the processors' load matters only before a probe: read /proc/stat for that chunk alone
        self._ticks = idle_cpu_ticks(self.cpus) if self.until_probe <= 1 else None
        self._cpu_s = time.process_time()
        if self.until_probe > 0 or not self.seconds_per_step:
            return self.current
        if self.current > 1:
            # a run starts on one thread, so the timings chose this count over it; with nobody to share the
            # cores, nothing threatens the choice
            if self.other_cores is not None and self.other_cores < self.QUIET_OTHERS:
                self.until_probe = 1  # a reading costs nothing: look again after the next chunk
                return self.current
            return 1
        room = self.idle_cores is None or self.idle_cores >= 0.5 * (allowed - 1)
        return allowed if room else 1

    def for_one_call(self, allowed: int) -> int:
        """Threads for a kernel call that cannot be split (a relaxation): the count the chunks chose, or
        before any chunk, one thread when the load average says the other processors are taken."""
        if allowed <= 1:
            return 1
        if self.seconds_per_step:
            return min(self.current, allowed)
        try:
            busy = os.getloadavg()[0]
        except (AttributeError, OSError):
            return allowed
        cores = len(self.cpus) or os.cpu_count() or 1
        # the load counts this process too (about one while it runs): room for the others' threads?
        return allowed if busy <= cores - allowed + 1.5 else 1

    @contextmanager
    def one_call(self):
        """Numba threads for one kernel call that cannot be timed in chunks (a force evaluation, a
        relaxation): :meth:`for_one_call`, then the count as it was."""
        allowed = numba.get_num_threads()
        numba.set_num_threads(self.for_one_call(allowed))
        try:
            yield
        finally:
            numba.set_num_threads(allowed)

    def record(self, threads: int, steps: int, seconds: float) -> None:
        if steps <= 0:
            return
        ticks = idle_cpu_ticks(self.cpus) if self._ticks is not None else None
        self.other_cores = None  # known only for a chunk read from start to end: a stale "quiet" would hide a load
        if ticks is not None and ticks[1] > self._ticks[1]:
            self.idle_cores = len(self.cpus) * (ticks[0] - self._ticks[0]) / (ticks[1] - self._ticks[1])
            if ticks[1] - self._ticks[1] >= self.MIN_TICKS and seconds > 0.0:
                own_cores = (time.process_time() - self._cpu_s) / seconds
                self.other_cores = len(self.cpus) - self.idle_cores - own_cores
        before = self.seconds_per_step.get(threads)
        self.seconds_per_step[threads] = seconds / steps
        if threads == self.current:  # a chunk at the chosen count, or a probe the machine had no room for
            self.until_probe -= 1
            if before is not None and seconds / steps > 2.0 * before:  # the machine got busy: look again now
                self.until_probe, self.interval = 0, self.FIRST_INTERVAL
            return
        ratio = self.seconds_per_step[threads] / self.seconds_per_step[self.current]
        if ratio < 0.9:
            self.current, self.interval = threads, self.FIRST_INTERVAL
        else:  # a probe r times slower costs r chunks: wait 20 r chunks for the next (5 % at most)
            self.interval = min(max(2 * self.interval, math.ceil(20 * ratio)), self.LAST_INTERVAL)
        self.until_probe = self.interval


def axial_wave_speed(m) -> float:
    """The fastest axial wave, sqrt(EA / rho_L) [mm/ms]: no node of a sound run outruns it."""
    rho = m.mass.sum() / max(m.rest_length.sum(), 1e-300)
    c = np.sqrt(m.EA / rho) if m.EA.size else np.array([1.0])
    return float(np.max(c))


def check_open_chains(model, implicit_axial: bool) -> bool:
    """``implicit_axial``, refused for a model whose axial springs cannot be implicit: a ring (its closing
    node couples two edges that are not consecutive) or a periodic image (not a free mass)."""
    if not implicit_axial:
        return False
    shared = np.intersect1d(model.edge_a, model.edge_b).size
    chained = int(np.sum(model.edge_b[:-1] == model.edge_a[1:]))
    if shared != chained:
        raise ValueError("implicit_axial: the axial springs can be implicit on open yarns only (this scene has a ring)")
    if model.image_node.size:
        raise ValueError("implicit_axial: not with periodic images")
    return True


class SupportControl:
    """Supports and loads changed during a run, without rebuilding (mixed into :class:`Simulation`): each change
    is a new model (``replace_model``), so a model is still never changed in place."""

    def _nodes(self, nodes) -> np.ndarray:
        idx = np.atleast_1d(np.asarray(nodes, dtype=np.int64))
        n = self.model.n_nodes
        if idx.size and (idx.min() < -n or idx.max() >= n):
            raise IndexError(f"node out of range for a scene of {n} nodes")
        return idx % n

    def nodes_of(self, yarn: int, nodes=None) -> np.ndarray:
        """Global indices of ``nodes`` of ``yarn`` (all of them by default; negative counts from its end)."""
        start, stop = int(self.model.yarn_start[yarn]), int(self.model.yarn_start[yarn + 1])
        local = np.arange(stop - start) if nodes is None else np.atleast_1d(np.asarray(nodes, dtype=np.int64))
        if local.size and (local.min() < start - stop or local.max() >= stop - start):
            raise IndexError(f"node out of range for yarn {yarn} of {stop - start} nodes")
        return start + local % (stop - start)

    def hold(self, nodes, velocity_m_s=(0.0, 0.0, 0.0)) -> None:
        """Hold ``nodes`` (global indices, :meth:`nodes_of`) from the next step on, moving at ``velocity_m_s``
        (one 3-vector, or one per node); held nodes already held get the new velocity."""
        idx = self._nodes(nodes)
        v = finite_vectors("velocity_m_s", velocity_m_s, (idx.size, 3)) / units.VELOCITY
        held, v_prescribed = self.model.held.copy(), self.model.v_prescribed.copy()
        held[idx], v_prescribed[idx] = True, v
        self.replace_model(held=held, v_prescribed=v_prescribed)
        self.state.v[idx] = v

    def release(self, nodes) -> None:
        """Let ``nodes`` go from the next step on: they keep their prescribed velocity as their own."""
        idx = self._nodes(nodes)
        held, v_prescribed = self.model.held.copy(), self.model.v_prescribed.copy()
        held[idx] = False
        v_prescribed[idx] = 0.0
        self.replace_model(held=held, v_prescribed=v_prescribed)

    def move_held(self, nodes, to_m=None, by_m=None) -> None:
        """Put held ``nodes`` at positions ``to_m`` [m] or shift them by ``by_m`` [m] (one 3-vector or one
        per node), for displacement-controlled statics: move, then :meth:`relax`. The forces of the old
        positions stay until the next evaluation (a step or a relaxation), as a jump in a real test would;
        the contact list is rebuilt at the next evaluation."""
        idx = self._nodes(nodes)
        if (to_m is None) == (by_m is None):
            raise ValueError("give exactly one of to_m and by_m")
        if not self.model.held[idx].all():
            raise ValueError("move_held moves held nodes only: hold() them first")
        x = self.state.x
        if to_m is not None:
            x[idx] = finite_vectors("to_m", to_m, (idx.size, 3)) / units.LENGTH
        else:
            x[idx] += finite_vectors("by_m", by_m, (idx.size, 3)) / units.LENGTH
        self.contacts.status[STALE] = 1

    def displace_free(self, by_m) -> None:
        """Shift every free node by ``by_m`` [m] ((n, 3): the held nodes' rows are ignored) and evaluate the forces
        there (the contact list rebuilt): a perturbed state to start from."""
        by = finite_vectors("by_m", by_m, self.state.x.shape) / units.LENGTH
        free = ~self.model.held
        self.state.x[free] += by[free]
        self.contacts.status[STALE] = 1
        self.compute_forces()

    def set_external_forces(self, forces_N) -> None:
        """Replace the constant external forces [N], (n, 3) or one 3-vector for all, from now on (a new model).

        The forces of the current state change by the difference (not recomputed: a force
        evaluation would also advance the friction history by a step)."""
        f = finite_vectors("forces_N", forces_N, self.model.f_ext.shape) / units.FORCE
        self.work.force[:] += f - self.model.f_ext
        rail_forces(self.model.rail_node, self.model.rail_axis, self.work.force, self.work.rail_reaction)
        self.replace_model(f_ext=f)

    def reaction_forces_N(self) -> np.ndarray:
        """Force [N] the supports exert on each held node, and each rail on its node (zero on free nodes).

        A held node moves at constant prescribed velocity, so the support
        balances every other force on it: R = -F_rest. Read while held nodes move under a global drag
        (``ramp_held``), the reading carries the drag on everything they drag along, alpha M V
        (:meth:`reaction_bias_N`): a :class:`MovingSupportWarning` says so, with its size; read after ``settle``.
        """
        r = -self.work.force * units.FORCE
        r[~self.model.held] = 0.0
        r[self.model.rail_node] = -self.work.rail_reaction * units.FORCE
        bias = self.reaction_bias_N()
        if np.any(bias):
            total = float(np.linalg.norm(r.sum(axis=0)))
            warnings.warn(f"reaction read while the supports move under a drag of {self.drag / units.TIME:g} /s: "
                          f"biased by about {np.linalg.norm(bias):.3g} N (of {total:.3g} N in all); read it after "
                          "settle()", MovingSupportWarning, stacklevel=2)
        return r

    def reaction_bias_N(self) -> np.ndarray:
        """(3,) the bias [N] of the supports' total reaction read now: the global drag on the free nodes,
        alpha sum m v, which the supports pay while they move (zero when no held node moves or no drag acts)."""
        m = self.model
        if self.drag == 0.0 or not np.any(m.v_prescribed[m.held]):
            return np.zeros(3)
        free = ~m.held
        return self.drag * (m.mass[free, None] * self.state.v[free]).sum(axis=0) * units.FORCE


class ContactReadout:
    """What the contact saw, read from a :class:`Simulation`'s buffers (mixed into it): totals, each
    touching pair, the deepest overlap, the pairs between two yarns; the friction coefficient, and the
    friction history handed over from another simulation of the same nodes."""

    def adopt_friction_history(self, contacts: Contacts, edge_map: np.ndarray) -> None:
        """Take the contact pairs and their tangential springs from ``contacts`` (another simulation's, of the
        same nodes: its edge k is this one's ``edge_map[k]``, -1 where gone), then evaluate the forces with
        them: a knit loaded with friction, cut, keeps what the loading left in its contacts."""
        while not carry_friction_history(contacts, self.contacts, np.asarray(edge_map, dtype=np.int64)):
            self.contacts = make_contacts(self.rods, self.contact_model, capacity=2 * self.contacts.pairs.shape[0],
                                          previous=self.contacts)
        self.compute_forces()

    def set_friction(self, mu: float) -> None:
        """Change the Coulomb coefficient from the next step on (the paper: 0 while stretching, then 0.4)."""
        if self.contact_model is None:
            raise ValueError("this simulation has no contact model")
        check_friction_coefficient(mu)
        self.contacts = self.contacts._replace(params=self.contacts.params._replace(mu=float(mu)))

    @property
    def mu(self) -> float:
        """The Coulomb coefficient in force now (:meth:`set_friction`)."""
        return float(self.contacts.params.mu) if self.contact_model is not None else 0.0

    @property
    def friction(self) -> float:
        """Deprecated since 0.5.0: :attr:`mu`."""
        warnings.warn("Simulation.friction is deprecated since 0.5.0: use .mu", DeprecationWarning, stacklevel=2)
        return self.mu

    def contact_stats(self) -> ContactStats:
        """At the last force evaluation: touching pairs, largest overlap [m], sum of normal forces [N], sliding pairs, candidate pairs."""
        return ContactStats.of(self.contacts)

    def contact_pairs(self) -> ContactPairs:
        """Each touching pair at the last force evaluation: edges, yarns, contact point [m], normal and
        friction force on the first edge [N], overlap [m], sliding flag (arrays, one row per pair)."""
        m = self.model
        return ContactPairs.of(self.contacts, self.state.x, m.edge_a, m.edge_b, m.edge_shift)

    def peak_overlap_m(self, reset: bool = False) -> float:
        """Largest overlap of two yarns [m] at any step since the last reset (``reset``: start a new window)."""
        peak = float(self.contacts.stats[PEAK_OVERLAP] * units.LENGTH)
        if reset:
            self.contacts.stats[PEAK_OVERLAP] = 0.0
        return peak

    def touching_pairs(self, yarn_a: int, yarn_b: int) -> int:
        """Pairs of edges of yarns ``yarn_a`` and ``yarn_b`` touching now (images along a yarn's own period are it)."""
        return self.touching_pairs_of_edges(self.contacts.edge_yarn == yarn_a, self.contacts.edge_yarn == yarn_b)

    def touching_pairs_of_edges(self, in_a: np.ndarray, in_b: np.ndarray) -> int:
        """Pairs of an edge of ``in_a`` and one of ``in_b`` (boolean masks over the edges) touching now."""
        if self.contact_model is None:
            return 0
        m, c = self.model, self.fresh_contacts()
        return int(touching_pairs_among(self.state.x, m.edge_a, m.edge_b, m.edge_shift, c, in_a, in_b))


class Simulation(SupportControl, ContactReadout, ObstacleReadout, QuasiStatics, DissipationControl, Checkpointing,
                 Fracture):
    """Explicit dynamics and FIRE statics of a rod scene.

    Parameters
    ----------
    rods: the scene (from :meth:`knitlad.engine.state.Scene.build`): its model, and the state that
        this simulation advances in place (``sim.state``; pass ``rods.copy()`` to keep it).
    dt_s: time step [s]; default ``safety`` x the stability limit. A larger one
        than the limit is refused with :class:`UnstableTimeStep`.
    safety: fraction of the stability limit used when ``dt_s`` is not given.
    drag_per_s: global viscous drag rate [1/s] (0 for true dynamics; :mod:`knitlad.engine.dissipation`).
    material_damping: the yarn's viscoelasticity (:class:`knitlad.engine.dissipation.MaterialDamping`), or None.
        Its branch stiffens the rods at high frequency, which the step counts: set here, not later.
    air: air drag (:class:`knitlad.engine.dissipation.AirDrag`), or None; :meth:`set_air` changes it.
    spin_drag_per_s: a drag on every edge's spin about its axis, -gamma I omega [1/s] (with twist; the authors'
        engine's, :func:`knitlad.engine.dissipation.authors_drag_per_s`); :meth:`set_spin_drag` changes it.
    guard_every: steps between blow-up checks.
    contact: yarn-yarn contact (:class:`knitlad.engine.contact.ContactModel`), or None.
    framed_twist: with twist, bend and twist through material frames even without natural curvature.
    implicit_axial: the axial springs at the end of each kick (open yarns): the step set by contact and bending.
    predicted_dashpots: the dashpots act on the velocities predicted at the end of each step (second order in dt).
    (Both are modes of :mod:`knitlad.engine.kernels.integrate`.)
    obstacles: rigid planes and cylinders (:mod:`knitlad.engine.obstacles`), fixed or moving.
    """

    def __init__(self, rods: Rods, dt_s: float | None = None, safety: float = DEFAULT_SAFETY, drag_per_s: float = 0.0,
                 guard_every: int = 500, contact: ContactModel | None = None, framed_twist: bool = False,
                 implicit_axial: bool = False, predicted_dashpots: bool = False, obstacles: Sequence[Obstacle] = (),
                 material_damping: MaterialDamping | None = None, air: AirDrag | None = None,
                 spin_drag_per_s: float = 0.0) -> None:
        """Build the model's stepping for ``rods`` (the parameters: the class docstring): the stability limits and
        the step, the contact buffers and the obstacles' state, the forces of the initial state, the energy
        ledger's start. Nothing is stepped. Refuses a step above the stability limit (UnstableTimeStep), a
        natural curvature without material frames, and settings out of range (ValueError, naming them)."""
        if not 0.0 < safety <= 1.0:
            raise ValueError(f"safety must lie in (0, 1], got {safety}")
        if rods.twist and not rods.framed and np.any(rods.model.kappa_bar):
            raise ValueError("the rods have a natural curvature (kappa_bar) but are not framed: build them with "
                             "Rods(..., framed=True) or replace_model(kappa_bar=..., framed=True)")
        self.rods = rods
        self._shift_drift = 0.0  # largest move of a closing edge [mm] since the last forced rebuild (replace_model)
        self.twist = rods.twist
        self.framed_twist = bool(framed_twist)
        self.axial_mode = AXIAL_IMPLICIT if check_open_chains(rods.model, implicit_axial) else AXIAL_EXPLICIT
        self.dashpot_mode = DASHPOTS_PREDICTED if predicted_dashpots else DASHPOTS_HALF_STEP
        self.work = Workspace.for_model(self.model)
        self.contact_model = contact
        self.contacts: Contacts = make_contacts(rods, contact)
        self.obstacles = obstacle_state(list(obstacles), self.model.n_nodes) if len(obstacles) else None
        # the kernels get an empty state rather than None: one compiled step serves scenes with and without
        self._kernel_obstacles = self.obstacles if self.obstacles is not None else obstacle_state([], self.model.n_nodes)
        contact_limit = contact_time_step(self.model, contact, spin=self.twist, predicted=predicted_dashpots)
        wall_limit = obstacle_time_step(self.model, list(obstacles), predicted=predicted_dashpots)
        if math.isfinite(wall_limit):  # springs in parallel: omega^2 adds
            contact_limit = 1.0 / math.sqrt(1.0 / contact_limit**2 + 1.0 / wall_limit**2)
        self.material_damping = material_damping
        self.limits: TimeStepLimits = critical_time_steps(
            self.model, self.twist, contact_limit, bool(implicit_axial), bool(predicted_dashpots),
            material_damping.branch_ratio if material_damping else 0.0)
        self.dt = self.limits.time_step(dt_s, safety)
        self.set_drag(drag_per_s)
        self.set_spin_drag(spin_drag_per_s)
        self.set_air(air)
        if not (isinstance(guard_every, (int, np.integer)) and guard_every >= 1):
            raise ValueError(f"guard_every must be a whole number of steps >= 1, got {guard_every!r}")
        self.guard_every = int(guard_every)
        self.steps = 0
        self.time = 0.0  # internal ms
        self.threads = ThreadGovernor()
        self.max_speed = axial_wave_speed(self.model)
        self.relax_branches()
        self.compute_forces()
        self.reset_ledger()

    def _grow_contacts(self) -> None:
        """Double the pair buffer (past what the last build needed), keeping the history."""
        c = self.contacts
        cap = max(2 * c.pairs.shape[0], int(1.5 * c.status[PAIRS_NEEDED]))
        self.contacts = make_contacts(self.rods, self.contact_model, capacity=cap, previous=c)

    def compute_forces(self, predicted: bool = False) -> None:
        """Forces and torques of the current state into ``self.work`` (growing the contact buffer if needed);
        the dashpots see the state's velocities, or with ``predicted`` the step's prediction."""
        if not predicted:
            self.work.v_damp[:], self.work.omega_damp[:] = self.state.v, self.state.omega
        with self.threads.one_call():
            while not compute_forces(self.model, self.state, self.work, self.contacts, self.twist_mode,
                                     self.has_contact, self.damping, self.dt, self.axial_mode, self.dashpot_mode,
                                     self._kernel_obstacles):
                self._grow_contacts()

    @property
    def model(self):
        """The scene's :class:`knitlad.engine.state.RodModel` (replaced, never changed, by :meth:`replace_model`)."""
        return self.rods.model

    @property
    def state(self):
        """The :class:`knitlad.engine.state.RodState` this simulation advances in place."""
        return self.rods.state

    @property
    def has_contact(self) -> bool:
        """Yarn-yarn contact is on (a contact model was given)."""
        return self.contact_model is not None

    def replace_model(self, **arrays) -> None:
        """Replace model arrays of the same shapes (e.g. a periodic cell's shifts) from the next step on."""
        old_shift = self.model.edge_shift
        self.rods = self.rods.replace_model(**arrays)
        if "edge_shift" in arrays:  # closing edges moved without their nodes: the pairs' stored gaps no longer bound
            self.contacts.status[GAPS_KNOWN] = 0
            # nor does the list's skin, which counts node displacements only: rebuild once the closing
            # edges may have moved by half of it since this simulation last forced a rebuild
            self._shift_drift += float(np.max(np.abs(self.model.edge_shift - old_shift), initial=0.0)) * math.sqrt(3.0)
            if self._shift_drift > 0.5 * self.contacts.params.skin:
                self.contacts.status[STALE] = 1
                self._shift_drift = 0.0

    def fresh_contacts(self) -> Contacts:
        """The contact buffers with a candidate list valid at the current positions."""
        m, s = self.model, self.state
        follow_images(s.x, s.v, m.image_node, m.image_master, m.image_shift)
        if self.contact_model is None:
            return self.contacts  # empty buffers: nothing to refresh
        while not refresh_contacts(s.x, m.edge_a, m.edge_b, m.edge_shift, self.contacts, s.v, 0.0):  # no lookahead
            self._grow_contacts()
        return self.contacts

    # ------------------------------------------------------------------ dynamics
    @property
    def dt_s(self) -> float:
        return self.dt * units.TIME

    @property
    def twist_mode(self) -> int:
        """The kernels' twist mode: framed DER for natural curvature (or ``framed_twist``), else the frame-free path."""
        framed = self.framed_twist or self.rods.framed
        return TWIST_OFF if not self.twist else TWIST_FRAMED if framed else TWIST_STRAIGHT

    @property
    def time_s(self) -> float:
        return self.time * units.TIME

    def step(self, n_steps: int = 1) -> None:
        """Advance ``n_steps`` steps, checking for blow-up every ``guard_every``. Refused before any step: a
        count that is not a whole number >= 0 or over :data:`knitlad.engine.timestep.MAX_STEPS`, a state or a load that is not finite."""
        left = step_count("n_steps", n_steps)
        self.check_finite()
        allowed = numba.get_num_threads()
        while left > 0:
            chunk = min(left, self.guard_every, self.break_check_every if self.breaking_force_N is not None else left)
            threads = self.threads.plan(allowed)
            numba.set_num_threads(threads)
            t0 = time.perf_counter()
            try:
                done = verlet_steps(self.model, self.state, self.work, self.contacts, self.dt, chunk, self.twist_mode,
                                    self.has_contact, self.damping, self.axial_mode, self.dashpot_mode,
                                    self._kernel_obstacles)
            finally:
                numba.set_num_threads(allowed)
            self.threads.record(threads, done, time.perf_counter() - t0)
            if done < chunk:
                # the contact buffer overflowed inside step `done`: grow it and close that step
                self.compute_forces(predicted=True)
                half_kick(self.model, self.state, self.work, 0.5 * self.dt, self.twist_mode)
                done += 1
            self.steps += done
            self.time += done * self.dt
            left -= done
            self._guard()
            self.break_overloaded()

    def run(
        self,
        duration_s: float,
        observe: Callable[["Simulation"], None] | None = None,
        observe_every_s: float | None = None,
    ) -> None:
        """Advance by ``duration_s``; call ``observe(self)`` every ``observe_every_s``."""
        n_total = max(1, step_count("duration_s", duration_s / self.dt_s))
        every = n_total if observe_every_s is None else max(1, step_count("observe_every_s", observe_every_s / self.dt_s))
        done = 0
        while done < n_total:
            chunk = min(every, n_total - done)
            self.step(chunk)
            done += chunk
            if observe is not None:
                observe(self)

    def check_finite(self) -> None:
        """A ValueError naming what is not finite, among the positions, velocities, constant forces and
        prescribed velocities: an infinity would reach the contact's grid (outside its cells), a NaN the step."""
        m, s = self.model, self.state
        for name, array in (("state.x (positions)", s.x), ("state.v (velocities)", s.v),
                            ("external forces (f_ext)", m.f_ext), ("prescribed velocities of held nodes", m.v_prescribed)):
            if not np.all(np.isfinite(array)):
                node = int(np.flatnonzero(~np.isfinite(array).all(axis=-1))[0])
                raise ValueError(f"{name}: NaN or infinity at node {node}; nothing was run")

    def _guard(self) -> None:
        node, kind = first_bad_node(self.state.x, self.state.v, self.max_speed)
        if node >= 0:
            yarn, local = self.model.yarn_of(node)
            what = "non-finite position or velocity" if kind == 1 else (
                f"speed above the axial wave speed {self.max_speed * units.VELOCITY:.0f} m/s"
            )
            raise SimulationBlowUp(
                f"blow-up by step {self.steps} (t = {self.time_s:.4e} s): {what} at yarn {yarn}, node {local}; "
                f"dt = {self.dt_s:.3e} s, stability limit {self.limits.combined * units.TIME:.3e} s"
            )

    # ------------------------------------------------------------------ statics
    def relax(self, force_tol_N: float = 1e-7, max_steps: int = 200_000, torque_tol_Nm: float | None = None) -> dict:
        """FIRE minimisation to static equilibrium with the held nodes fixed.

        Returns a dict with ``steps``, ``max_force_N``, ``converged``.
        """
        max_steps = step_count("max_steps", max_steps)
        self.check_finite()
        ftol = force_tol_N / units.FORCE
        ttol = (torque_tol_Nm if torque_tol_Nm is not None else force_tol_N * 1e-3) / (units.FORCE * units.LENGTH)
        with self.threads.one_call():
            while True:
                steps, fmax, tmax = fire_relax(
                    self.model, self.state, self.work, self.contacts, 0.5 * self.dt, self.dt, int(max_steps), ftol,
                    ttol, self.twist_mode, self.has_contact, self._kernel_obstacles,
                )
                if steps >= 0:
                    break
                self._grow_contacts()
        self._guard()
        self.relax_branches()
        self.compute_forces()
        self.reset_ledger()
        return {
            "steps": int(steps),
            "max_force_N": float(fmax * units.FORCE),
            "max_torque_Nm": float(tmax * units.FORCE * units.LENGTH),
            "converged": bool(fmax <= ftol and tmax <= ttol),
        }

    # ------------------------------------------------------------------ read-out
    def positions_m(self) -> np.ndarray:
        return self.state.x * units.LENGTH

    def forces_N(self) -> np.ndarray:
        """Net force on each node at the last evaluation [N]."""
        return self.work.force * units.FORCE


def energy_history(sim: Simulation, samples: int, every_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Step ``sim`` ``samples`` times by ``every_s`` (whole steps, at least one); the total and
    kinetic energy [J] at the start and after each interval, as two arrays of samples + 1."""
    n = max(1, int(round(every_s / sim.dt_s)))
    total, kinetic = [], []
    for k in range(samples + 1):
        if k:
            sim.step(n)
        e = sim.energies_J()
        total.append(e["total"])
        kinetic.append(e["kinetic"])
    return np.array(total), np.array(kinetic)
