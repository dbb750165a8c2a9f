"""A weft-knitted fabric of a pattern (jersey by default): n_x stitches per course, n_y courses.

Centreline of course r (after Crane's "plain-knit-yarn", see shared/notes), one
stitch per 2 pi of the parameter t:

    x = (t + a sin 2t) l_x / (2 pi),  y = r l_y + H cos t,  z = c cos 2t,   a = 3/2

for jersey (stockinette); other patterns multiply z by the face sign of their purl
stitches (:mod:`knitlad.fabric.patterns`).

Heads (needle loops, pointing +y) sit at t = 2 pi i (column i), sinker loops
(pointing -y) at t = 2 pi i + pi. The loop half-height H is solved so that each
stitch holds exactly l0 of yarn; c = 2 d by default keeps crossing yarns about
3 d apart. Each course runs from the sinker left of column 0 to the sinker right
of column n_x - 1: on the box edges x = +-n_x l_x / 2. One extra course below
(r = -1) and above (r = n_y), entirely held, secure the bottom and top edges so
that a ladder reaching them stops there.

How those edge courses, the bars, are held (``KnitGeometry.bars``):

* ``"held"`` (default): every node of a bar is held, as the paper's simulations fix the yarn.
* ``"sliding"``: a bar's two end nodes at each end are held and every other node slides along x on a rail
  through its place, as the experiment's clips slide along the bars of its biaxial machine: the bar holds
  the yarn in y and z, and the edge stitches are free to shift sideways along it.

How the course ends are held (``KnitGeometry.edge``):

* ``"clamped"`` (default): the last two nodes at each end are held, fixing the
  end's position and its tangent (along x). The periodic stitch is mirror
  symmetric about its sinkers, so there the yarn runs along x: the clamp
  imposes that symmetry. It also fixes the sinker's height (as built, then
  carried by the affine stretch), which in the bulk is free.
* ``"tail"``: a straight tail 0.5 l_x long continues each end, and only its
  tip is held. The edge sinker and the tail are then free to bend and to trade
  yarn with the edge stitches, which at mu = 0 they do without end: the knit
  held at a fixed box creeps (42 x 42 at l_x/l0 = 0.355: f_x 0.33 -> 2.04 over
  57 rounds of 750 FIRE steps, then a drop to 0.77; the loop heads of the two
  outermost columns moved 7.5 and 3.3 nodes, the interior ones < 1), where the
  clamped knit settles (f_x 2.36 -> 2.28 over 30 rounds, heads moved <= 1 node).
* ``"continuous"``: the experiment's fabric, one yarn knitted back and forth. Course r runs from left to
  right for even r and back for odd r; the end of course r turns into the start of course r + 1 in a
  half circle of diameter l_y outside the box (:func:`turning_loop`), tangent to both courses' ends (their
  sinkers run along x). The apex of each turning loop sits in a clip that slides along y on a rail: it holds
  the loop in x and z, as the experiment's sliding clips on the side bars of its biaxial machine. The yarn's
  two ends (the start of course 0, the end of course n_y - 1) are clamped. Each clip carries the pull of the
  two courses it joins: each course counts half of it (``KnitScene.left_share``, ``right_share``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from knitlad.engine.deprecation import renamed_fields
from knitlad.engine.state import Rods, Scene
from knitlad.engine.units import NYLON, Material
from knitlad.fabric.patterns import fabric_pattern, knit_pattern


class CourseTooWide(ValueError):
    """No centreline of this family holds l0 per stitch at this l_x: even a flat course is longer."""

CRANE_A = 1.5
EDGES = ("clamped", "tail", "continuous")  # how the course ends are held: see the module docstring
BARS = ("held", "sliding")  # how the edge courses below and above are held: see the module docstring
# widest l_x/l0 at which the knit and the periodised stitch are built: wider, Crane's loops
# of successive courses barely overlap; they are stretched from there
BUILD_LX = 0.30
# a pattern with purl stitches passes its yarn through the mid-plane where the face changes, which
# takes yarn from the loops (H smaller than jersey's): built where its loops reach this far past the
# next course [d] (rib and garter at l_y/l0 0.25: 4.8 and 3.8 d at l_x/l0 0.27 left 2.0 and 1.5 d
# between yarns; at 2.8 and 1.9 d, 0.42 and 0.29 d, and garter's loops no longer interlocked)
PATTERN_LOOP_OVERLAP_D = 5.0
# yarns thicker than the paper's collide in the plane where the paper's is built (d/l0 = 1/50 at l_x/l0
# 0.30, l_y/l0 0.25: loops 1.6 d past the next course, nodes of two yarns 0.35 d apart; 1/35 at 0.24:
# 1.5 d and 0.53 d): they are built where their loops reach this far [d] (1/50: 0.24, 2.2 d apart)
THICK_LOOP_OVERLAP_D = 4.0
PAPER_D_OVER_L0 = NYLON.diameter / NYLON.stitch_length


def build_loop_overlap(material: Material, pattern: str = "jersey", band: str | None = None) -> float:
    """How far [m] the loops of a knit being built must reach past the next course (2 H - l_y), for
    :func:`widest_fitting_width`: jersey of the paper's yarn or finer, no demand (its builds as they
    always were); thicker yarns THICK_LOOP_OVERLAP_D d, other patterns (or bands of them)
    PATTERN_LOOP_OVERLAP_D d."""
    d = material.diameter
    if pattern != "jersey" or band not in (None, "jersey"):
        return PATTERN_LOOP_OVERLAP_D * d
    if d / material.stitch_length <= PAPER_D_OVER_L0 * (1 + 1e-9):
        return -math.inf
    return THICK_LOOP_OVERLAP_D * d


@renamed_fields({"nodes_per_stitch": "resolution"}, since="0.14.0")
@dataclass(frozen=True)
class KnitGeometry:
    """Geometry of a weft knit of ``pattern`` (:data:`knitlad.fabric.patterns.PATTERNS`; SI units)."""

    n_x: int = 42
    n_y: int = 42
    l_x: float = 0.245 * NYLON.stitch_length
    l_y: float = 0.245 * NYLON.stitch_length
    resolution: int = 36
    material: Material = NYLON
    depth: float | None = None  # c, default 2 d
    tail: float = 0.5  # straight tail beyond the last sinker, in l_x (edge "tail" only)
    edge: str = "clamped"  # how the course ends are held: EDGES
    bars: str = "held"  # how the edge courses below and above are held: BARS
    width: float = CRANE_A  # a: how far the head bulges sideways (Crane: 3/2)
    pattern: str = "jersey"  # which stitches are knit and which purl (knitlad.fabric.patterns)
    band: tuple[str, int, int] | None = None  # (pattern, first course, courses) knitted in another pattern

    def __post_init__(self) -> None:
        if self.n_x < 1 or self.n_y < 1:
            raise ValueError(f"the knit needs at least 1 x 1 stitches, got {self.n_x} x {self.n_y}")
        if self.resolution < 8:
            raise ValueError(f"resolution must be >= 8, got {self.resolution}")
        if self.edge not in EDGES:
            raise ValueError(f"edge must be one of {', '.join(EDGES)}, got {self.edge!r}")
        if self.bars not in BARS:
            raise ValueError(f"bars must be one of {', '.join(BARS)}, got {self.bars!r}")
        fabric_pattern(self.pattern, self.band)
        l0 = self.material.stitch_length
        if not 0 < self.l_x < l0 or not 0 < self.l_y < l0:
            raise ValueError("l_x and l_y must lie strictly between 0 and l0")

    @property
    def c(self) -> float:
        return 2.0 * self.material.diameter if self.depth is None else self.depth

    @property
    def segment(self) -> float:
        return self.material.stitch_length / self.resolution

    def column_x(self, i: np.ndarray | int) -> np.ndarray | float:
        """x of the head (column centre) of column i; the knit is centred on x = 0."""
        return (np.asarray(i) - 0.5 * (self.n_x - 1)) * self.l_x

    def curve(self, t: np.ndarray, row: int, H: float) -> np.ndarray:
        x = (t + self.width * np.sin(2 * t)) * self.l_x / (2 * math.pi) + self.column_x(0)
        y = row * self.l_y + H * np.cos(t)
        z = self.c * np.cos(2 * t)
        pattern = fabric_pattern(self.pattern, self.band)
        if not pattern.plain:
            z = z * pattern.face(t, row)
        return np.column_stack([x, y, z])

    def stitch_length_for(self, H: float, samples: int = 4000) -> float:
        """Yarn length per stitch of the smooth curve: one stitch of jersey, the mean over a pattern's repeat
        (a band's courses are knitted at the same loop height: their stitches hold a little more or less)."""
        columns, rows = knit_pattern(self.pattern).period
        t = np.linspace(0.0, 2 * math.pi * columns, samples * columns + 1)
        plain = dataclasses.replace(self, band=None) if self.band else self
        total = sum(np.linalg.norm(np.diff(plain.curve(t, r, H), axis=0), axis=1).sum() for r in range(rows))
        return float(total / (columns * rows))

    def loop_half_height(self, length: float | None = None) -> float:
        """H such that one stitch of the smooth curve holds ``length`` (default l0) of yarn."""
        l0 = self.material.stitch_length if length is None else length
        lo, hi = 0.0, self.material.stitch_length
        if self.stitch_length_for(lo) > l0:
            raise CourseTooWide(
                f"l_x/l0 = {self.l_x / l0:.3f} is too wide for this centreline: a flat course is already longer than l0"
            )
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if self.stitch_length_for(mid) < l0:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    def course_points(self, row: int, H: float) -> tuple[np.ndarray, np.ndarray]:
        """Nodes of one course, uniform in arc length, and the parameter t of each.

        With ``edge="tail"``, straight tails continue from the end sinkers out to the held ends.
        """
        fine_per_stitch = 400
        t = np.linspace(-math.pi, 2 * math.pi * (self.n_x - 1) + math.pi, fine_per_stitch * self.n_x + 1)
        pts = self.curve(t, row, H)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        n_seg = self.resolution * self.n_x
        targets = np.linspace(0.0, s[-1], n_seg + 1)
        knit = np.column_stack([np.interp(targets, s, pts[:, k]) for k in range(3)])
        tk = np.interp(targets, s, t)
        seg = s[-1] / n_seg
        if self.edge != "tail":
            return knit, tk
        n_tail = max(1, int(round(self.tail * self.l_x / seg)))
        left = knit[0] + np.outer(np.arange(n_tail, 0, -1) * seg, [-1.0, 0.0, 0.0])
        right = knit[-1] + np.outer(np.arange(1, n_tail + 1) * seg, [1.0, 0.0, 0.0])
        t_left = np.full(n_tail, -np.inf)
        t_right = np.full(n_tail, np.inf)
        return np.vstack([left, knit, right]), np.concatenate([t_left, tk, t_right])


def turning_loop(a: np.ndarray, b: np.ndarray, segments: int, outward: float) -> np.ndarray:
    """The ``segments - 1`` nodes strictly between ``a`` and ``b`` on the half circle of diameter |b - a| that
    bulges along ``outward`` x (+1: right, -1: left), in the plane of x and b - a; the yarn leaves ``a`` and
    enters ``b`` along x, as it leaves and enters a course's end sinkers.

        p(phi) = m + R (-cos(phi) u + sin(phi) w),  m = (a + b)/2,  R = |b - a|/2,  u = (b - a)/2R,

    w the unit x direction made normal to u, phi = pi j / segments (j = 1 .. segments - 1)."""
    m, R = 0.5 * (a + b), 0.5 * float(np.linalg.norm(b - a))
    u = (b - a) / (2 * R)
    w = np.array([outward, 0.0, 0.0]) - outward * u[0] * u
    w /= np.linalg.norm(w)
    phi = math.pi * np.arange(1, segments) / segments
    return m + R * (np.outer(-np.cos(phi), u) + np.outer(np.sin(phi), w))


def turning_segments(geometry: KnitGeometry) -> int:
    """Segments of a turning loop (``edge="continuous"``): its half circle pi l_y / 2 at the knit's segment
    length, even so that a node sits at the apex (its clip)."""
    return max(2, 2 * int(round(0.25 * math.pi * geometry.l_y / geometry.segment)))


def widest_fitting_width(lx_max: float, ly: float, material: Material, resolution: int,
                         min_loop_overlap: float = -math.inf, lx_min: float = 0.1, pattern: str = "jersey") -> float:
    """The widest l_x/l0 <= lx_max, in steps of 0.01, at which a stitch holds l0 of yarn and its
    loop reaches ``min_loop_overlap`` [m] past the next course (2 H - l_y); thick yarns need
    narrower cells. Raises :class:`CourseTooWide` if none down to ``lx_min`` does."""
    l0 = material.stitch_length
    lx = lx_max
    while lx >= lx_min - 1e-12:
        geometry = KnitGeometry(n_x=1, n_y=1, l_x=lx * l0, l_y=ly * l0, resolution=resolution,
                                material=material, pattern=pattern)
        try:
            if 2 * geometry.loop_half_height() - ly * l0 > min_loop_overlap:
                return lx
        except CourseTooWide:
            pass
        lx = round(lx - 0.01, 6)
    raise CourseTooWide(f"no {pattern} stitch of d/l0 = {material.diameter / l0:.3g} fits at l_y/l0 = {ly}")


@dataclass
class KnitScene:
    """The built knit: its state plus the bookkeeping the protocol and observers need."""

    geometry: KnitGeometry
    rods: Rods
    H: float
    courses: list[int]  # yarn index of each free course, bottom to top
    bars: list[int]  # yarn indices of the held edge courses
    node_t: np.ndarray  # centreline parameter of each node (+-inf on tails)
    left_end: np.ndarray  # (courses, k) node indices of the support at the left end of each free course
    right_end: np.ndarray
    # (courses, 2) [start, stop) nodes of each free course's stitches (None: its whole yarn, as before the
    # continuous edge); the share of each end node's reaction the course carries (None: all of it)
    course_span: np.ndarray | None = None
    left_share: np.ndarray | None = None
    right_share: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.course_span is None:
            start = self.rods.model.yarn_start  # as built: this scene is never cut
            self.course_span = np.array([[start[y], start[y + 1]] for y in self.courses], dtype=np.int64)
        for name, end in (("left_share", self.left_end), ("right_share", self.right_end)):
            if getattr(self, name) is None:
                setattr(self, name, np.ones(end.shape))

    def course_nodes(self, k: int) -> slice:
        """Node slice of free course k (0 = bottom): its stitches, sinker to sinker (and tails). Node indices
        never change (a cut makes two yarns of a course and shifts the yarn indices above it, not the
        nodes). On the continuous edge the odd courses run from right to left."""
        start, stop = self.course_span[k]
        return slice(int(start), int(stop))

    def row_nodes(self) -> list[slice]:
        """Node slices of the free courses, bottom to top, then of the held top course."""
        return [self.course_nodes(k) for k in range(len(self.courses))] + [self.yarn_nodes(self.bars[1])]

    def node_course(self) -> np.ndarray:
        """The course of each node: 0 to n_y - 1 for the free courses, -1 and n_y for the held ones; a
        turning loop's nodes (continuous edge) belong to the course it leaves."""
        out = np.empty(self.rods.model.n_nodes, dtype=np.int64)
        out[self.yarn_nodes(self.bars[0])] = -1
        out[self.yarn_nodes(self.bars[1])] = len(self.courses)
        span = self.course_span
        for k in range(len(self.courses)):
            out[span[k, 0]:span[k + 1, 0] if k + 1 < len(self.courses) else span[k, 1]] = k
        return out

    def place_turning_loops(self, x: np.ndarray) -> None:
        """Lay each turning loop (continuous edge) on its half circle between the courses' ends at positions
        ``x`` [any length unit], in place: after the courses were moved (tiled)."""
        if self.geometry.edge != "continuous":
            return
        span = self.course_span
        for k in range(len(self.courses) - 1):
            a, b = span[k, 1] - 1, span[k + 1, 0]
            x[a + 1:b] = turning_loop(x[a], x[b], b - a, 1.0 if x[a, 0] > 0 else -1.0)

    def yarn_nodes(self, y: int) -> slice:
        start = self.rods.model.yarn_start  # as built: this scene is never cut
        return slice(int(start[y]), int(start[y + 1]))


def discrete_loop_half_height(geometry: KnitGeometry) -> float:
    """H at which the resampled polygon (not the smooth curve) holds l0 per stitch.

    Chords are shorter than the arcs they span, by about (kappa seg)^2 / 24; the
    smooth curve is lengthened to compensate, in two fixed-point passes.
    """
    l0 = geometry.material.stitch_length
    target = l0
    H = geometry.loop_half_height(target)
    for _ in range(3):
        pts, t = geometry.course_points(0, H)
        inside = np.isfinite(t)
        chord = np.linalg.norm(np.diff(pts[inside], axis=0), axis=1).sum() / geometry.n_x
        target *= l0 / chord
        H = geometry.loop_half_height(target)
    return H


def build_knit(geometry: KnitGeometry, stretch_damping_ratio: float = 0.2) -> KnitScene:
    """A knit at (l_x, l_y), every course held at its two ends or all of them one yarn turning in clips
    (``geometry.edge``), edge courses held whole or sliding along x (``geometry.bars``).

    ``stretch_damping_ratio``: each edge's axial dashpot as a fraction of critical (``Scene.build``).
    """
    H = discrete_loop_half_height(geometry)
    scene = Scene(geometry.material)
    courses, bars, ts = [], [], []
    left, right = [], []
    offset = 0
    continuous = None
    for row in range(-1, geometry.n_y + 1):
        if 0 <= row and geometry.edge == "continuous":
            if continuous is None:  # all the free courses, one yarn
                continuous = _add_continuous_yarn(scene, geometry, H, offset)
                courses, left, right, spans, shares, t = continuous
                ts.append(t)
                offset += t.shape[0]
            if row < geometry.n_y:
                continue
        pts, t = geometry.course_points(row, H)
        y = scene.add_yarn(pts)
        ts.append(t)
        if row in (-1, geometry.n_y):
            if geometry.bars == "sliding":
                last = pts.shape[0] - 1
                scene.hold(y, [0, 1, last - 1, last])
                scene.slide(y, range(2, last - 1), (1.0, 0.0, 0.0))
            else:
                scene.hold(y, range(pts.shape[0]))
            bars.append(y)
        else:
            held = 2 if geometry.edge == "clamped" else 1
            last = pts.shape[0] - 1
            scene.hold(y, list(range(held)) + list(range(last - held + 1, last + 1)))
            courses.append(y)
            left.append(offset + np.arange(held))
            right.append(offset + last - np.arange(held))
        offset += pts.shape[0]
    rods = scene.build(twist=False, stretch_damping_ratio=stretch_damping_ratio)
    extra = {} if continuous is None else dict(course_span=spans, left_share=shares[0], right_share=shares[1])
    return KnitScene(
        geometry=geometry, rods=rods, H=H, courses=courses, bars=bars, node_t=np.concatenate(ts),
        left_end=np.array(left), right_end=np.array(right), **extra,
    )


def _add_continuous_yarn(scene: Scene, geometry: KnitGeometry, H: float, offset: int):
    """The free courses as one yarn of the continuous edge (module docstring), its first node ``offset``:
    (courses, left_end, right_end, course_span, (left_share, right_share), node_t)."""
    n_y, segments = geometry.n_y, turning_segments(geometry)
    pieces, ts, spans = [], [], []
    count = 0
    for row in range(n_y):
        pts, t = geometry.course_points(row, H)
        if row % 2:
            pts, t = pts[::-1], t[::-1]
        if row:  # the turning loop from the end of the course below
            side = 1.0 if pieces[-1][-1, 0] > 0 else -1.0
            pieces.append(turning_loop(pieces[-1][-1], pts[0], segments, side))
            ts.append(np.full(segments - 1, side * np.inf))
            count += segments - 1
        spans.append((offset + count, offset + count + pts.shape[0]))
        pieces.append(pts)
        ts.append(t)
        count += pts.shape[0]
    y = scene.add_yarn(np.vstack(pieces))
    last = count - 1
    scene.hold(y, [0, 1, last - 1, last])
    spans = np.array(spans, dtype=np.int64)
    clips = [int(spans[k, 1]) - offset + segments // 2 - 1 for k in range(n_y - 1)]  # the apex of each loop
    scene.slide(y, clips, (0.0, 1.0, 0.0))
    clips = [offset + c for c in clips]
    ends = np.zeros((2, n_y, 2), dtype=np.int64)  # [start side, end side] of each course
    share = np.zeros((2, n_y, 2))
    for k in range(n_y):
        ends[0, k], share[0, k] = ([offset, offset + 1], (1.0, 1.0)) if k == 0 else ([clips[k - 1]] * 2, (0.5, 0.0))
        ends[1, k], share[1, k] = (([offset + last, offset + last - 1], (1.0, 1.0)) if k == n_y - 1
                                   else ([clips[k]] * 2, (0.5, 0.0)))
    odd = np.arange(n_y) % 2 == 1  # odd courses start on the right
    left, right = np.where(odd[:, None], ends[1], ends[0]), np.where(odd[:, None], ends[0], ends[1])
    shares = (np.where(odd[:, None], share[1], share[0]), np.where(odd[:, None], share[0], share[1]))
    return [y] * n_y, list(left), list(right), spans, shares, np.concatenate(ts)
