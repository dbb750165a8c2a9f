"""Contact model (parameters in SI) and its buffers (internal units).

See :mod:`knitlad.engine.kernels.contact` for the physics. Stiffness is set from the
working force of a scene: ``ContactModel.for_force(F, overlap_fraction=0.05)``
gives the k_n at which a contact carrying F overlaps by 5 % of the diameter.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

import numba
import numpy as np

from knitlad.engine import units
from knitlad.engine.deprecation import removed_field, renamed_field
from knitlad.engine.kernels.contact import (
    GAPS_KNOWN,
    HISTORY_COLUMNS,
    MAX_OVERLAP,
    N_STATS,
    NORMAL_FORCE_SUM,
    PAIR_RESULTS,
    PEAK_OVERLAP,
    SHARE_COLUMNS,
    SLIDING_PAIRS,
    STALE,
    TOUCHING,
    ContactParams,
    ListScratch,
    list_scratch,
)
from knitlad.engine.kernels.contact_law import (
    FRICTION_FACTOR,
    K_NORMAL,
    K_TANGENT,
    LAW,
    LAW_COLUMNS,
    REFERENCE_OVERLAP,
    largest_slope_factor,
    law_mode,
)
from knitlad.engine.state import RodModel, Rods
from knitlad.engine.timestep import damped_limit_factor


class Counting(str, Enum):
    """How touching capsules of two yarns count (see :mod:`knitlad.engine.kernels.contact`).

    UNION: a yarn is the union of its capsules, a contact at a node shared by two edges
    counts once (exact friction; not conservative where a crossing sits at a node).
    ALL_PAIRS: every touching edge pair counts (a sum of pair potentials, conservative).
    """

    UNION = "union"
    ALL_PAIRS = "all_pairs"


COUNTING = tuple(c.value for c in Counting)
# the contact list gives an edge fast enough to cross half the skin within this many steps an allowance
# that lasts it as long (ContactParams.lookahead_steps, refresh_contacts): a cut yarn's flying ends rebuilt
# the whole list every 12 steps of the accurate 42 x 42 ladder, every 46 at 40 steps, every 39 at 80 (4 % faster
# than 40; 160 not resolved from 80: docs/performance.md)
LIST_LOOKAHEAD_STEPS = 80
# the list's skin when the model gives none, in the smallest yarn diameter: 0.75 lists 20 % fewer pairs than 1
# for 25 % more rebuilds, since the allowances keep the fast edges from setting the rebuilds (0.91 x the time of
# the accurate 42 x 42 ladder's steps, 0.86 x at the fast preset, paired; any skin gives the same bits:
# docs/performance.md)
DEFAULT_SKIN_DIAMETERS = 0.75


def check_contact_law(law: str, reference_overlap: float | None) -> None:
    """The one check of a contact law and its reference overlap [m] (yarn contact and obstacles)."""
    law_mode(law)
    if reference_overlap is not None and not (reference_overlap > 0 and math.isfinite(reference_overlap)):
        raise ValueError(f"reference_overlap must be > 0 m or None, got {reference_overlap!r}")
    if law != "linear" and reference_overlap is None:
        raise ValueError(f"the {law} contact law needs reference_overlap, the overlap [m] where it gives "
                         "stiffness x reference_overlap (ContactModel.for_force sets it)")


def check_friction_coefficient(mu: float) -> None:
    """The one check of a Coulomb coefficient, wherever one is given (contact, obstacles, a run's switch)."""
    if not (mu >= 0 and math.isfinite(mu)):
        raise ValueError(f"mu (the friction coefficient) must be >= 0, got {mu!r}")


# the knit scenes' contact stiffness, said once: a contact carrying this force [f0] overlaps by KNIT_OVERLAP d
# (halving or doubling it moves the 42 x 42 knit's v_lad by under 5 %: docs/dissipation.md)
KNIT_CONTACT_FORCE_F0 = 20.0
KNIT_OVERLAP = 0.05


def dashpot_ratio(coefficient_N_s_per_m: float, stiffness_N_per_m: float, node_mass_kg: float) -> float:
    """The fraction of critical (``ContactModel.damping_ratio``) that a normal dashpot of ``coefficient`` is on a
    contact between two yarns of nodes of ``node_mass_kg``: c / (2 sqrt(k_n m_eff)), m_eff = m / 2 (each side's
    interpolated mass is one node's on a uniform yarn), as the pair kernel's dashpot 2 zeta sqrt(k_n m_eff)."""
    return coefficient_N_s_per_m / (2.0 * math.sqrt(stiffness_N_per_m * 0.5 * node_mass_kg))


HELD_FRICTION_REMOVED = "the friction held over several steps was a study, measured a no-go: docs/performance.md"


@renamed_field("friction", "mu", since="0.5.0")
@removed_field("friction_every", 1, since="0.15.0", why=HELD_FRICTION_REMOVED)
@dataclass(frozen=True)
class ContactModel:
    """Yarn-yarn contact parameters (SI).

    stiffness       k_n [N/m]   normal penalty stiffness
    mu              [-]         Coulomb coefficient (changeable during a run; ``friction`` before 0.5.0)
    damping_ratio   zeta_n [-]  normal dashpot as a fraction of critical (per contact)
    tangential_stiffness_ratio  k_t / k_n [-]
    tangential_damping_ratio    zeta_t [-]
    skin            [m]         neighbour-list margin (default: 0.75 x the smallest yarn diameter)
    exclusion_diameters [-]     same-yarn edges closer than this many diameters of arc
                                (and at least the adjacent edge) never interact
    contacts_per_node [-]       contacts one node may carry at once, for the time-step limit
    capacity_per_edge [-]       initial pair-buffer size per edge (grown on overflow)
    counting                    "union" (default): a yarn is the union of its capsules, a
                                contact at a node shared by two edges counts once; "all_pairs":
                                every touching edge pair counts (a conservative energy, stiffer
                                where a crossing sits at a node; see docs/accuracy.md)
    sagitta_radius  R_s [m]     the capsule chain's sagitta correction: each edge's contact radius
                                is r - l^2/(12 R_s), l its rest length (:func:`sagitta_corrected_radius`);
                                None: capsules of the yarn's radius
    law                         the normal spring f(delta): "linear" (default, f = k_n delta) or "hertz"
                                (f = k_n delta_ref (delta/delta_ref)^(3/2), crossed elastic cylinders;
                                :mod:`knitlad.engine.kernels.contact_law`)
    reference_overlap  delta_ref [m]  the overlap where every law gives k_n delta_ref (set by :meth:`for_force`;
                                needed by a nonlinear law)
    yarn_friction   [-]         ``((yarn, factor), ...)``: a contact touching one of these yarns (its index as
                                built: a cut's pieces keep it) has the Coulomb coefficient factor x mu; one between
                                two of them the larger factor (the rougher surface sets the friction): a band of
                                coated courses in a knit (a run-stop band)
    pair_stiffness  [N/m]       ``((material_a, material_b, k_n), ...)``: the normal stiffness of contacts
                                between a yarn of material a and one of material b (either order; the
                                tangential spring keeps its ratio); every other pair has ``stiffness``.
                                A yarn's material is known to the contact by its diameter and Young's
                                modulus (what sets a contact's stiffness); a material that no edge has
                                is refused (an EA softened by ``with_axial_stiffness`` hides a material)
    """

    stiffness: float
    mu: float = 0.0
    damping_ratio: float = 0.3
    tangential_stiffness_ratio: float = 0.5
    tangential_damping_ratio: float = 0.3
    skin: float | None = None
    exclusion_diameters: float = 2.5
    contacts_per_node: int = 2
    capacity_per_edge: int = 4
    counting: Counting = Counting.UNION
    sagitta_radius: float | None = None
    pair_stiffness: tuple = ()
    law: str = "linear"
    reference_overlap: float | None = None
    yarn_friction: tuple = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "pair_stiffness", tuple(tuple(entry) for entry in self.pair_stiffness))
        for entry in self.pair_stiffness:
            if len(entry) != 3 or not all(isinstance(m, units.Material) for m in entry[:2]):
                raise ValueError(f"pair_stiffness entries are (Material, Material, k_n [N/m]), got {entry!r}")
            if not (entry[2] > 0 and math.isfinite(entry[2])):
                raise ValueError(f"pair_stiffness: k_n must be > 0 N/m, got {entry[2]!r}")
        if not (self.stiffness > 0 and math.isfinite(self.stiffness)):
            raise ValueError(f"contact stiffness must be > 0 N/m, got {self.stiffness!r}")
        check_friction_coefficient(self.mu)
        for name in ("damping_ratio", "tangential_damping_ratio", "exclusion_diameters"):
            if not (getattr(self, name) >= 0 and math.isfinite(getattr(self, name))):
                raise ValueError(f"{name} must be a finite number >= 0, got {getattr(self, name)!r}")
        if not (self.tangential_stiffness_ratio > 0 and math.isfinite(self.tangential_stiffness_ratio)):
            raise ValueError(f"tangential_stiffness_ratio must be a finite number > 0, got "
                             f"{self.tangential_stiffness_ratio!r}")
        for name in ("contacts_per_node", "capacity_per_edge"):
            value = getattr(self, name)
            if not (isinstance(value, (int, np.integer)) and not isinstance(value, bool) and value >= 1):
                raise ValueError(f"{name} must be a whole number >= 1, got {value!r}")
        if self.counting not in COUNTING:
            raise ValueError(f"counting must be one of {', '.join(COUNTING)}, got {self.counting!r}")
        object.__setattr__(self, "counting", Counting(self.counting))
        if self.skin is not None and not self.skin > 0:
            raise ValueError(f"skin must be > 0 m, got {self.skin!r}")
        if self.sagitta_radius is not None and not (self.sagitta_radius > 0 and math.isfinite(self.sagitta_radius)):
            raise ValueError(f"sagitta_radius must be > 0 m or None, got {self.sagitta_radius!r}")
        check_contact_law(self.law, self.reference_overlap)
        object.__setattr__(self, "yarn_friction", tuple((int(y), float(f)) for y, f in self.yarn_friction))
        for yarn, factor in self.yarn_friction:
            if yarn < 0 or not (factor >= 0 and math.isfinite(factor)):
                raise ValueError(f"yarn_friction entries are (yarn index >= 0, factor >= 0), got {(yarn, factor)!r}")

    @staticmethod
    def for_force(force_N: float, diameter_m: float, overlap_fraction: float = 0.05, **kwargs) -> "ContactModel":
        """k_n such that a contact carrying ``force_N`` overlaps by ``overlap_fraction`` x d (that overlap is the
        law's reference: a contact carries ``force_N`` there whatever the law)."""
        if not 0 < overlap_fraction < 1:
            raise ValueError("overlap_fraction must lie in (0, 1)")
        return ContactModel(stiffness=force_N / (overlap_fraction * diameter_m),
                            reference_overlap=overlap_fraction * diameter_m, **kwargs)

    @staticmethod
    def of_settings(settings, **kwargs) -> "ContactModel":
        """The contact of an experiment's settings (:meth:`for_knit`): any object naming ``material``,
        ``contact_force_f0``, ``overlap_fraction`` and, if it has them, ``sagitta_radius`` (in d) and ``contact_law``
        (the laddering's, the stitch's and the single loops' settings); ``kwargs`` as :meth:`for_knit`'s (``mu``,
        dashpots)."""
        return ContactModel.for_knit(settings.material, settings.contact_force_f0, settings.overlap_fraction,
                                     getattr(settings, "sagitta_radius", 0.0),
                                     **{"law": getattr(settings, "contact_law", "linear"), **kwargs})

    @staticmethod
    def for_knit(material, contact_force_f0: float = KNIT_CONTACT_FORCE_F0, overlap_fraction: float = KNIT_OVERLAP,
                 sagitta_radius_d: float = 0.0, **kwargs) -> "ContactModel":
        """The knit scenes' contact: a contact carrying ``contact_force_f0`` f0 overlaps by ``overlap_fraction`` d;
        ``sagitta_radius_d`` > 0: the sagitta correction for a yarn curved on that many diameters."""
        sagitta = sagitta_radius_d * material.diameter if sagitta_radius_d > 0 else None
        return ContactModel.for_force(contact_force_f0 * material.f0, material.diameter,
                                      overlap_fraction=overlap_fraction, sagitta_radius=sagitta, **kwargs)


def sagitta_corrected_radius(radius: np.ndarray, rest_length: np.ndarray, curvature_radius: float) -> np.ndarray:
    """Contact radius r - l^2 / (12 R) of edges of rest length l on a yarn curved on radius R (any one unit).

    A straight capsule stands for an arc of its yarn; on an arc of curvature 1/R the chord lies
    on the concave side, by l^2 s (1 - s) / (2 R) at s along it, l^2 / (12 R) on average. Where
    a yarn wraps another (a loop's head round the legs of the next course) the other yarn is on
    that side, so a chain of capsules of the yarn's radius touches it sooner than the smooth
    yarn would: the stitch behaves as if the yarn were thicker, and its tension at fixed
    periodicities is too high (by 50 % at l_x/l0 = 0.37 with 24 nodes per stitch, where l = 2.9 d).
    Taking the mean sagitta off the radius removes most of that at no cost; R is the typical
    radius of curvature at the stitch's contacts, measured through the converged stitch
    (``docs/accuracy.md``). The correction vanishes as l^2 when the yarn is refined.
    """
    corrected = radius - rest_length**2 / (12.0 * curvature_radius)
    if np.any(corrected < 0.5 * radius):
        raise ValueError(f"edges up to {float(rest_length.max()):.3g} long are too long for the sagitta correction "
                         f"on a radius of curvature {curvature_radius:.3g}: it would take over half their radius; "
                         "refine the yarn")
    return corrected


class Contacts(NamedTuple):
    """Buffers of the contact kernels (internal units). Rebuilt by :func:`make_contacts`."""

    pairs: np.ndarray  # (cap, 2) candidate edge pairs, i < j, sorted
    keys: np.ndarray  # (cap,) i * ne + j
    slip: np.ndarray  # (cap, HISTORY_COLUMNS or HELD_...) per pair: tangential spring u_t, union verdict, overlap
    n_pairs: np.ndarray  # (1,) valid pairs
    status: np.ndarray  # (N_STATUS,) slots STALE (the list must be rebuilt), PAIRS_NEEDED (at the last overflow), ...
    x_ref: np.ndarray  # (n, 3) positions at the last rebuild
    edge_radius: np.ndarray
    edge_prev: np.ndarray  # previous edge along the yarn, -1 at an open end
    edge_next: np.ndarray  # next edge along the yarn, -1 at an open end
    union: bool  # Counting.UNION (else ALL_PAIRS)
    edge_yarn: np.ndarray  # physical yarn (see contact_topology)
    edge_local: np.ndarray  # arc index along the physical yarn
    yarn_edges: np.ndarray
    yarn_closed: np.ndarray  # arc indices wrap (rings)
    exclusion: np.ndarray  # (n_yarns,) edges excluded either side along a yarn
    edge_image: np.ndarray  # (ne,) bool: edge of a periodic image (image-image pairs are skipped)
    params: ContactParams  # stiffnesses, dashpots, mu, skin (internal units)
    stats: np.ndarray  # (N_STATS,) slots TOUCHING ... PEAK_OVERLAP of knitlad.engine.kernels.contact
    threads: np.ndarray  # (1,) blocks the broad phase and the pair forces are split into (Numba threads)
    pair_results: np.ndarray  # (cap, PAIR_RESULTS) scratch of contact_forces
    gap_ref: np.ndarray  # (cap,) each pair's gap at the list's first evaluation (a lower bound at its rebuild)
    edge_moved: np.ndarray  # (ne,) each edge's largest end displacement since the rebuild (scratch)
    edge_class: np.ndarray  # (ne,) int64 row of ``stiffness`` for each edge's material (0: the default)
    pair_law: np.ndarray  # (c, c, LAW_COLUMNS) k_n, k_t [mN/mm], law, delta_ref [mm] of a pair of edge classes
    edge_allowance: np.ndarray  # (ne,) how far each edge may move before the list is stale (half the skin, more if fast)
    list_scratch: ListScratch  # work arrays of a rebuild, kept between rebuilds
    edge_rod: np.ndarray  # (ne,) int64 the yarn of the state (RodModel.yarn_start) whose nodes each edge moves
    share_layout: np.ndarray  # (1,) int64 the pair blocks ``bucket_start`` is laid out for (0: none yet)
    bucket_start: np.ndarray  # (max threads, n_yarns) int64 first slot of each block's shares for each yarn
    bucket_fill: np.ndarray  # (max threads, n_yarns) int64 the next free slot of each bucket, this evaluation
    shares: np.ndarray  # (2 cap, SHARE_COLUMNS) each touching pair's share on each of its two edges
    share_edge: np.ndarray  # (2 cap,) int64 2 k + (0: the pair's first edge k, 1: its second)
    rod_stats: np.ndarray  # (n_yarns, N_STATS) each yarn's part of ``stats`` (rod_contact_sum)


def edge_topology(m: RodModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Yarn of each edge, its index within the yarn, edges per yarn, closed flags."""
    edge_yarn = m.edge_yarn
    n_yarns = m.n_yarns
    yarn_edges = np.bincount(edge_yarn, minlength=n_yarns).astype(np.int64)
    first = np.concatenate([[0], np.cumsum(yarn_edges)[:-1]])
    edge_local = np.arange(edge_yarn.shape[0]) - first[edge_yarn]
    yarn_nodes = np.diff(m.yarn_start)
    yarn_closed = yarn_edges == yarn_nodes
    return edge_yarn.astype(np.int64), edge_local.astype(np.int64), yarn_edges, yarn_closed


def contact_topology(m: RodModel):
    """What the contact kernels need to know about the yarns, periodic images included.

    Returns (edge_yarn, edge_arc, yarn_edges, yarn_wraps, edge_prev, edge_next, edge_image):

    * ``edge_yarn``: the *physical* yarn of each edge. An image of a yarn
      periodised along its own period P by k P is the same physical yarn k
      periods further along, so its edges carry the master's id and the arc
      index local + k n_edges: the same-yarn exclusion then also works across
      the seam. Other images (another course, say) are yarns of their own. The
      pieces of a cut yarn (``RodModel.yarn_parent``) are one physical yarn whose
      arc index skips the cut edge, so the exclusion also holds across the cut.
    * ``yarn_wraps``: arc indices wrap around (true rings only; a periodised
      yarn continues into its images instead).
    * ``edge_prev``/``edge_next``: the neighbouring edge along the yarn, into
      the next image across a periodised yarn's seam, -1 at an open end or
      where that image is not in the scene.
    * ``edge_image``: the edge belongs to a periodic image.
    """
    edge_yarn, edge_local, yarn_edges, yarn_closed = edge_topology(m)
    n_yarns = m.n_yarns
    parent = m.yarn_parent
    first_edge = np.concatenate([[0], np.cumsum(yarn_edges)[:-1]]).astype(np.int64)
    last_edge = first_edge + yarn_edges - 1
    period = np.zeros((n_yarns, 3))
    period[yarn_closed] = m.edge_shift[last_edge[yarn_closed]]
    periodised = yarn_closed & np.any(period != 0, axis=1)
    master = np.arange(n_yarns)
    shift = np.zeros((n_yarns, 3))
    is_image = np.zeros(n_yarns, dtype=bool)
    if m.image_node.size:
        first_node = m.yarn_start[:-1]
        where = {int(n): g for g, n in enumerate(m.image_node)}
        for y in range(n_yarns):
            g = where.get(int(first_node[y]))
            if g is not None:
                is_image[y] = True
                master[y] = m.node_yarn[m.image_master[g]]
                shift[y] = m.image_shift[g]
    key = {}  # (master, lattice shift) -> yarn
    for y in range(n_yarns):
        key[(int(master[y]), tuple(np.round(shift[y], 9)))] = y
    physical = np.arange(n_yarns)
    arc_offset = np.zeros(n_yarns, dtype=np.int64)
    for y in np.flatnonzero(is_image):
        m = master[y]
        if periodised[m]:
            P = period[m]
            k = float(shift[y] @ P / (P @ P))
            if abs(k - round(k)) < 1e-9 and np.allclose(shift[y], round(k) * P, atol=1e-9 * np.linalg.norm(P)):
                physical[y] = m
                arc_offset[y] = int(round(k)) * yarn_edges[m]
    for y in range(1, n_yarns):
        if parent[y] == parent[y - 1] and not is_image[y]:  # the next piece of a cut yarn
            physical[y] = physical[y - 1]
            arc_offset[y] = arc_offset[y - 1] + yarn_edges[y - 1] + 1
    e = np.arange(edge_yarn.shape[0])
    out_yarn = physical[edge_yarn].astype(np.int64)
    edge_arc = (edge_local + arc_offset[edge_yarn]).astype(np.int64)
    wraps = yarn_closed & ~periodised
    prev = np.where(edge_local > 0, e - 1, -1).astype(np.int64)
    nxt = np.where(edge_local < yarn_edges[edge_yarn] - 1, e + 1, -1).astype(np.int64)
    for y in range(n_yarns):
        m = master[y]
        if wraps[m]:
            prev[first_edge[y]] = last_edge[y]
            nxt[last_edge[y]] = first_edge[y]
        elif periodised[m]:
            before = key.get((int(m), tuple(np.round(shift[y] - period[m], 9))))
            after = key.get((int(m), tuple(np.round(shift[y] + period[m], 9))))
            prev[first_edge[y]] = last_edge[before] if before is not None else -1
            nxt[last_edge[y]] = first_edge[after] if after is not None else -1
    return out_yarn, edge_arc, yarn_edges, wraps, prev, nxt, is_image[edge_yarn]


def make_contacts(rods: Rods, model: ContactModel | None, capacity: int | None = None,
                  previous: Contacts | None = None) -> Contacts:
    """Contact buffers for ``rods``; empty (capacity 0) when ``model`` is None.

    With ``previous`` (a buffer that overflowed), its valid pairs, slips and
    parameters are copied so the friction history and a changed mu survive the
    growth; the new buffer is rebuilt at the next step.
    """
    m = rods.model
    ne = m.edge_a.shape[0]
    edge_yarn, edge_local, yarn_edges, yarn_closed, edge_prev, edge_next, edge_image = contact_topology(m)
    yarn_radius = 0.5 * (m.radius[m.edge_a] + m.radius[m.edge_b])
    edge_radius = yarn_radius  # what the contact sees; the skin and the exclusion keep the yarn's
    if model is not None and model.sagitta_radius is not None:
        edge_radius = sagitta_corrected_radius(yarn_radius, m.rest_length, model.sagitta_radius / units.LENGTH)
    if model is None:
        cap = 0
        params = ContactParams(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        exclusion = np.zeros(m.n_yarns, dtype=np.int64)
    else:
        cap = capacity if capacity is not None else max(16, model.capacity_per_edge * ne)
        d_min = 2.0 * float(yarn_radius.min())
        skin = model.skin / units.LENGTH if model.skin is not None else DEFAULT_SKIN_DIAMETERS * d_min
        params = ContactParams(
            k_n=model.stiffness * units.LENGTH / units.FORCE,
            damping_n=float(model.damping_ratio),
            k_t=model.stiffness * model.tangential_stiffness_ratio * units.LENGTH / units.FORCE,
            damping_t=float(model.tangential_damping_ratio),
            mu=float(model.mu),
            skin=float(skin),
            lookahead_steps=float(LIST_LOOKAHEAD_STEPS),
        )
        # exclusion: edges within `exclusion_diameters` d of arc, and always the adjacent edge
        # (per state yarn: an image is a copy of its master, whose id it carries as its physical yarn)
        own_yarn = m.edge_yarn
        seg = np.bincount(own_yarn, weights=m.rest_length, minlength=m.n_yarns) / np.maximum(yarn_edges, 1)
        d_yarn = 2.0 * np.bincount(own_yarn, weights=yarn_radius, minlength=m.n_yarns) / np.maximum(yarn_edges, 1)
        exclusion = np.maximum(1, np.ceil(model.exclusion_diameters * d_yarn / seg)).astype(np.int64)
    contacts = Contacts(
        pairs=np.zeros((cap, 2), dtype=np.int64),
        keys=np.zeros(cap, dtype=np.int64),
        slip=np.zeros((cap, HISTORY_COLUMNS)),
        n_pairs=np.zeros(1, dtype=np.int64),
        status=np.array([1, 0, 0, 0], dtype=np.int64),  # STALE, PAIRS_NEEDED, GAPS_KNOWN, REBUILDS
        x_ref=rods.state.x.copy(),
        edge_radius=edge_radius,
        edge_prev=edge_prev,
        edge_next=edge_next,
        union=model is None or model.counting == Counting.UNION,
        edge_yarn=edge_yarn,
        edge_local=edge_local,
        yarn_edges=yarn_edges,
        yarn_closed=yarn_closed,
        exclusion=exclusion,
        edge_image=edge_image,
        params=params,
        stats=np.zeros(N_STATS),
        threads=np.array([numba.get_num_threads()], dtype=np.int64),
        pair_results=np.zeros((cap, PAIR_RESULTS)),
        gap_ref=np.zeros(cap),
        edge_moved=np.zeros(ne),
        **pair_law_table(m, model, params),
        edge_allowance=np.full(ne, 0.5 * params.skin),
        list_scratch=list_scratch(ne, cap),
        **share_buffers(m, cap),
    )
    if previous is not None:
        m = int(previous.n_pairs[0])
        contacts.pairs[:m] = previous.pairs[:m]
        contacts.keys[:m] = previous.keys[:m]
        contacts.slip[:m] = previous.slip[:m]
        contacts.n_pairs[0] = m
        contacts.stats[PEAK_OVERLAP] = previous.stats[PEAK_OVERLAP]
        contacts = contacts._replace(params=previous.params)
    return contacts


def carry_friction_history(old: Contacts, new: Contacts, edge_map: np.ndarray) -> bool:
    """Give ``new`` (the buffers of a changed model) the candidate pairs and tangential springs of ``old``:
    old edge k is new edge ``edge_map[k]``, -1 where it is gone (its pairs go with it). The list is
    rebuilt at the next evaluation, which keeps the springs of the pairs still candidates. False, with
    nothing changed, when ``new`` is too small to hold them."""
    n = int(old.n_pairs[0])
    pairs = edge_map[old.pairs[:n]]
    kept = np.all(pairs >= 0, axis=1)
    pairs = np.sort(pairs[kept], axis=1)
    keys = pairs[:, 0] * new.edge_moved.shape[0] + pairs[:, 1]
    order = np.argsort(keys, kind="stable")
    m = order.size
    if m > new.pairs.shape[0]:
        return False
    new.pairs[:m], new.keys[:m], new.slip[:m] = pairs[order], keys[order], old.slip[:n][kept][order]
    new.n_pairs[0] = m
    new.status[STALE], new.status[GAPS_KNOWN] = 1, 0
    return True


def share_buffers(m: RodModel, cap: int) -> dict:
    """The buffers of the contact sum yarn by yarn (:func:`knitlad.engine.kernels.contact.contact_sums_by_rod`)
    for a list of ``cap`` pairs: two shares per pair, buckets for each block of pairs (at most one per thread)
    and yarn."""
    blocks = numba.config.NUMBA_NUM_THREADS
    return dict(
        edge_rod=m.edge_yarn.astype(np.int64),
        share_layout=np.zeros(1, dtype=np.int64),
        bucket_start=np.zeros((blocks, m.n_yarns), dtype=np.int64),
        bucket_fill=np.zeros((blocks, m.n_yarns), dtype=np.int64),
        shares=np.empty((2 * cap, SHARE_COLUMNS)),
        share_edge=np.empty(2 * cap, dtype=np.int64),
        rod_stats=np.zeros((m.n_yarns, N_STATS)),
    )


def pair_law_table(m: RodModel, model: ContactModel | None, params: ContactParams) -> dict:
    """``edge_class`` and ``pair_law`` of :class:`Contacts`: class 0 has the model's k_n and k_t
    (``params``), class c > 0 the edges of the c-th material named in ``model.pair_stiffness``; every pair
    has the model's law and reference overlap (:mod:`knitlad.engine.kernels.contact_law`). With
    ``model.yarn_friction`` each material's edges split further by their yarn's friction factor, a pair's
    FRICTION_FACTOR the larger of its two (else 1)."""
    edge_class = np.zeros(m.edge_a.shape[0], dtype=np.int64)
    materials = []
    for entry in () if model is None else model.pair_stiffness:
        materials += [mat for mat in entry[:2] if mat not in materials]
    table = np.empty((len(materials) + 1, len(materials) + 1, LAW_COLUMNS))
    table[:, :, K_NORMAL], table[:, :, K_TANGENT] = params.k_n, params.k_t
    table[:, :, LAW] = law_mode("linear" if model is None else model.law)
    reference = None if model is None else model.reference_overlap
    table[:, :, REFERENCE_OVERLAP] = reference / units.LENGTH if reference is not None else 0.0
    radius = 0.5 * (m.radius[m.edge_a] + m.radius[m.edge_b])
    for c, mat in enumerate(materials, start=1):
        same = (np.isclose(radius, 0.5 * mat.diameter / units.LENGTH, rtol=1e-9, atol=0.0)
                & np.isclose(m.EA, mat.stretching_stiffness / units.FORCE, rtol=1e-9, atol=0.0))
        if not same.any():
            # else its contacts would silently keep the default stiffness
            raise ValueError(f"pair_stiffness: no yarn of material {mat!r} in the rods (a material is found by its "
                             "diameter and EA, and an EA softened by with_axial_stiffness hides it)")
        edge_class[same] = c
    for mat_a, mat_b, k in () if model is None else model.pair_stiffness:
        a, b = materials.index(mat_a) + 1, materials.index(mat_b) + 1
        k_n = k * units.LENGTH / units.FORCE
        for row in (table[a, b], table[b, a]):
            row[K_NORMAL], row[K_TANGENT] = k_n, k * model.tangential_stiffness_ratio * units.LENGTH / units.FORCE
    table[:, :, FRICTION_FACTOR] = 1.0
    if model is None or not model.yarn_friction:
        return dict(edge_class=edge_class, pair_law=table)
    return with_yarn_friction(m, model.yarn_friction, edge_class, table)


def with_yarn_friction(m: RodModel, yarn_friction: tuple, edge_class: np.ndarray, table: np.ndarray) -> dict:
    """The classes of :func:`pair_law_table` split by the friction factor of each edge's yarn (as built:
    ``yarn_parent``), and their law table: a pair keeps its materials' row, with the larger factor."""
    built_yarn = m.yarn_parent[m.edge_yarn]
    factor = np.ones(edge_class.shape[0])
    for yarn, f in yarn_friction:
        its = built_yarn == yarn
        if not its.any():
            raise ValueError(f"yarn_friction: no yarn {yarn} in the rods (yarns as built: 0 to {built_yarn.max()})")
        factor[its] = f
    classes, edge_new = np.unique(np.column_stack([edge_class, factor]), axis=0, return_inverse=True)
    material = classes[:, 0].astype(np.int64)
    split = table[material[:, None], material[None, :]].copy()
    split[:, :, FRICTION_FACTOR] = np.maximum(classes[:, 1][:, None], classes[:, 1][None, :])
    return dict(edge_class=edge_new.reshape(-1).astype(np.int64), pair_law=split)


class ContactStats(NamedTuple):
    """What the contact kernel saw at its last evaluation (SI)."""

    touching: int  # counted touching pairs
    max_overlap_m: float
    normal_force_sum_N: float
    sliding: int  # pairs sliding (friction at the Coulomb limit)
    candidates: int  # pairs in the candidate list

    def __getitem__(self, key):
        """``stats["touching"]``: the dict of 0.1.0, deprecated in 0.2.0 (use ``stats.touching``)."""
        if isinstance(key, str):
            warnings.warn("contact_stats()[name] is deprecated since knitlad 0.2.0: use contact_stats().name",
                          DeprecationWarning, stacklevel=2)
            return getattr(self, key)
        return tuple.__getitem__(self, key)

    @staticmethod
    def of(contacts: Contacts) -> "ContactStats":
        st = contacts.stats
        return ContactStats(int(st[TOUCHING]), float(st[MAX_OVERLAP] * units.LENGTH),
                            float(st[NORMAL_FORCE_SUM] * units.FORCE), int(st[SLIDING_PAIRS]), int(contacts.n_pairs[0]))


class ContactPairs(NamedTuple):
    """The touching pairs at the last force evaluation, one row each (SI). Forces act on the first
    edge of the pair; the second feels their opposite."""

    edges: np.ndarray  # (m, 2) edge indices
    yarns: np.ndarray  # (m, 2) the edges' yarns (a cut yarn's pieces count as one)
    points_m: np.ndarray  # (m, 3) contact point: midway between the two axes' closest points
    normal_N: np.ndarray  # (m, 3) normal force on the first edge (penalty and its dashpot)
    friction_N: np.ndarray  # (m, 3) tangential force on the first edge
    overlap_m: np.ndarray  # (m,) d minus the axes' distance (sagitta-corrected radii)
    sliding: np.ndarray  # (m,) bool: friction at the Coulomb limit

    @staticmethod
    def of(contacts: Contacts, x: np.ndarray, edge_a: np.ndarray, edge_b: np.ndarray,
           edge_shift: np.ndarray) -> "ContactPairs":
        """From the kernel's per-pair scratch (:func:`knitlad.engine.kernels.contact.contact_forces`), internal units in."""
        from knitlad.engine.kernels.contact import FORCE_X, FORCE_Z, OVERLAP, S_PAIR, SLIDING, T_PAIR

        n = int(contacts.n_pairs[0])
        results, pairs = contacts.pair_results[:n], contacts.pairs[:n]
        touching = results[:, OVERLAP] > 0.0  # separated pairs keep stale scratch: only touching rows count
        results, pairs = results[touching], pairs[touching]
        i, j = pairs[:, 0], pairs[:, 1]

        def on_axis(edge, frac):
            a = x[edge_a[edge]]
            return a + frac[:, None] * (x[edge_b[edge]] + edge_shift[edge] - a)

        pi, pj = on_axis(i, results[:, S_PAIR]), on_axis(j, results[:, T_PAIR])
        gap = pi - pj
        dist = np.linalg.norm(gap, axis=1)
        n_hat = np.divide(gap, dist[:, None], out=np.zeros_like(gap), where=dist[:, None] > 0)
        force = results[:, FORCE_X:FORCE_Z + 1]
        normal = np.where(dist[:, None] > 0, np.sum(force * n_hat, axis=1)[:, None] * n_hat, force)
        return ContactPairs(
            edges=pairs.copy(), yarns=contacts.edge_yarn[pairs], points_m=0.5 * (pi + pj) * units.LENGTH,
            normal_N=normal * units.FORCE, friction_N=(force - normal) * units.FORCE,
            overlap_m=results[:, OVERLAP] * units.LENGTH, sliding=results[:, SLIDING] > 0,
        )


def contact_time_step(m: RodModel, model: ContactModel | None, spin: bool = False, predicted: bool = False) -> float:
    """Critical time step [ms] of the contact springs: 2/omega with omega^2 = 2 z (k_n' + k_t) / m_min, k_n' the
    law's largest slope up to the overlaps it allows (:data:`knitlad.engine.kernels.contact_law.LAWS`).

    ``spin``: the yarns carry twist, so the tangential spring also turns each edge about
    its axis: omega^2 gains 2 z k_t max(r^2 / I) over edges free to twist (for a solid
    cylinder r^2 / I = 2 / m_edge: k_t then counts about three times). ``predicted``: the dashpots act
    on predicted velocities (:func:`knitlad.engine.timestep.damped_limit_factor`).
    """
    if model is None:
        return math.inf
    k_n = max([model.stiffness] + [entry[2] for entry in model.pair_stiffness]) * units.LENGTH / units.FORCE
    k_t = k_n * model.tangential_stiffness_ratio
    k_n *= largest_slope_factor(model.law)
    # counting every pair, a contact at a node shared by two edges of each yarn is four pairs,
    # each with its full lever weight on that node: four times the stiffness union counting puts there
    z = model.contacts_per_node * (4 if model.counting == Counting.ALL_PAIRS else 1)
    free = ~m.held
    omega2 = 2.0 * z * (k_n + k_t) / float(m.mass[free].min()) if np.any(free) else 0.0
    if spin:
        turning = ~m.theta_held
        if np.any(turning):
            r = 0.5 * (m.radius[m.edge_a] + m.radius[m.edge_b])
            omega2 += 2.0 * z * k_t * float(np.max(r[turning] ** 2 / m.twist_inertia[turning]))
    if omega2 == 0.0:
        return math.inf
    zeta = max(model.damping_ratio, model.tangential_damping_ratio)
    return 2.0 / math.sqrt(omega2) * damped_limit_factor(zeta, predicted)
