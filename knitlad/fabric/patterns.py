"""Knit patterns: which way each loop is drawn through the loop below it.

A weft knit is a grid of stitches. At course r and column i, the loop of course r + 1 is drawn
through the head of course r, either from the fabric's technical back to its technical face: a
*knit* stitch, +1, every stitch of a jersey; or from face to back: a *purl* stitch, -1. A pattern
is the repeat of these signs (Spencer, *Knitting Technology*, 3rd ed., 2001, ch. 5). In knitlad's
knits the technical face looks to -z: Crane's curve puts each head at +z, over the legs of the
next course, as heads show on jersey's back (the loop threads its head moving to -z:
:func:`knitlad.fabric.topology.threading_direction`).

* ``jersey``: every stitch knit (the paper's fabric);
* ``rib``: 1x1 rib, knit and purl columns alternating (wales of each face side by side);
* ``garter``: knit and purl courses alternating (both faces show purl bumps).

How the sign enters the centreline (:meth:`KnitGeometry.curve <knitlad.fabric.scenes.knit.KnitGeometry.curve>`):
along course r, the upper half of the stitch at column i (|t - 2 pi i| < pi/2: its head and the
upper legs) crosses only course r + 1, and its lower half (its legs' feet and sinkers) only course
r - 1. Jersey's depth profile c cos 2t is multiplied by a face sign: stitch (r, i) on the upper
half, stitch (r - 1, i) on the lower half. Where the sign changes (a garter course's legs, a rib
course's sinker between a knit and a purl column) the yarn passes through the fabric's mid-plane
over ``FACE_SWITCH`` radians of t, away from every crossing (measured at l_x/l0 0.25 to 0.30 and
l_y/l0 0.20 to 0.25: the nearest crossing lies 0.2 rad from a sinker and 0.35 rad from a leg's middle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

KNIT, PURL = 1, -1
FACE_SWITCH = 0.08  # half-width (tanh) of a face sign's change along t [rad]


@dataclass(frozen=True)
class KnitPattern:
    """A knit pattern: ``repeat[r % rows][i % columns]`` is the stitch at course r, column i (KNIT or PURL)."""

    name: str
    repeat: tuple[tuple[int, ...], ...]

    def __post_init__(self) -> None:
        widths = {len(row) for row in self.repeat}
        if not self.repeat or len(widths) != 1 or 0 in widths:
            raise ValueError(f"pattern {self.name!r}: the repeat must be a non-empty rectangle of stitches")
        if any(s not in (KNIT, PURL) for row in self.repeat for s in row):
            raise ValueError(f"pattern {self.name!r}: a stitch is knit (+1) or purl (-1)")

    @property
    def period(self) -> tuple[int, int]:
        """(columns, courses) of the repeat."""
        return len(self.repeat[0]), len(self.repeat)

    @property
    def plain(self) -> bool:
        """Every stitch knit: jersey, whose centreline is Crane's as it stands."""
        return all(s == KNIT for row in self.repeat for s in row)

    def stitch(self, row, column):
        """KNIT or PURL at course ``row``, column ``column`` (integers or integer arrays; any sign)."""
        table = np.asarray(self.repeat, dtype=np.int64)
        return table[np.mod(row, table.shape[0]), np.mod(column, table.shape[1])]

    def face(self, t: np.ndarray, row: int) -> np.ndarray:
        """The face sign along course ``row`` at centreline parameter ``t`` (:func:`face_sign`)."""
        return face_sign(self, t, row)


@dataclass(frozen=True)
class BandedPattern:
    """A fabric of pattern ``base`` with the courses ``first`` to ``first + rows - 1`` (0: the bottom free
    course) knitted in pattern ``band``: a run-stop band (hosiery's century-old device)."""

    base: KnitPattern
    band: KnitPattern
    first: int
    rows: int

    @property
    def name(self) -> str:
        return f"{self.base.name} with a {self.band.name} band"

    @property
    def period(self) -> tuple[int, int]:
        return self.base.period

    @property
    def plain(self) -> bool:
        return self.base.plain and self.band.plain

    def stitch(self, row, column):
        row = np.asarray(row)
        inside = (row >= self.first) & (row < self.first + self.rows)
        return np.where(inside, self.band.stitch(row, column), self.base.stitch(row, column))

    def face(self, t: np.ndarray, row: int) -> np.ndarray:
        return face_sign(self, t, row)


def face_sign(pattern, t: np.ndarray, row: int) -> np.ndarray:
    """The face sign along course ``row`` at centreline parameter ``t`` (module docstring): stitch
    (row, i) on the upper half of column i, stitch (row - 1, i) on its lower half, smoothed."""
    t = np.asarray(t, dtype=float)
    if pattern.plain:
        return np.ones_like(t)
    first = math.floor((t.min() + math.pi) / (2 * math.pi)) - 1
    last = math.ceil((t.max() + math.pi) / (2 * math.pi)) + 1
    columns = np.arange(first, last + 1)
    upper, lower = pattern.stitch(row, columns), pattern.stitch(row - 1, columns)
    # the sign piecewise, column by column: lower | upper | lower, switching at -pi/2, +pi/2 and +pi
    points = np.column_stack([2 * math.pi * columns - math.pi / 2, 2 * math.pi * columns + math.pi / 2,
                              2 * math.pi * columns + math.pi]).ravel()
    before = np.column_stack([lower, upper, lower]).ravel()
    after = np.column_stack([upper, lower, np.append(lower[1:], lower[-1])]).ravel()
    out = np.full(t.shape, float(before[0]))
    for p, a, b in zip(points, before, after):
        if a != b:
            out += 0.5 * (b - a) * (1.0 + np.tanh((t - p) / FACE_SWITCH))
    return out


PATTERNS: dict[str, KnitPattern] = {
    "jersey": KnitPattern("jersey", ((KNIT,),)),
    "rib": KnitPattern("rib", ((KNIT, PURL),)),
    "garter": KnitPattern("garter", ((KNIT,), (PURL,))),
}


def knit_pattern(name: str) -> KnitPattern:
    """The pattern of this name (``PATTERNS``)."""
    try:
        return PATTERNS[name]
    except KeyError:
        raise ValueError(f"unknown knit pattern {name!r}: one of {', '.join(PATTERNS)}") from None


def fabric_pattern(name: str, band: tuple[str, int, int] | list | None = None) -> KnitPattern | BandedPattern:
    """The pattern ``name``, with ``band`` = (its pattern, first course, courses) knitted in, if given."""
    base = knit_pattern(name)
    if band is None:
        return base
    band_name, first, rows = band
    if int(rows) < 1:
        raise ValueError(f"a band of {rows} courses: it needs at least one")
    return BandedPattern(base, knit_pattern(band_name), int(first), int(rows))
