"""Yarn-yarn contact: capsules, O(N) broad phase, penalty normal force, Coulomb friction.

Every edge is a capsule (a cylinder of its yarn's radius with spherical caps).

* Narrow phase: closest points P(s), Q(t) of two segments, s, t in [0, 1]
  (Ericson, *Real-Time Collision Detection*, sec. 5.1.9); for near-parallel
  segments the midpoint of their overlap, so the contact point moves
  continuously when two yarns lie side by side.
* Broad phase: edge midpoints binned in a grid of cells of size >= the longest
  interaction reach; candidate pairs closer than r_a + r_b + skin go to a
  fixed-capacity buffer. A count past the capacity is reported so the caller
  can grow the buffer and rebuild. The list stays valid until some edge has moved
  by its allowance: skin / 2, or for an edge that moves faster than that in a few
  dozen steps (a cut yarn's flying end), the reach of its speed, its pairs listed
  to the sum of the two allowances (:func:`refresh_contacts`).
* Normal force (overlap delta = r_a + r_b - |P - Q|): f_n = f(delta) + gamma_n d(delta)/dt,
  never pulling; f the contact's law (:mod:`knitlad.engine.kernels.contact_law`: k_n delta, or
  Hertz's). Tangential force (Cundall & Strack 1979): a spring stretched by the tangential slip
  u_t accumulated per persistent pair, plus a dashpot, capped by Coulomb |f_t| <= mu f_n; when
  capped, u_t is reset to the slipping value. u_t is reset when the pair separates and carried
  across rebuilds.
* A yarn is the *union* of its capsules, so a contact at a node shared by two
  edges of a yarn is counted once (:func:`counted_overlaps`): without this, a yarn
  sliding over a chain of capsules feels a bump at every node (two pairs share
  the load there), and the normal dashpot turns the bumps into a drag. The rule
  is not conservative (a count that jumps where two distance minima merge). With
  ``Contacts.union`` False every touching pair counts: a sum of pair potentials,
  which is (``counting="all_pairs"``).
* Forces go to the two nodes of each segment by the lever rule ((1 - s), s),
  which keeps the force and its moment about the contact point.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from knitlad.engine.kernels.contact_law import (
    FRICTION_FACTOR,
    K_NORMAL,
    K_TANGENT,
    LAW,
    REFERENCE_OVERLAP,
    normal_spring,
    normal_spring_energy,
)
from knitlad.engine.kernels.dissipation import CONTACT_DASHPOT, FRICTION, OWNER_CHANGES
from knitlad.engine.kernels.options import INLINE_OPTS, NUMBA_OPTS, PARALLEL_OPTS
from knitlad.engine.kernels.vec import cross, dot


PARALLEL_EPS = 1e-10


class ContactParams(NamedTuple):
    """Contact parameters in internal units (:class:`knitlad.engine.contact.ContactModel` in SI)."""

    k_n: float  # normal stiffness [mN/mm]
    damping_n: float  # normal dashpot, fraction of critical per contact [-]
    k_t: float  # tangential (Cundall-Strack) stiffness [mN/mm]
    damping_t: float  # tangential dashpot, fraction of critical [-]
    mu: float  # Coulomb coefficient [-]
    skin: float  # neighbour-list margin [mm]
    lookahead_steps: float = 0.0  # a fast edge's allowance lasts it this many steps (0: half the skin for all)
    max_allowance: float = 3.0  # the largest allowance of a fast edge, in skins (at least half a skin)


class ListScratch(NamedTuple):
    """Work arrays of a contact-list rebuild (:func:`refresh_contacts`, :func:`build_candidate_pairs`), kept from
    one rebuild to the next: fresh ones cost the kernel a page fault per 4 KiB each time, over a third of a
    rebuild of a large knit (docs/performance.md). Made by :func:`list_scratch`."""

    old_pairs: np.ndarray  # (cap, 2) the list before the rebuild (its slip is carried over)
    old_keys: np.ndarray  # (cap,)
    old_slip: np.ndarray  # (cap, the history's columns)
    mid: np.ndarray  # (ne, 3) edge midpoints
    reach: np.ndarray  # (ne,) bounding-sphere radius of each capsule plus half the skin
    cells: np.ndarray  # (ne, 3) int64 grid cell of each midpoint
    linear: np.ndarray  # (ne,) int64 its number, x fastest
    order: np.ndarray  # (ne,) int64 the edges sorted by cell
    cell_start: np.ndarray  # (max_cells + 1,) int64 first entry of each cell in ``order``
    cell_fill: np.ndarray  # (max_cells,) int64


@njit(**NUMBA_OPTS)
def list_scratch(n_edges, capacity):
    """The work arrays of a rebuild of a list of ``capacity`` pairs over ``n_edges`` edges (:class:`ListScratch`)."""
    max_cells = MAX_CELLS_PER_EDGE * n_edges + 64
    return ListScratch(
        np.empty((capacity, 2), dtype=np.int64), np.empty(capacity, dtype=np.int64),
        np.empty((capacity, HISTORY_COLUMNS)),
        np.empty((n_edges, 3)), np.empty(n_edges), np.empty((n_edges, 3), dtype=np.int64),
        np.empty(n_edges, dtype=np.int64), np.empty(n_edges, dtype=np.int64),
        np.empty(max_cells + 1, dtype=np.int64), np.empty(max_cells, dtype=np.int64),
    )


# slots of Contacts.stats, written by contact_forces at every evaluation
TOUCHING, MAX_OVERLAP, NORMAL_FORCE_SUM, SLIDING_PAIRS, PEAK_OVERLAP = range(5)
N_STATS = 5  # PEAK_OVERLAP is the deepest overlap since the caller last zeroed it
# slots of Contacts.status: STALE = 1 when the candidate list must be rebuilt at the next
# evaluation (set at start and on overflow); PAIRS_NEEDED = the pairs the last overflowing build found
STALE, PAIRS_NEEDED, GAPS_KNOWN, REBUILDS = range(4)
N_STATUS = 4  # GAPS_KNOWN = 1 once the narrow phase after a rebuild has stored each pair's gap (Contacts.gap_ref);
# REBUILDS counts the list's rebuilds since the buffers were made

# modes of counted_overlaps: every pair; every pair, storing its gap; pairs the stored gaps cannot rule out
ALL_PAIRS_PLAIN, ALL_PAIRS_RECORD_GAPS, SKIP_BY_GAPS = range(3)
# a pair is skipped only when its gap exceeds its edges' displacements by more than this [mm], far above round-off
GAP_MARGIN = 1e-9
# columns of the per-pair results of :func:`pair_contact_forces`
FORCE_X, FORCE_Y, FORCE_Z, S_PAIR, T_PAIR, OVERLAP, NORMAL, SLIDING, TORQUE_I, TORQUE_J, CEDED = range(11)
PAIR_RESULTS = 11

# columns of a pair's history (Contacts.slip): the tangential spring u_t in 0..2, then the union rule's last
# verdict on the pair, COUNTED (+1), CEDED_TO_NEIGHBOUR (-1: touching, but the contact is a neighbouring edge's)
# or 0 (apart, or new), and its overlap then (counted or ceded)
VERDICT, DEPTH = 3, 4
HISTORY_COLUMNS = 5
COUNTED, CEDED_TO_NEIGHBOUR = 1.0, -1.0
# columns of a touching pair's share on one of its edges (Contacts.shares: one 64-byte row): the pair's force on
# its first edge, that edge's lever parameter (s, or t on the second edge), its friction couple, and for the
# statistics the normal force, the overlap and 1 if sliding
SHARE_X, SHARE_Y, SHARE_Z, SHARE_LEVER, SHARE_TORQUE, SHARE_NORMAL, SHARE_OVERLAP, SHARE_SLIDING = range(8)
SHARE_COLUMNS = 8


@njit(**INLINE_OPTS)
def _clamp01(v):
    return 0.0 if v < 0.0 else (1.0 if v > 1.0 else v)


@njit(**INLINE_OPTS)
def segment_closest_points(p0x, p0y, p0z, d1x, d1y, d1z, q0x, q0y, q0z, d2x, d2y, d2z):
    """Parameters (s, t) of the closest points of P(s) = p0 + s d1 and Q(t) = q0 + t d2."""
    rx, ry, rz = p0x - q0x, p0y - q0y, p0z - q0z
    a = dot(d1x, d1y, d1z, d1x, d1y, d1z)
    e = dot(d2x, d2y, d2z, d2x, d2y, d2z)
    f = dot(d2x, d2y, d2z, rx, ry, rz)
    c = dot(d1x, d1y, d1z, rx, ry, rz)
    b = dot(d1x, d1y, d1z, d2x, d2y, d2z)
    denom = a * e - b * b
    if denom > PARALLEL_EPS * a * e:
        s = _clamp01((b * f - c * e) / denom)
    else:
        # (near) parallel: centre of the overlap of Q's projection on P
        s0 = -c / a
        s1 = (b - c) / a
        lo = min(s0, s1)
        hi = max(s0, s1)
        lo = max(lo, 0.0)
        hi = min(hi, 1.0)
        s = 0.5 * (lo + hi) if lo <= hi else (0.0 if max(s0, s1) < 0.0 else 1.0)
    t = _clamp01((b * s + f) / e)
    s = _clamp01((b * t - c) / a)
    return s, t


@njit(**INLINE_OPTS)
def _segment(x, edge_a, edge_b, edge_shift, k):
    a = edge_a[k]
    b = edge_b[k]
    return (
        x[a, 0], x[a, 1], x[a, 2],
        x[b, 0] + edge_shift[k, 0] - x[a, 0],
        x[b, 1] + edge_shift[k, 1] - x[a, 1],
        x[b, 2] + edge_shift[k, 2] - x[a, 2],
    )


@njit(**INLINE_OPTS)
def segment_distance(x, edge_a, edge_b, edge_shift, i, j):
    """Distance between the axes of edges i and j, and the closest-point parameters."""
    p0x, p0y, p0z, d1x, d1y, d1z = _segment(x, edge_a, edge_b, edge_shift, i)
    q0x, q0y, q0z, d2x, d2y, d2z = _segment(x, edge_a, edge_b, edge_shift, j)
    s, t = segment_closest_points(p0x, p0y, p0z, d1x, d1y, d1z, q0x, q0y, q0z, d2x, d2y, d2z)
    dx = p0x + s * d1x - q0x - t * d2x
    dy = p0y + s * d1y - q0y - t * d2y
    dz = p0z + s * d1z - q0z - t * d2z
    return math.sqrt(dx * dx + dy * dy + dz * dz), s, t


@njit(**NUMBA_OPTS)
def counted_overlaps(x, edge_a, edge_b, edge_shift, edge_radius, edge_prev, edge_next, union, pairs, lo, hi, out,
                     mode, gap_ref, edge_moved):
    """Narrow phase of the pairs p in [lo, hi): overlap, s, t into ``out[p, OVERLAP]``, ``out[p, S_PAIR]``,
    ``out[p, T_PAIR]``. The overlap is 0 when apart or, with ``union`` counting, when the contact
    belongs to a neighbouring edge (else every touching pair counts: ``all_pairs``); the overlap such a pair
    cedes goes to ``out[p, CEDED]`` (0 for the others).

    The union rule: at an interior node the capsules of edges i and i' (its neighbour) overlap.
    A closest point clamped at the start node (s = 0) belongs to the predecessor; one clamped at
    the end node (s = 1) belongs to i unless the successor reaches the same place from its
    interior (then its own closest point is not the node).

    The rule is written out in this loop, not in a helper: as a helper over the arrays (compiled
    or inlined) it made the narrow phase 4 to 7 x slower on a 42 x 42 knit (docs/history.md).

    ``mode`` ALL_PAIRS_RECORD_GAPS also stores each pair's gap (axis distance less the two radii)
    in ``gap_ref``; SKIP_BY_GAPS writes an overlap of 0 without a distance test for a pair whose
    stored gap exceeds the largest displacements of its two edges since (``edge_moved``): every
    point of a segment moves by at most its ends' largest displacement, so the axes' distance
    shrinks by at most the sum and the pair is still apart. The forces are the same to the bit;
    the parameters s, t of a skipped pair are left as they were (nothing reads them when apart).
    """
    for p in range(lo, hi):
        i = pairs[p, 0]
        j = pairs[p, 1]
        out[p, CEDED] = 0.0
        if mode == SKIP_BY_GAPS and gap_ref[p] > edge_moved[i] + edge_moved[j] + GAP_MARGIN:
            out[p, OVERLAP] = 0.0
            continue
        dist, s, t = segment_distance(x, edge_a, edge_b, edge_shift, i, j)
        overlap = edge_radius[i] + edge_radius[j] - dist
        if mode == ALL_PAIRS_RECORD_GAPS:  # the gap at the rebuild's positions, at least (a bound if moved since)
            gap_ref[p] = -overlap - edge_moved[i] - edge_moved[j]
        if union and overlap > 0.0:
            if s <= 0.0:
                owned = edge_prev[i] < 0
            elif s >= 1.0 and edge_next[i] >= 0:
                _, s_next, _ = segment_distance(x, edge_a, edge_b, edge_shift, edge_next[i], j)
                owned = s_next <= 0.0
            else:
                owned = True
            if owned:
                if t <= 0.0:
                    owned = edge_prev[j] < 0
                elif t >= 1.0 and edge_next[j] >= 0:
                    _, t_next, _ = segment_distance(x, edge_a, edge_b, edge_shift, edge_next[j], i)
                    owned = t_next <= 0.0
            if not owned:
                out[p, CEDED] = overlap
                overlap = 0.0
        out[p, OVERLAP] = max(overlap, 0.0)
        out[p, S_PAIR] = s
        out[p, T_PAIR] = t


# above this fraction of fast edges every edge gets half the skin (refresh_contacts)
MAX_FAST_FRACTION = 0.25
@njit(**INLINE_OPTS)
def excluded_along_yarn(i, j, edge_yarn, edge_local, yarn_edges, yarn_closed, exclusion):
    """Edges i and j never pair: the same yarn and at most ``exclusion`` edges apart along it (cyclically if
    closed). For the fast edges' pass; the main search writes it out (there a call costs 8 %)."""
    y = edge_yarn[i]
    if y != edge_yarn[j]:
        return False
    gap = abs(edge_local[i] - edge_local[j])
    if yarn_closed[y]:
        gap = min(gap, yarn_edges[y] - gap)
    return gap <= exclusion[y]


# a grid of more cells than this per edge is coarsened (a yarn flung far away must not
# make the grid huge); cells larger than the reach only cost more distance tests
MAX_CELLS_PER_EDGE = 8


@njit(**PARALLEL_OPTS)
def edge_midpoints(x, edge_a, edge_b, edge_shift, edge_radius, skin, n_blocks, mid, reach, block_lo, block_hi):
    """Each edge's midpoint and reach (bounding-sphere radius of its capsule plus half the skin) into ``mid``,
    ``reach``; the box of the finite midpoints of each of ``n_blocks`` blocks of edges into ``block_lo``,
    ``block_hi`` (a non-finite edge stays out of the box). Blocks in parallel."""
    ne = edge_a.shape[0]
    for blk in prange(n_blocks):
        for d in range(3):
            block_lo[blk, d] = np.inf
            block_hi[blk, d] = -np.inf
        for k in range(blk * ne // n_blocks, (blk + 1) * ne // n_blocks):
            a = edge_a[k]
            b = edge_b[k]
            half2 = 0.0
            for d in range(3):
                xb = x[b, d] + edge_shift[k, d]
                mid[k, d] = 0.5 * (x[a, d] + xb)
                half2 += 0.25 * (xb - x[a, d]) ** 2
                if math.isfinite(mid[k, d]):
                    block_lo[blk, d] = min(block_lo[blk, d], mid[k, d])
                    block_hi[blk, d] = max(block_hi[blk, d], mid[k, d])
            reach[k] = math.sqrt(half2) + edge_radius[k] + 0.5 * skin


@njit(**PARALLEL_OPTS)
def cells_of_edges(mid, lo, inv_cell, dims, cells, linear):
    """The grid cell of each edge's midpoint (``cells``, clamped into the grid: a non-finite midpoint lands
    somewhere and fails every distance test) and its number, x fastest (``linear``)."""
    for k in prange(mid.shape[0]):
        for d in range(3):
            c = (mid[k, d] - lo[d]) * inv_cell
            # clamped as a float first: the int of an infinity, or of a number past int64, is undefined
            cells[k, d] = int(min(max(c, 0.0), dims[d] - 1.0)) if c == c else 0
        linear[k] = (cells[k, 2] * dims[1] + cells[k, 1]) * dims[0] + cells[k, 0]


@njit(**PARALLEL_OPTS)
def concatenate_blocks(local, found, pairs, keys, ne):
    """The candidates of each block (``local[blk, :found[blk]]``) one after the other into ``pairs``, with
    their keys i * ne + j: blocks in parallel, each at its offset, so the order is the serial one."""
    n_blocks = found.shape[0]
    offset = np.zeros(n_blocks + 1, dtype=np.int64)
    for blk in range(n_blocks):
        offset[blk + 1] = offset[blk] + found[blk]
    for blk in prange(n_blocks):
        for q in range(found[blk]):
            pairs[offset[blk] + q, 0] = local[blk, q, 0]
            pairs[offset[blk] + q, 1] = local[blk, q, 1]
            keys[offset[blk] + q] = local[blk, q, 0] * ne + local[blk, q, 1]


@njit(**NUMBA_OPTS)
def build_candidate_pairs(
    x, edge_a, edge_b, edge_shift, edge_radius, edge_yarn, edge_local, yarn_edges, yarn_closed, exclusion,
    edge_image, cell_size, skin, pairs, keys, n_threads=1, allowance=None, n_fast=0, scratch=None,
):
    """Fill ``pairs`` (cap, 2) with candidate edge pairs (i < j), sorted; return how many were found:
    the pairs whose gap is below the skin, and with ``allowance`` (each edge's, >= skin/2) and ``n_fast``
    edges whose allowance exceeds skin/2, also each pair of a fast edge whose gap is below the sum of the
    two allowances (:func:`fast_edge_pairs`).

    Edge midpoints are binned in a dense grid of cells of at least ``cell_size``
    over their bounding box, numbered x fastest, so the three cells along x of a
    neighbourhood are one contiguous run of the binned edges: nine runs per edge.
    A return value above ``pairs.shape[0]`` means the buffer overflowed (the
    buffer's content is then undefined): grow it and call again. The midpoints, the
    cells, the search and the concatenation run on ``n_threads`` blocks of edges;
    the counting sort into cells is serial (it keeps each cell's edges in index order).
    ``scratch``: a :class:`ListScratch` for ``ne`` edges to work in (else fresh arrays).
    """
    ne = edge_a.shape[0]
    cap = pairs.shape[0]
    n_blocks = max(1, min(n_threads, ne))
    if scratch is None:
        scratch = list_scratch(ne, np.int64(0))
    mid = scratch.mid
    reach = scratch.reach
    block_lo = np.empty((n_blocks, 3))
    block_hi = np.empty((n_blocks, 3))
    edge_midpoints(x, edge_a, edge_b, edge_shift, edge_radius, skin, n_blocks, mid, reach, block_lo, block_hi)
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for blk in range(n_blocks):
        for d in range(3):
            lo[d] = min(lo[d], block_lo[blk, d])
            hi[d] = max(hi[d], block_hi[blk, d])
    extent = np.maximum(hi - lo, 0.0)  # 0 along an axis with no finite midpoint (hi - lo = -inf)
    cell = cell_size
    # counted as a float: a far-flung yarn must not overflow the count
    while np.prod(np.floor(extent / cell) + 1.0) > MAX_CELLS_PER_EDGE * ne + 64:
        cell *= 1.5
    dims = (extent / cell).astype(np.int64) + 1
    n_cells = dims[0] * dims[1] * dims[2]
    cells = scratch.cells
    linear = scratch.linear
    cells_of_edges(mid, lo, 1.0 / cell, dims, cells, linear)
    start = scratch.cell_start
    start[:n_cells + 1] = 0
    for k in range(ne):
        start[linear[k] + 1] += 1
    for h in range(n_cells):
        start[h + 1] += start[h]
    fill = scratch.cell_fill
    fill[:n_cells] = start[:n_cells]
    order = scratch.order
    for k in range(ne):
        order[fill[linear[k]]] = k
        fill[linear[k]] += 1
    # candidates of each block of edges, found in parallel, then concatenated in order
    block_cap = cap  # blocks can be very unequal (e.g. all partners j > i on the first yarns)
    local = np.empty((n_blocks, block_cap, 2), dtype=np.int64)
    found = np.zeros(n_blocks, dtype=np.int64)
    _search_blocks(x, edge_a, edge_b, edge_shift, edge_radius, edge_yarn, edge_local, yarn_edges, yarn_closed,
                   exclusion, edge_image, skin, cells, dims, mid, reach, start, order, local, found)
    n = np.int64(0)
    for blk in range(n_blocks):
        n += found[blk]
    if n > cap or np.any(found > block_cap):
        return max(n, cap + 1)
    # blocks run in edge order and each edge's partners are sorted: keys end up sorted
    concatenate_blocks(local, found, pairs, keys, ne)
    if n_fast > 0 and allowance is not None:
        fast = np.flatnonzero(allowance > 0.5 * skin)
        extra = fast_edge_pairs(x, edge_a, edge_b, edge_shift, edge_radius, edge_yarn, edge_local, yarn_edges,
                                yarn_closed, exclusion, edge_image, skin, allowance, fast, cell, cells, dims, mid,
                                reach, start, order)
        if n + extra.shape[0] > cap:
            return n + extra.shape[0]
        merge_sorted_pairs(pairs, keys, n, extra, ne)
        n += extra.shape[0]
    return n


@njit(**INLINE_OPTS)
def _beyond_skin_within_allowances(dist, r_i, r_j, skin, allowance_i, allowance_j):
    """A pair for :func:`fast_edge_pairs`: its axes' distance is at least the radii and the skin (the main
    search's test, complemented as written there) and below the radii and the two allowances."""
    return not dist < r_i + r_j + skin and dist < r_i + r_j + allowance_i + allowance_j


@njit(**NUMBA_OPTS)
def _appended_key(found, n, key):
    """``found[:n]`` with ``key`` after it, and the new count; ``found`` doubled when full. Compiled, not inlined:
    inlined, its branch on an array would put reference counting into the caller's loops (docs/performance.md)."""
    if n == found.shape[0]:
        found = np.concatenate((found, np.empty(max(n, 1), dtype=np.int64)))
    found[n] = key
    return found, n + 1


@njit(**NUMBA_OPTS)
def fast_edge_pairs(x, edge_a, edge_b, edge_shift, edge_radius, edge_yarn, edge_local, yarn_edges, yarn_closed,
                    exclusion, edge_image, skin, allowance, fast, cell, cells, dims, mid, reach, start, order):
    """Sorted keys i * ne + j (i < j) of the pairs of the ``fast`` edges whose gap is at least the skin (the
    main search has the others) and below the sum of their edges' allowances, each found once. A fast edge
    searches the cells its own reach and a slow partner's (at most half a cell: ``cell`` >= the longest edge
    + 2 radii + the skin) span; two fast edges meet in a sweep along x over the fast edges sorted by their
    midpoints' x. Same exclusions as :func:`_candidates_of_block`.

    The tests are written out in both loops: as one helper taking the arrays (compiled or inlined), the
    fast edges' pairs took 25 x longer (docs/performance.md)."""
    ne = edge_a.shape[0]
    half_skin = 0.5 * skin
    nf = fast.shape[0]
    found = np.empty(64 * nf, dtype=np.int64)
    n = np.int64(0)
    for q in range(nf):  # a fast edge and its slow partners
        f = fast[q]
        # as a float first, at most the grid (an infinite reach, a flying end gone to infinity, must not wrap)
        reach_cells = (reach[f] - half_skin + allowance[f] + 0.5 * cell) / cell
        span = int(min(reach_cells, float(dims[0] + dims[1] + dims[2]))) + 1 if reach_cells == reach_cells \
            else dims[0] + dims[1] + dims[2]
        x0 = max(cells[f, 0] - span, 0)
        x1 = min(cells[f, 0] + span, dims[0] - 1)
        for cz in range(max(cells[f, 2] - span, 0), min(cells[f, 2] + span, dims[2] - 1) + 1):
            for cy in range(max(cells[f, 1] - span, 0), min(cells[f, 1] + span, dims[1] - 1) + 1):
                row = (cz * dims[1] + cy) * dims[0]
                for idx in range(start[row + x0], start[row + x1 + 1]):
                    j = order[idx]
                    if allowance[j] > half_skin or (edge_image[f] and edge_image[j]):  # fast partners: below
                        continue
                    r = reach[f] + reach[j] - skin + allowance[f] + allowance[j]
                    if (mid[f, 0] - mid[j, 0]) ** 2 + (mid[f, 1] - mid[j, 1]) ** 2 + (mid[f, 2] - mid[j, 2]) ** 2 > r * r:
                        continue
                    if excluded_along_yarn(f, j, edge_yarn, edge_local, yarn_edges, yarn_closed, exclusion):
                        continue
                    dist, _, _ = segment_distance(x, edge_a, edge_b, edge_shift, f, j)
                    if _beyond_skin_within_allowances(dist, edge_radius[f], edge_radius[j], skin, allowance[f],
                                                      allowance[j]):
                        found, n = _appended_key(found, n, min(f, j) * ne + max(f, j))
    # two fast edges: a sweep along x, each pair once
    by_x = fast[np.argsort(mid[fast, 0])]
    widest = 0.0
    for f in fast:
        widest = max(widest, reach[f] - half_skin + allowance[f])
    for q in range(nf):
        f = by_x[q]
        reach_f = reach[f] - half_skin + allowance[f]
        for qq in range(q + 1, nf):
            g = by_x[qq]
            if mid[g, 0] - mid[f, 0] > reach_f + widest:
                break
            if edge_image[f] and edge_image[g]:
                continue
            r = reach_f + reach[g] - half_skin + allowance[g]
            if (mid[f, 0] - mid[g, 0]) ** 2 + (mid[f, 1] - mid[g, 1]) ** 2 + (mid[f, 2] - mid[g, 2]) ** 2 > r * r:
                continue
            if excluded_along_yarn(f, g, edge_yarn, edge_local, yarn_edges, yarn_closed, exclusion):
                continue
            dist, _, _ = segment_distance(x, edge_a, edge_b, edge_shift, f, g)
            if _beyond_skin_within_allowances(dist, edge_radius[f], edge_radius[g], skin, allowance[f], allowance[g]):
                found, n = _appended_key(found, n, min(f, g) * ne + max(f, g))
    return np.sort(found[:n])


@njit(**NUMBA_OPTS)
def merge_sorted_pairs(pairs, keys, n, extra, ne):
    """Merge the sorted keys ``extra`` (none in ``keys[:n]``) into the sorted list ``pairs[:n]``, ``keys[:n]``, in
    place from the back (the buffers hold n + len(extra))."""
    i = n - 1
    w = n + extra.shape[0] - 1
    for q in range(extra.shape[0] - 1, -1, -1):
        while i >= 0 and keys[i] > extra[q]:
            keys[w] = keys[i]
            pairs[w, 0] = pairs[i, 0]
            pairs[w, 1] = pairs[i, 1]
            i -= 1
            w -= 1
        keys[w] = extra[q]
        pairs[w, 0] = extra[q] // ne
        pairs[w, 1] = extra[q] % ne
        w -= 1


@njit(**PARALLEL_OPTS)
def _search_blocks(x, edge_a, edge_b, edge_shift, edge_radius, edge_yarn, edge_local, yarn_edges, yarn_closed,
                   exclusion, edge_image, skin, cells, dims, mid, reach, start, order, local, found):
    ne = edge_a.shape[0]
    n_blocks = found.shape[0]
    for blk in prange(n_blocks):
        found[blk] = _candidates_of_block(
            blk * ne // n_blocks, (blk + 1) * ne // n_blocks, x, edge_a, edge_b, edge_shift, edge_radius,
            edge_yarn, edge_local, yarn_edges, yarn_closed, exclusion, edge_image, skin, cells, dims, mid, reach,
            start, order, local[blk],
        )


@njit(**NUMBA_OPTS)
def _candidates_of_block(
    lo, hi, x, edge_a, edge_b, edge_shift, edge_radius, edge_yarn, edge_local, yarn_edges, yarn_closed,
    exclusion, edge_image, skin, cells, dims, mid, reach, start, order, out,
):
    """Candidate pairs (i, j > i) for edges i in [lo, hi) into ``out``; partners of each i sorted.

    Two edges of periodic images never pair: the image of that pair is already a
    pair of a real edge with an image.

    Returns how many were found (may exceed ``out``'s size: then only the count is valid).
    """
    cap = out.shape[0]
    n = 0
    for i in range(lo, hi):
        first = n
        x0 = max(cells[i, 0] - 1, 0)
        x1 = min(cells[i, 0] + 1, dims[0] - 1)
        for cz in range(max(cells[i, 2] - 1, 0), min(cells[i, 2] + 1, dims[2] - 1) + 1):
            for cy in range(max(cells[i, 1] - 1, 0), min(cells[i, 1] + 1, dims[1] - 1) + 1):
                row = (cz * dims[1] + cy) * dims[0]
                for idx in range(start[row + x0], start[row + x1 + 1]):
                    j = order[idx]
                    if j <= i:
                        continue
                    if edge_image[i] and edge_image[j]:
                        continue
                    # bounding spheres first: most neighbours in the 27 cells are far
                    r = reach[i] + reach[j]
                    dm = (mid[i, 0] - mid[j, 0]) ** 2 + (mid[i, 1] - mid[j, 1]) ** 2 + (mid[i, 2] - mid[j, 2]) ** 2
                    if dm > r * r:
                        continue
                    # excluded: same yarn and at most `exclusion` edges apart along it (cyclically if
                    # closed); written out here: as a call, even inlined (excluded_along_yarn), the search
                    # is slower (docs/performance.md)
                    y = edge_yarn[i]
                    if y == edge_yarn[j]:
                        gap = abs(edge_local[i] - edge_local[j])
                        if yarn_closed[y]:
                            gap = min(gap, yarn_edges[y] - gap)
                        if gap <= exclusion[y]:
                            continue
                    dist, _, _ = segment_distance(x, edge_a, edge_b, edge_shift, i, j)
                    if dist < edge_radius[i] + edge_radius[j] + skin:
                        if n < cap:
                            out[n, 0] = i
                            out[n, 1] = j
                        n += 1
        # insertion sort of this edge's partners (a handful)
        if n <= cap:
            for a in range(first + 1, n):
                v = out[a, 1]
                b = a - 1
                while b >= first and out[b, 1] > v:
                    out[b + 1, 1] = out[b, 1]
                    b -= 1
                out[b + 1, 1] = v
    return n


@njit(**PARALLEL_OPTS)
def carry_history(old_keys, old_slip, n_old, new_keys, new_slip, n_new, n_blocks=1):
    """Copy the history (tangential slip, union verdict) of pairs present in both sorted lists; zero the new
    ones. The new list in ``n_blocks`` blocks in parallel, each merging from the first old key not below its own
    first key."""
    for blk in prange(n_blocks):
        q0 = blk * n_new // n_blocks
        q1 = (blk + 1) * n_new // n_blocks
        p = 0
        if q0 < q1:
            p = np.searchsorted(old_keys[:n_old], new_keys[q0])
        for q in range(q0, q1):
            while p < n_old and old_keys[p] < new_keys[q]:
                p += 1
            found = p < n_old and old_keys[p] == new_keys[q]
            for k in range(new_slip.shape[1]):
                new_slip[q, k] = old_slip[p, k] if found else 0.0


@njit(**PARALLEL_OPTS)
def copy_rows(src, dst, n):
    """``dst[:n] = src[:n]`` for (m, k) arrays, rows in parallel."""
    for p in prange(n):
        for d in range(src.shape[1]):
            dst[p, d] = src[p, d]


@njit(**PARALLEL_OPTS)
def copy_entries(src, dst, n):
    """``dst[:n] = src[:n]`` for (m,) arrays, in parallel."""
    for p in prange(n):
        dst[p] = src[p]


@njit(**PARALLEL_OPTS)
def longest_edge(x, edge_a, edge_b, edge_shift):
    """The longest edge now (the grid's cells must hold a whole capsule)."""
    longest = 0.0
    for k in prange(edge_a.shape[0]):
        a = edge_a[k]
        b = edge_b[k]
        l2 = 0.0
        for d in range(3):
            l2 += (x[b, d] + edge_shift[k, d] - x[a, d]) ** 2
        longest = max(longest, math.sqrt(l2))
    return longest


# below this many candidate pairs per thread, starting the threads costs more than they save
MIN_PAIRS_PER_THREAD = 1000


@njit(**INLINE_OPTS)
def coulomb_spring(ux, uy, uz, nx, ny, nz, vtx, vty, vtz, sx, sy, sz, dt, k_t, gamma_t, limit):
    """The tangential force of a touching contact (Cundall & Strack 1979; module docstring), shared by the
    yarn-yarn pairs and the obstacles: the slip u (kept in the tangent plane of normal n with its length)
    grows by the slip velocity s over dt; f_t = -k_t u - gamma_t v_t (v_t: the dashpot's tangential
    velocity), capped at ``limit`` = mu f_n, when u is set to the slipping value.
    Returns (f_t, the new u, sliding)."""
    u_len = math.sqrt(ux * ux + uy * uy + uz * uz)
    un = dot(ux, uy, uz, nx, ny, nz)
    ux -= un * nx
    uy -= un * ny
    uz -= un * nz
    u_new = math.sqrt(ux * ux + uy * uy + uz * uz)
    if u_new > 0.0:
        ux *= u_len / u_new
        uy *= u_len / u_new
        uz *= u_len / u_new
    ux += sx * dt
    uy += sy * dt
    uz += sz * dt
    ftx = -k_t * ux - gamma_t * vtx
    fty = -k_t * uy - gamma_t * vty
    ftz = -k_t * uz - gamma_t * vtz
    ft = math.sqrt(ftx * ftx + fty * fty + ftz * ftz)
    sliding = False
    if ft > limit:
        # sliding: Coulomb force along the trial direction, spring set to match it
        scale = limit / ft if ft > 0.0 else 0.0
        ftx *= scale
        fty *= scale
        ftz *= scale
        if k_t > 0.0:
            ux = -(ftx + gamma_t * vtx) / k_t
            uy = -(fty + gamma_t * vty) / k_t
            uz = -(ftz + gamma_t * vtz) / k_t
        sliding = True
    return ftx, fty, ftz, ux, uy, uz, sliding


@njit(**NUMBA_OPTS)
def pair_contact_forces(
    lo, hi, x, v, omega, v_damp, omega_damp, predicted, spin, mass, edge_a, edge_b, edge_shift, edge_radius,
    edge_prev, edge_next, union, pairs, slip, edge_class, pair_law, damping_n, damping_t, mu, dt, out, mode, gap_ref,
    edge_moved, blk, edge_rod, bucket_fill, shares, share_edge, ledger,
):
    """Contact force of each candidate pair p in [lo, hi) on its first edge, into ``out[p]``
    (the narrow phase in ``mode``, :func:`counted_overlaps`).

    The buffers and parameters of :class:`knitlad.engine.contact.Contacts`, passed one by one:
    Numba's parallel regions (:func:`_pair_contact_forces_in_blocks`) take no named tuple.

    ``out[p]``: the force (FORCE_X..Z), the closest-point parameters (S_PAIR, T_PAIR),
    the overlap (OVERLAP, 0 when apart or owned by a neighbouring edge), the normal
    force and 1 if sliding. Advances the slip history of each pair. Pairs are
    independent here, so blocks of pairs can run on different threads.

    ``spin``: the yarns carry twist (spin rate ``omega`` per edge). The contact point
    then sits on the two surfaces, C = P - r_i n = Q + r_j n, and each surface moves with
    its yarn's spin: v_C,i = v_P + omega_i t_i x (-r_i n). The friction force, applied
    there, twists each edge about its axis (TORQUE_I, TORQUE_J): the friction couple.
    Its moment about the other two axes (lever r << edge length) is dropped.

    ``predicted``: the dashpots act on ``v_damp``, ``omega_damp`` (the velocities predicted at the end
    of the step, :func:`knitlad.engine.kernels.integrate.predict_velocities`), the slip on the half-step
    ``v``, ``omega``; else both on ``v``, ``omega``.

    Each touching pair's two shares (one per edge: the force, s or t, the friction couple) are appended to the
    bucket of this block ``blk`` and that edge's rod (``bucket_fill[blk, rod]``, the next free slot of
    ``shares`` and ``share_edge``), for :func:`contact_sums_by_rod`.

    ``pair_law``: the law table (c, c, LAW_COLUMNS) of :mod:`knitlad.engine.kernels.contact_law`, the row of
    each pair's two edge classes: its k_n, k_t, normal law f(delta) with energy U(delta), and the factor on
    ``mu`` of its friction.

    The energy the contacts take out over the step goes to ``ledger[blk]``: at CONTACT_DASHPOT the normal
    force's excess over the spring's, (f_n - f(delta)) d(delta)/dt dt (the dashpot, and a spring cut off when the
    force would pull); at FRICTION the tangential force's work on the slip less the change of its spring's
    energy, -f_t.s dt - k_t (|u'|^2 - |u|^2)/2 (sliding at the Coulomb limit and the tangential dashpot), and
    the spring's energy k_t |u|^2/2 when a pair separates (its history is reset); at OWNER_CHANGES the energy
    the union rule puts in when a touching pair's contact passes to a neighbouring edge or back (the counted
    energy jumps by U(delta) there, with no force doing work): +U(delta) for a pair that takes a contact,
    -U(delta) for one that cedes it, U the mean of its values at the step's two ends.
    """
    counted_overlaps(x, edge_a, edge_b, edge_shift, edge_radius, edge_prev, edge_next, union, pairs, lo, hi, out,
                     mode, gap_ref, edge_moved)
    friction = 0.0
    dashpot = 0.0
    switched = 0.0
    for p in range(lo, hi):
        i = pairs[p, 0]
        j = pairs[p, 1]
        overlap = out[p, OVERLAP]
        ceded = out[p, CEDED]
        verdict = COUNTED if overlap > 0.0 else (CEDED_TO_NEIGHBOUR if ceded > 0.0 else 0.0)
        depth = overlap if verdict == COUNTED else ceded
        ci = edge_class[i]
        cj = edge_class[j]
        if verdict != 0.0 and slip[p, VERDICT] == -verdict:  # the contact changed owner: its energy jumps
            # by U(delta) somewhere in the step: booked at the mean of its two ends (the step's work is a
            # trapezoid of the forces at its two ends, so this leaves an error of second order in the step)
            law = pair_law[ci, cj, LAW]
            k_n = pair_law[ci, cj, K_NORMAL]
            reference = pair_law[ci, cj, REFERENCE_OVERLAP]
            switched += verdict * 0.5 * (normal_spring_energy(law, k_n, reference, depth)
                                         + normal_spring_energy(law, k_n, reference, slip[p, DEPTH]))
        slip[p, VERDICT] = verdict
        slip[p, DEPTH] = depth
        if overlap <= 0.0:
            stored = slip[p, 0] * slip[p, 0] + slip[p, 1] * slip[p, 1] + slip[p, 2] * slip[p, 2]
            if stored > 0.0:
                friction += 0.5 * pair_law[ci, cj, K_TANGENT] * stored
            slip[p, 0] = 0.0
            slip[p, 1] = 0.0
            slip[p, 2] = 0.0
            continue
        s = out[p, S_PAIR]
        t = out[p, T_PAIR]
        dist = edge_radius[i] + edge_radius[j] - overlap
        a0 = edge_a[i]
        a1 = edge_b[i]
        b0 = edge_a[j]
        b1 = edge_b[j]
        p0x, p0y, p0z, d1x, d1y, d1z = _segment(x, edge_a, edge_b, edge_shift, i)
        q0x, q0y, q0z, d2x, d2y, d2z = _segment(x, edge_a, edge_b, edge_shift, j)
        nx = p0x + s * d1x - q0x - t * d2x
        ny = p0y + s * d1y - q0y - t * d2y
        nz = p0z + s * d1z - q0z - t * d2z
        if dist > 1e-12 * (edge_radius[i] + edge_radius[j]):
            nx /= dist
            ny /= dist
            nz /= dist
        else:
            # axes intersect: push apart along the common normal of the two segments
            nx, ny, nz = cross(d1x, d1y, d1z, d2x, d2y, d2z)
            nn = math.sqrt(nx * nx + ny * ny + nz * nz) + 1e-300
            nx /= nn
            ny /= nn
            nz /= nn
        # relative velocity of the contact points (material points of the two axes)
        vrx = (1 - s) * v[a0, 0] + s * v[a1, 0] - (1 - t) * v[b0, 0] - t * v[b1, 0]
        vry = (1 - s) * v[a0, 1] + s * v[a1, 1] - (1 - t) * v[b0, 1] - t * v[b1, 1]
        vrz = (1 - s) * v[a0, 2] + s * v[a1, 2] - (1 - t) * v[b0, 2] - t * v[b1, 2]
        if predicted:
            dvx = (1 - s) * v_damp[a0, 0] + s * v_damp[a1, 0] - (1 - t) * v_damp[b0, 0] - t * v_damp[b1, 0]
            dvy = (1 - s) * v_damp[a0, 1] + s * v_damp[a1, 1] - (1 - t) * v_damp[b0, 1] - t * v_damp[b1, 1]
            dvz = (1 - s) * v_damp[a0, 2] + s * v_damp[a1, 2] - (1 - t) * v_damp[b0, 2] - t * v_damp[b1, 2]
        li = 1.0
        lj = 1.0
        if spin:
            # surfaces at the contact point: - r_i omega_i (t_i x n) on i, + r_j omega_j (t_j x n) on j
            li = math.sqrt(d1x * d1x + d1y * d1y + d1z * d1z)
            lj = math.sqrt(d2x * d2x + d2y * d2y + d2z * d2z)
            wi = edge_radius[i] * omega[i] / li
            wj = edge_radius[j] * omega[j] / lj
            cix, ciy, ciz = cross(d1x, d1y, d1z, nx, ny, nz)
            cjx, cjy, cjz = cross(d2x, d2y, d2z, nx, ny, nz)
            vrx -= wi * cix + wj * cjx
            vry -= wi * ciy + wj * cjy
            vrz -= wi * ciz + wj * cjz
            if predicted:
                wi = edge_radius[i] * omega_damp[i] / li
                wj = edge_radius[j] * omega_damp[j] / lj
                dvx -= wi * cix + wj * cjx
                dvy -= wi * ciy + wj * cjy
                dvz -= wi * ciz + wj * cjz
        if not predicted:
            dvx, dvy, dvz = vrx, vry, vrz
        vn = dot(dvx, dvy, dvz, nx, ny, nz)  # > 0: separating
        m_a = (1 - s) * mass[a0] + s * mass[a1]
        m_b = (1 - t) * mass[b0] + t * mass[b1]
        m_eff = m_a * m_b / (m_a + m_b)
        k_n = pair_law[ci, cj, K_NORMAL]
        k_t = pair_law[ci, cj, K_TANGENT]
        spring = normal_spring(pair_law[ci, cj, LAW], k_n, pair_law[ci, cj, REFERENCE_OVERLAP], overlap)
        fn = spring - 2.0 * damping_n * math.sqrt(k_n * m_eff) * vn
        if fn < 0.0:
            fn = 0.0
        vtx = dvx - vn * nx  # of the dashpot
        vty = dvy - vn * ny
        vtz = dvz - vn * nz
        if predicted:  # the slip grows with the half-step velocity (midpoint rule)
            vn_slip = dot(vrx, vry, vrz, nx, ny, nz)
            sx, sy, sz = vrx - vn_slip * nx, vry - vn_slip * ny, vrz - vn_slip * nz
        else:
            sx, sy, sz = vtx, vty, vtz
        gamma_t = 2.0 * damping_t * math.sqrt(k_t * m_eff)
        limit = mu * pair_law[ci, cj, FRICTION_FACTOR] * fn
        ftx, fty, ftz, ux, uy, uz, slides = coulomb_spring(slip[p, 0], slip[p, 1], slip[p, 2], nx, ny, nz, vtx, vty,
                                                           vtz, sx, sy, sz, dt, k_t, gamma_t, limit)
        sliding = 1.0 if slides else 0.0
        dashpot -= (fn - spring) * vn * dt
        friction -= (ftx * sx + fty * sy + ftz * sz) * dt + 0.5 * k_t * (
            ux * ux + uy * uy + uz * uz - slip[p, 0] * slip[p, 0] - slip[p, 1] * slip[p, 1] - slip[p, 2] * slip[p, 2])
        slip[p, 0] = ux
        slip[p, 1] = uy
        slip[p, 2] = uz
        out[p, FORCE_X] = fn * nx + ftx
        out[p, FORCE_Y] = fn * ny + fty
        out[p, FORCE_Z] = fn * nz + ftz
        out[p, NORMAL] = fn
        out[p, SLIDING] = sliding
        if spin:
            # torque about each axis of the friction force at the surface: t . (-r n x f_t) on i,
            # t . (r n x (-f_t)) on j: the same expression for both
            mx, my, mz = cross(nx, ny, nz, ftx, fty, ftz)
            out[p, TORQUE_I] = -edge_radius[i] * dot(d1x, d1y, d1z, mx, my, mz) / li
            out[p, TORQUE_J] = -edge_radius[j] * dot(d2x, d2y, d2z, mx, my, mz) / lj
        for side in range(2):
            k = i if side == 0 else j
            r = edge_rod[k]
            q = bucket_fill[blk, r]
            bucket_fill[blk, r] = q + 1
            share_edge[q] = 2 * k + side
            shares[q, SHARE_X] = out[p, FORCE_X]
            shares[q, SHARE_Y] = out[p, FORCE_Y]
            shares[q, SHARE_Z] = out[p, FORCE_Z]
            shares[q, SHARE_LEVER] = s if side == 0 else t
            shares[q, SHARE_TORQUE] = (out[p, TORQUE_I] if side == 0 else out[p, TORQUE_J]) if spin else 0.0
            shares[q, SHARE_NORMAL] = fn
            shares[q, SHARE_OVERLAP] = overlap
            shares[q, SHARE_SLIDING] = sliding
    ledger[blk, FRICTION] += friction
    ledger[blk, CONTACT_DASHPOT] += dashpot
    ledger[blk, OWNER_CHANGES] += switched


@njit(**PARALLEL_OPTS)
def _pair_contact_forces_in_blocks(
    n_blocks, n_pairs, x, v, omega, v_damp, omega_damp, predicted, spin, mass, edge_a, edge_b, edge_shift, edge_radius,
    edge_prev, edge_next, union, pairs, slip, edge_class, pair_law, damping_n, damping_t, mu, dt, out, mode, gap_ref,
    edge_moved, edge_rod, bucket_fill, shares, share_edge, ledger,
):
    for blk in prange(n_blocks):
        block = np.int64(blk)  # prange's index is unsigned: as int64 the serial call's specialisation serves it
        pair_contact_forces(
            block * n_pairs // n_blocks, (block + 1) * n_pairs // n_blocks, x, v, omega, v_damp, omega_damp,
            predicted, spin, mass, edge_a, edge_b, edge_shift, edge_radius, edge_prev, edge_next, union, pairs, slip,
            edge_class, pair_law, damping_n, damping_t, mu, dt, out, mode, gap_ref, edge_moved, block, edge_rod,
            bucket_fill, shares, share_edge, ledger,
        )


@njit(**PARALLEL_OPTS)
def edge_displacements(x, x_ref, edge_a, edge_b, allowance, out):
    """Largest displacement of each edge's two ends since ``x_ref`` (the last rebuild) into ``out``; returns
    the largest excess of an edge's displacement over its ``allowance`` (the list is stale when it is > 0).
    With a zero allowance that is the largest |x - x_ref| over the nodes where every node ends an edge (sqrt
    is monotonic and correctly rounded: the same bits), so one pass serves the rebuild's test and the narrow
    phase's skipping."""
    excess = -np.inf
    for k in prange(edge_a.shape[0]):
        a = edge_a[k]
        b = edge_b[k]
        da = (x[a, 0] - x_ref[a, 0]) ** 2 + (x[a, 1] - x_ref[a, 1]) ** 2 + (x[a, 2] - x_ref[a, 2]) ** 2
        db = (x[b, 0] - x_ref[b, 0]) ** 2 + (x[b, 1] - x_ref[b, 1]) ** 2 + (x[b, 2] - x_ref[b, 2]) ** 2
        out[k] = math.sqrt(max(da, db))
        excess = max(excess, out[k] - allowance[k])
    return excess


@njit(**PARALLEL_OPTS)
def edge_allowances(v, edge_a, edge_b, half_skin, lookahead, cap, out):
    """Each edge's allowance, the displacement its pairs in the list are good for: half the skin, or for an edge
    moving faster than half the skin per ``lookahead`` (a time), 1.5 x its fastest end's speed x ``lookahead``,
    at most ``cap``. Returns how many edges have more than half the skin."""
    n_fast = 0
    for k in prange(edge_a.shape[0]):
        a = edge_a[k]
        b = edge_b[k]
        speed2 = max(v[a, 0] ** 2 + v[a, 1] ** 2 + v[a, 2] ** 2, v[b, 0] ** 2 + v[b, 1] ** 2 + v[b, 2] ** 2)
        reach = 1.5 * math.sqrt(speed2) * lookahead
        if reach > half_skin:  # false for NaN
            out[k] = min(reach, cap)
            n_fast += 1
        else:
            out[k] = half_skin
    return n_fast


@njit(**NUMBA_OPTS)
def share_buckets(pairs, n_pairs, edge_rod, n_blocks, bucket_start):
    """The slots of the touching pairs' shares in ``Contacts.shares`` for a list evaluated in ``n_blocks`` equal
    blocks of pairs: ``bucket_start[b, r]`` is the first slot of what block b gives rod r (a yarn of the state;
    one share per edge of rod r among the block's pairs at most). A rod's buckets follow each other in block
    order, so a rod reads its shares in pair order."""
    n_rods = bucket_start.shape[1]
    count = np.zeros((n_blocks, n_rods), dtype=np.int64)
    for b in range(n_blocks):
        for p in range(b * n_pairs // n_blocks, (b + 1) * n_pairs // n_blocks):
            count[b, edge_rod[pairs[p, 0]]] += 1
            count[b, edge_rod[pairs[p, 1]]] += 1
    q = 0
    for r in range(n_rods):
        for b in range(n_blocks):
            bucket_start[b, r] = q
            q += count[b, r]


@njit(**NUMBA_OPTS)
def rod_contact_sum(r, n_blocks, bucket_start, bucket_fill, shares, share_edge, edge_a, edge_b, spin, F, torque,
                    rod_stats):
    """Add rod r's shares to its nodes by the lever rule, (1 - s) f and s f on a pair's first edge, -(1 - t) f
    and -t f on its second (with ``spin`` the friction couple to the edge's torque), block after block: in pair
    order, as a serial sum over the pairs adds them. ``rod_stats[r]`` (slots TOUCHING, MAX_OVERLAP,
    NORMAL_FORCE_SUM, SLIDING_PAIRS): those of the touching pairs whose first edge is rod r's."""
    n_touch = 0
    max_overlap = 0.0
    fn_sum = 0.0
    n_slide = 0
    for b in range(n_blocks):
        for q in range(bucket_start[b, r], bucket_fill[b, r]):
            k = share_edge[q] >> 1
            # +1 on a pair's first edge, -1 on its second; the products in one block, with no branch: a
            # branch for each side made the compiler hoist (1 - w) f out of it and drop the fused multiply-adds
            # that the serial sum gets, which changed the last bits
            sign = 1.0 - 2.0 * (share_edge[q] & 1)
            lever_a = sign * (1 - shares[q, SHARE_LEVER])
            lever_b = sign * shares[q, SHARE_LEVER]
            fx = shares[q, SHARE_X]
            fy = shares[q, SHARE_Y]
            fz = shares[q, SHARE_Z]
            n0 = edge_a[k]
            n1 = edge_b[k]
            F[n0, 0] += lever_a * fx
            F[n0, 1] += lever_a * fy
            F[n0, 2] += lever_a * fz
            F[n1, 0] += lever_b * fx
            F[n1, 1] += lever_b * fy
            F[n1, 2] += lever_b * fz
            if share_edge[q] & 1 == 0:
                n_touch += 1
                fn_sum += shares[q, SHARE_NORMAL]
                n_slide += int(shares[q, SHARE_SLIDING])
                max_overlap = max(max_overlap, shares[q, SHARE_OVERLAP])
            if spin:
                torque[k] += shares[q, SHARE_TORQUE]
    rod_stats[r, TOUCHING] = n_touch
    rod_stats[r, MAX_OVERLAP] = max_overlap
    rod_stats[r, NORMAL_FORCE_SUM] = fn_sum
    rod_stats[r, SLIDING_PAIRS] = n_slide


@njit(**PARALLEL_OPTS)
def contact_sums_by_rod(n_blocks, bucket_start, bucket_fill, shares, share_edge, edge_a, edge_b, spin, F, torque,
                        rod_stats):
    """The contact forces onto the nodes, rod by rod in parallel (:func:`rod_contact_sum`): a rod's edges move
    only its own nodes."""
    for r in prange(rod_stats.shape[0]):
        rod_contact_sum(np.int64(r), n_blocks, bucket_start, bucket_fill, shares, share_edge, edge_a, edge_b, spin, F, torque,
                        rod_stats)


@njit(**NUMBA_OPTS)
def contact_forces(x, v, omega, spin, mass, edge_a, edge_b, edge_shift, c, dt, F, torque, v_damp, omega_damp,
                   predicted, ledger):
    """Add the contact forces of the candidate pairs of ``c`` (:class:`knitlad.engine.contact.Contacts`) to F
    (and, with ``spin``, the friction couples to ``torque``); advance the slip history. ``predicted``:
    the dashpots act on ``v_damp``, ``omega_damp`` (:func:`pair_contact_forces`). Call
    :func:`refresh_contacts` at these positions first: it fills ``c.edge_moved``, which this reads.

    The damping parameters are damping ratios of the contact springs (gamma =
    2 zeta sqrt(k m_eff)). ``c.stats`` receives, at slots TOUCHING, MAX_OVERLAP,
    NORMAL_FORCE_SUM and SLIDING_PAIRS, the state of this evaluation, and keeps at
    PEAK_OVERLAP the deepest overlap since the caller last zeroed it. The pairs are
    evaluated on up to ``c.threads[0]`` threads into ``c.pair_results``, each touching pair's two shares
    into the buckets of its block and its edges' rods; each rod then adds its shares, block after block, to its
    own nodes (:func:`contact_sums_by_rod`): every node gets its shares in pair order, so the forces are bit
    for bit those of a serial sum over the pairs, on any number of threads. The energy the contacts take out
    goes to ``ledger`` (rows: the blocks; :func:`pair_contact_forces`).
    """
    n_pairs = c.n_pairs[0]
    n_blocks = max(1, min(c.threads[0], n_pairs // MIN_PAIRS_PER_THREAD))
    p = c.params
    if c.status[GAPS_KNOWN] == 0 or c.share_layout[0] != n_blocks:  # a new list, or new blocks
        share_buckets(c.pairs, n_pairs, c.edge_rod, n_blocks, c.bucket_start)
        c.share_layout[0] = n_blocks
    c.bucket_fill[:n_blocks] = c.bucket_start[:n_blocks]
    # most candidate pairs stay apart between two rebuilds: after the first evaluation of a list, a pair
    # its stored gap rules out skips the distance test (counted_overlaps, SKIP_BY_GAPS)
    mode = SKIP_BY_GAPS if c.status[GAPS_KNOWN] == 1 else ALL_PAIRS_RECORD_GAPS
    # c.edge_moved: filled by refresh_contacts for these positions (always called just before)
    if n_blocks > 1:
        _pair_contact_forces_in_blocks(
            n_blocks, n_pairs, x, v, omega, v_damp, omega_damp, predicted, spin, mass, edge_a, edge_b, edge_shift,
            c.edge_radius, c.edge_prev, c.edge_next, c.union, c.pairs, c.slip, c.edge_class, c.pair_law, p.damping_n,
            p.damping_t, p.mu, dt, c.pair_results, mode, c.gap_ref, c.edge_moved, c.edge_rod, c.bucket_fill, c.shares,
            c.share_edge, ledger,
        )
        contact_sums_by_rod(n_blocks, c.bucket_start, c.bucket_fill, c.shares, c.share_edge, edge_a, edge_b, spin, F,
                            torque, c.rod_stats)
    else:
        # int64 zeros and ones, not literals: a literal argument compiles a specialisation of its own (kernels/options.py)
        pair_contact_forces(
            np.int64(0), n_pairs, x, v, omega, v_damp, omega_damp, predicted, spin, mass, edge_a, edge_b, edge_shift,
            c.edge_radius, c.edge_prev, c.edge_next, c.union, c.pairs, c.slip, c.edge_class, c.pair_law, p.damping_n,
            p.damping_t, p.mu, dt, c.pair_results, mode, c.gap_ref, c.edge_moved, np.int64(0), c.edge_rod,
            c.bucket_fill, c.shares, c.share_edge, ledger,
        )
        for r in range(c.rod_stats.shape[0]):
            rod_contact_sum(r, np.int64(1), c.bucket_start, c.bucket_fill, c.shares, c.share_edge, edge_a, edge_b,
                            spin, F, torque, c.rod_stats)
    c.status[GAPS_KNOWN] = 1
    stats = c.stats
    n_touch = 0
    max_overlap = 0.0
    fn_sum = 0.0
    n_slide = 0
    for r in range(c.rod_stats.shape[0]):
        n_touch += int(c.rod_stats[r, TOUCHING])
        max_overlap = max(max_overlap, c.rod_stats[r, MAX_OVERLAP])
        fn_sum += c.rod_stats[r, NORMAL_FORCE_SUM]
        n_slide += int(c.rod_stats[r, SLIDING_PAIRS])
    stats[TOUCHING] = n_touch
    stats[MAX_OVERLAP] = max_overlap
    stats[NORMAL_FORCE_SUM] = fn_sum
    stats[SLIDING_PAIRS] = n_slide
    # the peak over every evaluation since the caller last zeroed it: an interpenetration
    # lasting a few steps between two observations must not go unseen
    if max_overlap > stats[PEAK_OVERLAP]:
        stats[PEAK_OVERLAP] = max_overlap


@njit(**NUMBA_OPTS)
def contact_energy(x, edge_a, edge_b, edge_shift, c, pairs, slip):
    """Stored contact energy: sum of U(delta) + k_t |u_t|^2 / 2 over the counted touching
    ``pairs`` (m, 2) with their ``slip`` (m, 3) (``c.pairs[:n]``, ``c.slip[:n]``, or a subset)."""
    n_pairs = pairs.shape[0]
    narrow = np.empty((n_pairs, PAIR_RESULTS))
    counted_overlaps(x, edge_a, edge_b, edge_shift, c.edge_radius, c.edge_prev, c.edge_next, c.union, pairs, np.int64(0),
                     n_pairs, narrow, np.int64(ALL_PAIRS_PLAIN), c.gap_ref, c.edge_moved)
    total = 0.0
    for p in range(n_pairs):
        overlap = narrow[p, OVERLAP]
        if overlap > 0.0:
            law = c.pair_law[c.edge_class[pairs[p, 0]], c.edge_class[pairs[p, 1]]]
            total += normal_spring_energy(law[LAW], law[K_NORMAL], law[REFERENCE_OVERLAP], overlap)
            total += 0.5 * law[K_TANGENT] * (slip[p, 0] ** 2 + slip[p, 1] ** 2 + slip[p, 2] ** 2)
    return total


@njit(**NUMBA_OPTS)
def refresh_contacts(x, edge_a, edge_b, edge_shift, c, v, lookahead):
    """Rebuild the candidate list of ``c`` (a :class:`knitlad.engine.contact.Contacts`) if stale
    or if an edge moved by more than its allowance since the last build. Returns False on overflow: the
    old list is kept, ``c.status[PAIRS_NEEDED]`` holds the pairs needed, and the caller must grow the buffer.

    A pair is listed when its gap is below the sum of its edges' allowances, so while no edge has moved by
    more than its own, no pair left out can touch (a Verlet list with a skin per edge). The allowance is half
    the skin, except, with velocities ``v`` and a ``lookahead`` time, for the few edges fast enough to cross
    half the skin within it (a cut yarn's flying ends, at 100 m/s and more): those get the reach of their
    speed (:func:`edge_allowances`), so they no longer rebuild the whole list every few steps. Any valid list
    gives the same forces to the bit (pairs apart add nothing, and the touching ones are summed in key order).
    """
    skin = c.params.skin
    excess = edge_displacements(x, c.x_ref, edge_a, edge_b, c.edge_allowance, c.edge_moved)
    if c.status[STALE] == 0 and excess <= 0.0:
        return True
    n_old = c.n_pairs[0]
    old_pairs = c.list_scratch.old_pairs
    old_keys = c.list_scratch.old_keys
    old_slip = c.list_scratch.old_slip
    copy_rows(c.pairs, old_pairs, n_old)
    copy_entries(c.keys, old_keys, n_old)
    copy_rows(c.slip, old_slip, n_old)
    longest = longest_edge(x, edge_a, edge_b, edge_shift)
    r_max = 0.0
    for k in range(c.edge_radius.shape[0]):
        r_max = max(r_max, c.edge_radius[k])
    n_fast = 0
    if v is not None and lookahead > 0.0:
        n_fast = edge_allowances(v, edge_a, edge_b, 0.5 * skin, lookahead, max(c.params.max_allowance, 0.5) * skin,
                                 c.edge_allowance)
    if n_fast > MAX_FAST_FRACTION * edge_a.shape[0] or not (v is not None and lookahead > 0.0):
        # the fast edges' pass is serial: where most edges move fast (a knit translated, a relaxation's
        # velocities), half the skin for all, which is always valid
        c.edge_allowance[:] = 0.5 * skin
        n_fast = 0
    cell = longest + 2.0 * r_max + skin
    n = build_candidate_pairs(
        x, edge_a, edge_b, edge_shift, c.edge_radius, c.edge_yarn, c.edge_local, c.yarn_edges,
        c.yarn_closed, c.exclusion, c.edge_image, cell, skin, c.pairs, c.keys, c.threads[0], c.edge_allowance, n_fast,
        c.list_scratch,
    )
    if n > c.pairs.shape[0]:
        c.pairs[:n_old] = old_pairs[:n_old]
        c.keys[:n_old] = old_keys[:n_old]
        c.slip[:n_old] = old_slip[:n_old]
        c.status[STALE] = 1
        c.status[PAIRS_NEEDED] = n
        return False
    carry_history(old_keys, old_slip, n_old, c.keys, c.slip, n, max(1, c.threads[0]))
    c.n_pairs[0] = n
    copy_rows(x, c.x_ref, x.shape[0])
    c.edge_moved[:] = 0.0  # |x - x_ref| = 0 exactly: what edge_displacements would give
    c.status[STALE] = 0
    c.status[GAPS_KNOWN] = 0
    c.status[REBUILDS] += 1
    return True


@njit(**NUMBA_OPTS)
def touching_pairs_among(x, edge_a, edge_b, edge_shift, c, in_a, in_b):
    """Number of counted touching pairs of ``c`` between an edge of the set ``in_a`` and one of the
    set ``in_b`` (boolean masks over the edges: a part of a yarn and its images, say)."""
    n_pairs = c.n_pairs[0]
    narrow = np.empty((n_pairs, PAIR_RESULTS))
    counted_overlaps(x, edge_a, edge_b, edge_shift, c.edge_radius, c.edge_prev, c.edge_next, c.union, c.pairs,
                     np.int64(0), n_pairs, narrow, np.int64(ALL_PAIRS_PLAIN), c.gap_ref, c.edge_moved)
    n = 0
    for p in range(n_pairs):
        i = c.pairs[p, 0]
        j = c.pairs[p, 1]
        if ((in_a[i] and in_b[j]) or (in_a[j] and in_b[i])) and narrow[p, OVERLAP] > 0.0:
            n += 1
    return n
