"""A yarn that breaks: segments whose tension exceeds the yarn's breaking force are cut during a run.

The criterion is the axial spring's tension T = EA (|e|/|e_bar| - 1) of each segment, against the
material's breaking force (:attr:`knitlad.engine.units.Material.breaking_force`; the Nylon's from its
tenacity). Between steps (every ``check_every`` of them) the most loaded segment of each yarn over the
limit is cut as the laddering's cut is (:func:`knitlad.engine.state.cut_edge`): the node arrays keep their
indices, the contact pairs of every other segment keep their tangential springs (the friction history),
the viscoelastic branches of the segments and hinges that stay keep their state, and the energy ledger
goes on. The elastic energy stored in what the cut removes (the segment's spring, its two hinges, its
contact springs) leaves with it: the ledger books it as ``fracture``.

A segment touching a yarn's end is not cut (a piece of one node is no rod). The breaking force may be
one value or one per segment: a uniform yarn under a uniform tension reaches its limit everywhere at
once and breaks at many points within a few steps, as a uniform brittle fibre would fragment; a real
yarn breaks at its weakest point, which a per-segment strength gives it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import make_contacts
from knitlad.engine.kernels.elastic import edge_vectors
from knitlad.engine.state import Workspace, cut_edge


@dataclass(frozen=True)
class Break:
    """One segment the run cut: when [s] and after how many steps, which segment (its index in the model
    before the cut, and its first node, whose index does not change), its yarn and the tension it carried [N]."""

    time_s: float
    step: int
    edge: int
    node: int
    yarn: int
    tension_N: float


def breakable_edges(model) -> np.ndarray:
    """(ne,) bool: the inner segments of open yarns, which :func:`knitlad.engine.state.cut_edge` can cut and
    leave two pieces of two nodes or more, less those between two held nodes: their length is imposed by
    the supports (a knit's held bars and clamps, stretched with its box: 48 % at l_x/l0 0.26 -> 0.38, 10.7 N
    in a Nylon bar that "broke" at the first step of a snag), so their tension is the machine's, not the
    yarn's under test."""
    a, b = model.edge_a, model.edge_b
    inner = (b == a + 1) & ~np.any(model.edge_shift != 0, axis=1)
    first = model.yarn_start[model.node_yarn[a]]
    last = model.yarn_start[model.node_yarn[a] + 1] - 1
    return inner & (a > first) & (b < last) & ~(model.held[a] & model.held[b])


class Fracture:
    """Mixin of :class:`knitlad.engine.simulation.Simulation`: a breaking force, the check between steps, the
    cut during a run with the history kept, and the record of what broke (``breaks``)."""

    breaking_force_N: float | np.ndarray | None = None
    break_check_every: int = 1
    breaks: tuple[Break, ...] = ()
    _fracture_J: float = 0.0

    def set_breaking_force(self, force_N, check_every: int = 1) -> None:
        """Cut, between steps (every ``check_every``), each yarn's most loaded segment whose tension exceeds its
        breaking force ``force_N`` [N]: one value (a material's :attr:`~knitlad.engine.units.Material.breaking_force`)
        or one per segment (a weak point); None: no yarn breaks."""
        if force_N is not None:
            force_N = np.asarray(force_N, dtype=float)
            if force_N.shape not in ((), self.model.edge_a.shape):
                raise ValueError(f"the breaking force is one value or one per segment ({self.model.edge_a.shape[0]}), "
                                 f"got shape {force_N.shape}")
            if not np.all(force_N > 0):
                raise ValueError(f"the breaking force must be > 0 N (or None), got {force_N.min()!r}")
            force_N = float(force_N) if force_N.ndim == 0 else force_N.copy()
        if not (isinstance(check_every, (int, np.integer)) and check_every >= 1):
            raise ValueError(f"check_every must be a whole number of steps >= 1, got {check_every!r}")
        self.breaking_force_N = force_N
        self.break_check_every = int(check_every)

    def tensions_N(self) -> np.ndarray:
        """(ne,) each segment's axial spring tension EA (|e|/|e_bar| - 1) [N] at the current positions."""
        m = self.model
        e, elen = np.zeros((m.edge_a.shape[0], 3)), np.zeros(m.edge_a.shape[0])
        edge_vectors(self.state.x, m.edge_a, m.edge_b, m.edge_shift, e, elen)
        return m.EA * (elen / m.rest_length - 1.0) * units.FORCE

    def break_overloaded(self) -> list[Break]:
        """Cut each yarn's most loaded breakable segment over the breaking force (none without one); the new
        breaks, also added to ``breaks``."""
        if self.breaking_force_N is None:
            return []
        m = self.model
        tension = self.tensions_N()
        over = np.flatnonzero(breakable_edges(m) & (tension > self.breaking_force_N))
        if over.size == 0:
            return []
        yarn = m.node_yarn[m.edge_a[over]]
        worst = {}
        for k, y in zip(over, yarn):
            if int(y) not in worst or tension[k] > tension[worst[int(y)]]:
                worst[int(y)] = int(k)
        new = [Break(self.time_s, self.steps, k, int(m.edge_a[k]), y, float(tension[k])) for y, k in worst.items()]
        self.cut_edges([b.edge for b in new])
        self.breaks = (*self.breaks, *new)
        return new

    def cut_edges(self, edges) -> None:
        """Cut the segments ``edges`` (indices in the present model) now, as a break would: the friction history
        of every other segment's contacts, the branches' state and the ledger (with the energy the cut removed
        booked as ``fracture``) carry on. The step size is kept: a cut lowers no stiffness's frequency bound."""
        edges = sorted({int(k) for k in edges}, reverse=True)  # from the last: the indices before it stay valid
        if not edges:
            return
        stored_before = self.ledger().stored
        for edge in edges:
            self._cut_one(edge)
        self._fracture_J += stored_before - self.ledger().stored

    def _cut_one(self, edge: int) -> None:
        m, w = self.model, self.work
        ne, mu = m.edge_a.shape[0], self.mu
        kept_edges = np.arange(ne) != edge
        kept_hinges = (m.hinge_e0 != edge) & (m.hinge_e1 != edge)
        old_contacts = self.contacts
        self.rods = cut_edge(self.rods, edge)
        if isinstance(self.breaking_force_N, np.ndarray):
            self.breaking_force_N = self.breaking_force_N[kept_edges]
        work = Workspace.for_model(self.model)
        work.ledger[0] = w.ledger.sum(axis=0)  # the rows are yarns' and blocks': only their sum is read
        work.branch_ext[:] = w.branch_ext[kept_edges]
        work.branch_kb[:] = w.branch_kb[kept_hinges]
        self.work = work
        edge_map = np.where(kept_edges, np.cumsum(kept_edges) - 1, -1)
        if self.has_contact:
            self.contacts = make_contacts(self.rods, self.contact_model)
            self.set_friction(mu)
            self.adopt_friction_history(old_contacts, edge_map)
        else:
            self.compute_forces()
