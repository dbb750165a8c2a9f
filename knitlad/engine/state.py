"""One structure-of-arrays state for all yarns, and the builder that makes it.

All yarns live in the same arrays; ``yarn_start[y]`` is the index of yarn y's
first node (``yarn_start[-1] == n``). Node arrays are ``(n, 3)``. Every value is
in internal units (:mod:`knitlad.engine.units`: mm, mg, ms, mN). Edges and bending
hinges are flat index lists derived once from the offsets, so an open yarn, a
ring and a yarn periodised with a shift all use the same kernels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple, Sequence

import numba
import numpy as np

from knitlad.engine import units
from knitlad.engine.kernels.dissipation import N_LEDGER
from knitlad.engine.kernels.elastic import edge_vectors, material_curvatures
from knitlad.engine.kernels.frames import bishop_reference_directors, material_frames, update_reference_twist
from knitlad.engine.units import Material


def finite_vectors(name: str, value, shape: tuple) -> np.ndarray:
    """``value`` as a float array broadcast to ``shape``; a ValueError naming ``name`` if it is not finite (an
    infinity reaching the contact's grid would index outside it) or does not fit the shape."""
    try:
        array = np.broadcast_to(np.asarray(value, dtype=float), shape)
    except (ValueError, TypeError):
        raise ValueError(f"{name}: expected {'a 3-vector' if shape == (3,) else f'shape {shape}'} of numbers, "
                         f"got {value!r}") from None
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: must be finite, got " + (repr(value) if array.size <= 3 else "NaN or infinity"))
    return np.array(array)


# The axis each array runs along (said once per field, read by cut_edge and the HDF5 writer):
NODE, EDGE, HINGE, YARN, RAIL, IMAGE = "node", "edge", "hinge", "yarn", "rail", "image"


class RodModel(NamedTuple):
    """What a scene builds: topology, parameters and constraints of every yarn (internal units).

    A model does not change while a simulation runs; a change of the scene (a cut, twist
    switched on, other dashpots) builds a new model (:func:`cut_edge`, :func:`with_twist`,
    ``model._replace``). The axis of each array is in :data:`MODEL_AXES`.
    """

    # nodes (n,)
    mass: np.ndarray  # (n,) lumped masses
    radius: np.ndarray  # (n,) yarn radius at the node (contact)
    held: np.ndarray  # (n,) bool: position prescribed, x(t) = x + t * v_prescribed
    v_prescribed: np.ndarray  # (n, 3)
    f_ext: np.ndarray  # (n, 3) constant external force
    node_yarn: np.ndarray  # (n,) int64 yarn of each node
    yarn_start: np.ndarray  # (n_yarns + 1,) int64 offsets
    yarn_parent: np.ndarray  # (n_yarns,) int64 the yarn this one was cut from (itself if never cut)
    rail_node: np.ndarray  # (k,) int64 nodes that may only slide along a line ...
    rail_axis: np.ndarray  # (k, 3) ... the unit direction of that line ...
    rail_friction: np.ndarray  # (k,) ... and the Coulomb coefficient between the node and its rail (0: none)
    image_node: np.ndarray  # (g,) int64 nodes of periodic images: held copies that follow ...
    image_master: np.ndarray  # (g,) int64 ... their master node ...
    image_shift: np.ndarray  # (g, 3) ... shifted by a lattice vector: x[image] = x[master] + shift
    # edges (ne,)
    edge_a: np.ndarray
    edge_b: np.ndarray
    edge_shift: np.ndarray  # (ne, 3) added to x[edge_b] (periodised yarns)
    rest_length: np.ndarray
    EA: np.ndarray
    stretch_damping: np.ndarray  # dashpot coefficient c (mN ms / mm)
    twist_inertia: np.ndarray  # rho_L d^2/8 |e_bar|
    theta_held: np.ndarray  # bool: twist angle clamped
    # hinges (nh,)
    hinge_e0: np.ndarray
    hinge_e1: np.ndarray
    B_over_l: np.ndarray  # B / l_h (Voronoi length of the rest shape)
    GJ_over_l: np.ndarray
    kappa_bar: np.ndarray  # (nh, 2) natural material curvature (integrated, dimensionless)
    twist_bar: np.ndarray  # natural twist (integrated)

    @property
    def n_nodes(self) -> int:
        return self.mass.shape[0]

    @property
    def n_yarns(self) -> int:
        return self.yarn_start.shape[0] - 1

    @property
    def edge_yarn(self) -> np.ndarray:
        """(ne,) int64 the yarn of each edge (that of its first node: an edge joins two nodes of one yarn)."""
        return self.node_yarn[self.edge_a]

    def yarn_of(self, node: int) -> tuple[int, int]:
        """(yarn, index of the node within its yarn)."""
        y = int(self.node_yarn[node])
        return y, int(node - self.yarn_start[y])


class RodState(NamedTuple):
    """What changes in time (internal units): positions, velocities, twist angles and frames."""

    x: np.ndarray  # (n, 3) positions
    v: np.ndarray  # (n, 3) velocities
    theta: np.ndarray  # (ne,) twist angle of the material frame
    omega: np.ndarray  # (ne,) d theta / dt
    ref_u: np.ndarray  # (ne, 3) reference director
    tangent: np.ndarray  # (ne, 3) unit tangent at the last frame update
    ref_twist: np.ndarray  # (nh,) reference twist, kept continuous in time

    def copy(self) -> "RodState":
        return RodState(*(np.array(a, copy=True) for a in self))


MODEL_AXES = {
    **dict.fromkeys(("mass", "radius", "held", "v_prescribed", "f_ext", "node_yarn"), NODE),
    "yarn_start": YARN, "yarn_parent": YARN, "rail_node": RAIL, "rail_axis": RAIL,
    "rail_friction": RAIL,
    **dict.fromkeys(("image_node", "image_master", "image_shift"), IMAGE),
    **dict.fromkeys(("edge_a", "edge_b", "edge_shift", "rest_length", "EA", "stretch_damping", "twist_inertia",
                     "theta_held"), EDGE),
    **dict.fromkeys(("hinge_e0", "hinge_e1", "B_over_l", "GJ_over_l", "kappa_bar", "twist_bar"), HINGE),
}
STATE_AXES = {"x": NODE, "v": NODE, "theta": EDGE, "omega": EDGE, "ref_u": EDGE, "tangent": EDGE,
              "ref_twist": HINGE}


@dataclass(frozen=True)
class Rods:
    """A built scene: its model, its state and its modes.

    ``twist``: the yarns carry material frames and twist (framed DER bending with natural
    curvature, twisting, the friction couple); else isotropic bending of rods straight
    at rest, with the twist angles unused. ``framed``: the yarns remember a curved shape
    (``kappa_bar``), so they bend through their material frames (needs ``twist``); said by
    whoever gives them the shape (``Scene.build`` for ``natural_curvature="rest"``,
    ``natural_curvature.remember_shape``), never inferred from the arrays.
    """

    model: RodModel
    state: RodState
    twist: bool = False
    framed: bool = False

    def __post_init__(self) -> None:
        if self.framed and not self.twist:
            raise ValueError("framed rods (a natural curvature) need twist: a curvature lives in the material frame")

    def copy(self) -> "Rods":
        """A copy whose state can run on its own (the model is shared: it is never changed in place)."""
        return Rods(self.model, self.state.copy(), self.twist, self.framed)

    def replace_model(self, framed: bool | None = None, **arrays) -> "Rods":
        """The same state with some model arrays replaced (same shapes), e.g. other dashpots or loads;
        ``framed`` set anew where a natural curvature is given (None: kept)."""
        for name, value in arrays.items():
            old = getattr(self.model, name)
            if np.shape(value) != old.shape:
                raise ValueError(f"{name}: shape {np.shape(value)} where the model has {old.shape}")
        return Rods(self.model._replace(**{k: np.array(v, dtype=getattr(self.model, k).dtype, order="C") for k, v in arrays.items()}),
                    self.state, self.twist, self.framed if framed is None else bool(framed))


class Workspace(NamedTuple):
    """Preallocated scratch for one force evaluation."""

    e: np.ndarray  # (ne, 3) edge vectors
    elen: np.ndarray  # (ne,)
    d1: np.ndarray  # (ne, 3) material frame
    d2: np.ndarray
    force: np.ndarray  # (n, 3) total force on each node
    torque: np.ndarray  # (ne,) torque about each edge tangent
    yarn_edges: np.ndarray  # (n_yarns + 1,) first edge of each yarn (edges are stored yarn by yarn)
    yarn_hinges: np.ndarray  # (n_yarns + 1,) first hinge of each yarn
    axial_sweep: np.ndarray  # (ne, 4) the tridiagonal solve of implicit axial forces (and the ledger's terms)
    v_damp: np.ndarray  # (n, 3) the velocities the dashpots see with DASHPOTS_PREDICTED ...
    omega_damp: np.ndarray  # (ne,) ... and the spins
    frame_anchor: np.ndarray  # (ne,) bool: the edges whose reference frame the frame-free twist carries each step
    # the energy ledger: what each mechanism took out since it was zeroed [uJ], per yarn or per block of contact
    # pairs (rows), per channel (knitlad.engine.kernels.dissipation.LEDGER_NAMES)
    ledger: np.ndarray  # (max(n_yarns, threads), N_LEDGER)
    # the viscoelastic branches' internal variables (knitlad.engine.kernels.dissipation.viscoelastic_forces):
    # state of the material, kept with the simulation that advances it and relaxed when it starts
    branch_ext: np.ndarray  # (ne,) the extension each edge's branch has relaxed to [mm]
    branch_kb: np.ndarray  # (nh, 3) the curvature binormal each hinge's branch has relaxed to [-]
    rail_reaction: np.ndarray  # (rails, 3) what each rail took from its node's force at the last evaluation

    @staticmethod
    def for_model(model: RodModel) -> "Workspace":
        ne = model.edge_a.shape[0]
        n = model.n_nodes
        yarns = np.arange(model.n_yarns + 1)
        edge_yarn = model.edge_yarn
        hinge_yarn = edge_yarn[model.hinge_e1]
        rows = max(model.n_yarns, numba.config.NUMBA_NUM_THREADS, 1)
        return Workspace(
            np.zeros((ne, 3)), np.zeros(ne), np.zeros((ne, 3)), np.zeros((ne, 3)), np.zeros((n, 3)), np.zeros(ne),
            np.searchsorted(edge_yarn, yarns).astype(np.int64), np.searchsorted(hinge_yarn, yarns).astype(np.int64),
            np.zeros((ne, 4)), np.zeros((n, 3)), np.zeros(ne), frame_anchors(model),
            np.zeros((rows, N_LEDGER)), np.zeros(ne), np.zeros((model.hinge_e0.shape[0], 3)),
            np.zeros((model.rail_node.shape[0], 3)),
        )


def frame_anchors(model: RodModel) -> np.ndarray:
    """(ne,) bool: the first edge of each yarn and every edge no hinge ends on (a cut's new end).

    The frame-free twist (TWIST_STRAIGHT) time-transports only these edges' reference frames;
    ``kernels.frames.rebuild_reference_frames`` gives the others from them and the reference
    twist, hinge by hinge in storage order, which needs each hinge's first edge to be an anchor
    or the second edge of an earlier hinge: checked here.
    """
    ne, nh = model.edge_a.shape[0], model.hinge_e0.shape[0]
    edge_yarn = model.edge_yarn
    anchor = np.ones(ne, dtype=bool)
    anchor[model.hinge_e1] = False
    first = np.searchsorted(edge_yarn, np.arange(model.n_yarns + 1))
    anchor[first[:-1][first[:-1] < first[1:]]] = True
    ends_at = np.full(ne, nh, dtype=np.int64)  # the hinge whose second edge each edge is
    ends_at[model.hinge_e1] = np.arange(nh)
    k0 = model.hinge_e0
    rebuilt = ~anchor[model.hinge_e1]
    if np.any(rebuilt & ~anchor[k0] & (ends_at[k0] >= np.arange(nh))):
        raise ValueError("the hinges are not stored in order along their yarns")
    return anchor


@dataclass
class _Yarn:
    points: np.ndarray  # (k, 3) metres
    material: Material
    closed: bool
    period: np.ndarray  # (3,) metres, shift of the closing edge
    natural_curvature: str
    start: np.ndarray | None = None  # (k, 3) metres: where the yarn starts, when not at its rest shape
    held: dict[int, np.ndarray] = field(default_factory=dict)  # node -> velocity (m/s)
    rails: dict[int, tuple[np.ndarray, float]] = field(default_factory=dict)  # node -> (unit axis, Coulomb mu)
    image_of: tuple[int, np.ndarray] | None = None  # (master yarn, lattice shift [m]) for a periodic image
    forces: dict[int, np.ndarray] = field(default_factory=dict)  # node -> force (N)
    twist_held: set[int] = field(default_factory=set)


class Scene:
    """Build :class:`Rods` (a model and its initial state) from yarn centrelines given in SI units.

    Example::

        scene = Scene()
        y = scene.add_yarn(points)            # (k, 3) array in metres
        scene.hold(y, [0, 1])                 # clamp the first two nodes
        scene.apply_force(y, -1, (0, -1e-3, 0))  # 1 mN downward at the tip
        rods = scene.build()                  # rods.model, rods.state
    """

    def __init__(self, material: Material | None = None) -> None:
        self.material = material or units.NYLON
        self._yarns: list[_Yarn] = []

    def add_yarn(
        self,
        points: np.ndarray,
        material: Material | None = None,
        closed: bool = False,
        period: Sequence[float] | None = None,
        natural_curvature: str = "straight",
        start: np.ndarray | None = None,
    ) -> int:
        """Add a yarn through ``points`` (k, 3) [m]; returns its index.

        ``closed``: the last node joins the first (a ring); with ``period`` (m),
        the closing edge goes to ``points[0] + period`` (a yarn periodised along
        ``period``). ``natural_curvature``: ``"straight"`` (rest shape straight,
        the paper's simulations) or ``"rest"`` (the given shape is force-free;
        needs ``build(twist=True)``). ``points`` are the rest shape: they set the rest lengths
        (and, with ``"rest"``, the rest curvatures and twists, in the rest shape's twist-free frames).
        ``start`` (k, 3) [m]: the yarn starts there instead, strained, e.g. a straight column started
        with an imperfection, or a ring started squeezed; with ``"straight"`` it needs no twist.
        """
        pts = np.asarray(points, dtype=float)
        if start is not None:
            start = np.asarray(start, dtype=float)
            if start.shape != pts.shape:
                raise ValueError(f"start must have the shape of points {pts.shape}, got {start.shape}")
            if not np.all(np.isfinite(start)):
                raise ValueError("start contains NaN or infinity")
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2:
            raise ValueError(f"points must be a (k >= 2, 3) array, got shape {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise ValueError("points contain NaN or infinity")
        if natural_curvature not in ("straight", "rest"):
            raise ValueError(f"natural_curvature must be 'straight' or 'rest', got {natural_curvature!r}")
        if period is not None and not closed:
            raise ValueError("period only applies to a closed (periodised) yarn")
        if closed and pts.shape[0] < 3:
            raise ValueError("a closed yarn needs at least 3 nodes")
        shift = np.zeros(3) if period is None else np.asarray(period, dtype=float)
        ends = np.vstack([pts, pts[:1] + shift]) if closed else pts
        if np.any(np.linalg.norm(np.diff(ends, axis=0), axis=1) <= 0):
            raise ValueError("two consecutive points coincide (zero-length edge)")
        self._yarns.append(_Yarn(pts, material or self.material, closed, shift, natural_curvature,
                                 None if start is None else start.copy()))
        return len(self._yarns) - 1

    def _yarn(self, yarn: int) -> _Yarn:
        if not 0 <= yarn < len(self._yarns):
            raise IndexError(f"no yarn {yarn}: the scene has {len(self._yarns)}")
        return self._yarns[yarn]

    def _node_index(self, y: _Yarn, node: int) -> int:
        k = y.points.shape[0]
        if not -k <= node < k:
            raise IndexError(f"node {node} out of range for a yarn of {k} nodes")
        return node % k

    def hold(self, yarn: int, nodes: Sequence[int], velocity: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        """Prescribe the motion of ``nodes``: x(t) = x(0) + t * velocity [m/s]."""
        y = self._yarn(yarn)
        velocity = finite_vectors("velocity", velocity, (3,))
        for node in nodes:
            y.held[self._node_index(y, node)] = velocity

    def slide(self, yarn: int, nodes: Sequence[int], axis: Sequence[float], friction: float = 0.0) -> None:
        """Let ``nodes`` move only along ``axis`` through their initial position (a rail, or a clip on a bar):
        the force on them is projected on the axis, with Coulomb ``friction`` from the rail's normal reaction
        (:func:`knitlad.engine.kernels.integrate.rail_friction_forces`; 0: frictionless)."""
        y = self._yarn(yarn)
        a = np.asarray(axis, dtype=float)
        norm = float(np.linalg.norm(a))
        if a.shape != (3,) or not norm > 0:
            raise ValueError(f"axis must be a non-zero 3-vector, got {axis!r}")
        if not (math.isfinite(friction) and friction >= 0):
            raise ValueError(f"friction must be a finite coefficient >= 0, got {friction!r}")
        for node in nodes:
            y.rails[self._node_index(y, node)] = (a / norm, float(friction))

    def add_image(self, yarn: int, shift: Sequence[float]) -> int:
        """A periodic image of ``yarn`` shifted by the lattice vector ``shift`` [m]; returns its index.

        The image is a held copy whose nodes follow the master's at every force
        evaluation; the forces on it are discarded. Contact between a yarn and
        images (never between two images) makes a cell periodic: each real node
        feels its neighbours in all the surrounding cells.
        """
        master = self._yarn(yarn)
        if master.image_of is not None:
            raise ValueError("an image of an image: give the master yarn")
        shift = np.asarray(shift, dtype=float)
        if shift.shape != (3,) or not np.any(shift):
            raise ValueError(f"shift must be a non-zero 3-vector, got {shift!r}")
        y = _Yarn(master.points + shift, master.material, master.closed, master.period.copy(),
                  master.natural_curvature, None if master.start is None else master.start + shift)
        y.held = {j: np.zeros(3) for j in range(master.points.shape[0])}
        y.image_of = (yarn, shift)
        self._yarns.append(y)
        return len(self._yarns) - 1

    def hold_twist(self, yarn: int, edges: Sequence[int]) -> None:
        """Clamp the twist angle of ``edges`` (a clamped end: hold 2 nodes and edge 0)."""
        y = self._yarn(yarn)
        ne = y.points.shape[0] if y.closed else y.points.shape[0] - 1
        for k in edges:
            if not -ne <= k < ne:
                raise IndexError(f"edge {k} out of range for a yarn of {ne} edges")
            y.twist_held.add(k % ne)

    def apply_force(self, yarn: int, node: int, force: Sequence[float]) -> None:
        """A constant external force [N] on one node."""
        y = self._yarn(yarn)
        y.forces[self._node_index(y, node)] = finite_vectors("force", force, (3,))

    def build(self, twist: bool | None = None, stretch_damping_ratio: float = 0.2) -> Rods:
        """Assemble the model and the initial state in internal units.

        ``twist``: carry material frames and twist (needed for natural curvature
        or twist loads); default: on only if some yarn has ``natural_curvature="rest"``.
        ``stretch_damping_ratio``: the internal dashpot of each edge as a fraction
        of the critical damping of its axial mode (0 = no dissipation).
        """
        if not self._yarns:
            raise ValueError("the scene has no yarn")
        if not (stretch_damping_ratio >= 0 and math.isfinite(stretch_damping_ratio)):
            raise ValueError(f"stretch_damping_ratio must be a finite number >= 0, got {stretch_damping_ratio!r}")
        needs_frames = any(y.natural_curvature == "rest" for y in self._yarns)
        if twist is None:
            twist = needs_frames
        if needs_frames and not twist:
            raise ValueError("natural_curvature='rest' needs build(twist=True): a curvature lives in the material frame")
        if stretch_damping_ratio < 0:
            raise ValueError("stretch_damping_ratio must be >= 0")
        counts = [y.points.shape[0] for y in self._yarns]
        yarn_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        x = np.vstack([y.points for y in self._yarns]) / units.LENGTH
        topology = self._topology(yarn_start)
        parameters = self._parameters(x, topology, twist, stretch_damping_ratio)
        model = RodModel(**topology, **parameters, **self._constraints(yarn_start, topology["edge_a"].shape[0]))
        frames = _initial_frames(x, model, twist, [y.natural_curvature == "rest" for y in self._yarns])
        kappa_bar, twist_bar, state = frames
        if any(y.start is not None for y in self._yarns):
            # the rest shape gave lengths and curvatures; the yarns start elsewhere, in their own frames
            x0 = np.vstack([y.points if y.start is None else y.start for y in self._yarns]) / units.LENGTH
            state = _initial_frames(x0, model, twist, [False] * len(self._yarns))[2]
        return Rods(model._replace(kappa_bar=kappa_bar, twist_bar=twist_bar), state, bool(twist), needs_frames)

    def _topology(self, yarn_start: np.ndarray) -> dict:
        """Edges (joining consecutive nodes; a closed yarn's last edge back to its first node plus
        its period) and bending hinges (consecutive edge pairs), yarn by yarn."""
        counts = np.diff(yarn_start)
        edge_a, edge_b, edge_shift, hinge_e0, hinge_e1 = [], [], [], [], []
        for iy, y in enumerate(self._yarns):
            s, k = int(yarn_start[iy]), int(counts[iy])
            first_edge = len(edge_a)
            ne = k if y.closed else k - 1
            for j in range(ne):
                edge_a.append(s + j)
                edge_b.append(s + (j + 1) % k)
                edge_shift.append(y.period / units.LENGTH if (y.closed and j == k - 1) else np.zeros(3))
            for j in range(1 if not y.closed else 0, ne):
                hinge_e0.append(first_edge + (j - 1) % ne)
                hinge_e1.append(first_edge + j)
        return dict(
            node_yarn=np.repeat(np.arange(len(counts)), counts).astype(np.int64), yarn_start=yarn_start,
            yarn_parent=np.arange(len(counts), dtype=np.int64),
            edge_a=np.array(edge_a, dtype=np.int64), edge_b=np.array(edge_b, dtype=np.int64),
            edge_shift=np.array(edge_shift, dtype=float).reshape(-1, 3),
            hinge_e0=np.array(hinge_e0, dtype=np.int64), hinge_e1=np.array(hinge_e1, dtype=np.int64),
        )

    def _parameters(self, x: np.ndarray, top: dict, twist: bool, stretch_damping_ratio: float) -> dict:
        """Masses, stiffnesses, dashpots and inertias from the materials and the rest shape ``x``."""
        edge_a, edge_b, hinge_e0, hinge_e1 = top["edge_a"], top["edge_b"], top["hinge_e0"], top["hinge_e1"]
        ne, nh, n = edge_a.shape[0], hinge_e0.shape[0], x.shape[0]
        e = np.zeros((ne, 3))
        rest_length = np.zeros(ne)
        edge_vectors(x, edge_a, edge_b, top["edge_shift"], e, rest_length)
        edge_yarn = top["node_yarn"][edge_a]
        mats = [y.material for y in self._yarns]
        rho = np.array([m.line_density / units.LINE_DENSITY for m in mats])[edge_yarn]
        EA = np.array([m.stretching_stiffness / units.FORCE for m in mats])[edge_yarn]
        d = np.array([m.diameter / units.LENGTH for m in mats])
        mass = np.zeros(n)
        np.add.at(mass, edge_a, 0.5 * rho * rest_length)
        np.add.at(mass, edge_b, 0.5 * rho * rest_length)
        # critical damping of the two-node axial mode: c = 2 zeta sqrt(k m_a m_b / (m_a + m_b))
        reduced = mass[edge_a] * mass[edge_b] / (mass[edge_a] + mass[edge_b])
        voronoi = 0.5 * (rest_length[hinge_e0] + rest_length[hinge_e1])
        hinge_yarn = edge_yarn[hinge_e1] if nh else np.zeros(0, dtype=np.int64)
        B = np.array([m.bending_stiffness / units.BENDING_STIFFNESS for m in mats])
        GJ = np.array([m.twisting_stiffness / units.BENDING_STIFFNESS for m in mats])
        return dict(
            mass=mass, radius=0.5 * d[top["node_yarn"]], rest_length=rest_length, EA=EA,
            stretch_damping=2.0 * stretch_damping_ratio * np.sqrt(EA / rest_length * reduced),
            twist_inertia=rho * d[edge_yarn] ** 2 / 8.0 * rest_length,
            B_over_l=B[hinge_yarn] / voronoi, GJ_over_l=(GJ[hinge_yarn] / voronoi) if twist else np.zeros(nh),
            kappa_bar=np.zeros((nh, 2)), twist_bar=np.zeros(nh),
        )

    def _constraints(self, yarn_start: np.ndarray, ne: int) -> dict:
        """Held nodes and their velocities, loads, rails, periodic images and clamped twist angles."""
        n = int(yarn_start[-1])
        held = np.zeros(n, dtype=bool)
        v_prescribed = np.zeros((n, 3))
        f_ext = np.zeros((n, 3))
        theta_held = np.zeros(ne, dtype=bool)
        rail_node, rail_axis, rail_friction, image_node, image_master, image_shift = [], [], [], [], [], []
        first_edge = 0
        for iy, y in enumerate(self._yarns):
            s, k = int(yarn_start[iy]), y.points.shape[0]
            if y.image_of is not None:
                m, shift = y.image_of
                image_node.extend(range(s, s + k))
                image_master.extend(range(int(yarn_start[m]), int(yarn_start[m]) + k))
                image_shift.extend([shift / units.LENGTH] * k)
            for j, (axis, mu) in sorted(y.rails.items(), key=lambda item: item[0]):
                if j not in y.held:
                    rail_node.append(s + j)
                    rail_axis.append(axis)
                    rail_friction.append(mu)
            for j, vel in y.held.items():
                held[s + j] = True
                v_prescribed[s + j] = vel / units.VELOCITY
            for j, f in y.forces.items():
                f_ext[s + j] = f / units.FORCE
            for j in y.twist_held:
                theta_held[first_edge + j] = True
            first_edge += k if y.closed else k - 1
        return dict(
            held=held, v_prescribed=v_prescribed, f_ext=f_ext, theta_held=theta_held,
            rail_node=np.array(rail_node, dtype=np.int64), rail_axis=np.array(rail_axis, dtype=float).reshape(-1, 3),
            rail_friction=np.array(rail_friction, dtype=float),
            image_node=np.array(image_node, dtype=np.int64), image_master=np.array(image_master, dtype=np.int64),
            image_shift=np.array(image_shift, dtype=float).reshape(-1, 3),
        )


def _initial_frames(x: np.ndarray, model: RodModel, twist: bool, curved_yarns: list[bool]):
    """(kappa_bar, twist_bar, state): Bishop reference frames along the yarns, and for yarns with
    ``natural_curvature="rest"`` the rest curvatures and twists of the built shape."""
    ne, nh = model.edge_a.shape[0], model.hinge_e0.shape[0]
    e = np.zeros((ne, 3))
    elen = np.zeros(ne)
    edge_vectors(x, model.edge_a, model.edge_b, model.edge_shift, e, elen)
    tangent = e / elen[:, None]
    edge_yarn = model.edge_yarn
    ref_u = _initial_reference_directors(tangent, edge_yarn)
    ref_twist = np.zeros(nh)
    kappa_bar = np.zeros((nh, 2))
    twist_bar = np.zeros(nh)
    theta = np.zeros(ne)
    if twist:
        update_reference_twist(tangent, ref_u, model.hinge_e0, model.hinge_e1, ref_twist)
        d1 = np.zeros((ne, 3))
        d2 = np.zeros((ne, 3))
        material_frames(tangent, ref_u, theta, d1, d2)
        rest_curv = np.zeros((nh, 2))
        material_curvatures(e, elen, d1, d2, model.hinge_e0, model.hinge_e1, rest_curv)
        hinge_yarn = edge_yarn[model.hinge_e1] if nh else np.zeros(0, dtype=np.int64)
        curved = np.array(curved_yarns)[hinge_yarn]
        kappa_bar[curved] = rest_curv[curved]
        twist_bar[curved] = ref_twist[curved]
    state = RodState(x=x, v=np.zeros_like(x), theta=theta, omega=np.zeros(ne), ref_u=ref_u, tangent=tangent,
                     ref_twist=ref_twist)
    return kappa_bar, twist_bar, state


def _initial_reference_directors(tangent: np.ndarray, edge_yarn: np.ndarray) -> np.ndarray:
    """Space-parallel reference frame along each yarn (Bishop frame), from a seed normal."""
    ref_u = np.zeros_like(tangent)
    bishop_reference_directors(tangent, edge_yarn, ref_u)
    return ref_u


def cut_edge(rods: Rods, edge: int) -> Rods:
    """A new scene with ``edge`` removed: its open yarn becomes two yarns at that point.

    Node arrays are unchanged (same indices); the edge and the bending hinges that
    used it disappear, so the two new ends are free. Every array is cut along the
    axis :data:`MODEL_AXES` / :data:`STATE_AXES` gives it, so a new field cannot be missed.
    The second piece keeps the first's ``yarn_parent``: for the contact the two stay one
    yarn with a gap of one edge, so their new ends, closer than a diameter once the
    segments are shorter than d, are excluded from each other as neighbours along a yarn
    are (:func:`knitlad.engine.contact.contact_topology`), instead of pushing each other apart.
    """
    m = rods.model
    ne = m.edge_a.shape[0]
    if not 0 <= edge < ne:
        raise IndexError(f"no edge {edge}")
    a, b = int(m.edge_a[edge]), int(m.edge_b[edge])
    if b != a + 1 or np.any(m.edge_shift[edge] != 0):
        raise ValueError("only an inner edge of an open yarn can be cut")
    keep = {EDGE: np.ones(ne, dtype=bool), HINGE: (m.hinge_e0 != edge) & (m.hinge_e1 != edge)}
    keep[EDGE][edge] = False

    def cut(array: np.ndarray, axis: str) -> np.ndarray:
        return np.array(array[keep[axis]] if axis in keep else array, copy=True)

    model = {name: cut(getattr(m, name), MODEL_AXES[name]) for name in RodModel._fields}
    remap = np.cumsum(keep[EDGE]) - 1  # old edge index -> new
    model["hinge_e0"] = remap[model["hinge_e0"]].astype(np.int64)
    model["hinge_e1"] = remap[model["hinge_e1"]].astype(np.int64)
    y = int(m.node_yarn[a])
    yarn_start = np.insert(m.yarn_start, y + 1, b).astype(np.int64)
    model["yarn_start"] = yarn_start
    model["yarn_parent"] = np.insert(m.yarn_parent, y + 1, m.yarn_parent[y]).astype(np.int64)
    model["node_yarn"] = np.repeat(np.arange(yarn_start.shape[0] - 1), np.diff(yarn_start)).astype(np.int64)
    state = RodState(**{name: cut(getattr(rods.state, name), STATE_AXES[name]) for name in RodState._fields})
    return Rods(RodModel(**model), state, rods.twist, rods.framed)


def with_twist(rods: Rods, twist_over_bending: float) -> Rods:
    """A copy of a twist-free scene (``build(twist=False)``) that carries twist from here on.

    For yarns straight at rest, twist decouples from the centreline while nothing
    loads it; a frictional contact does (its force acts on the yarn's surface), so
    a study of the friction couple switches twist on, here, from the current shape:
    Bishop reference frames along the current tangents, theta = omega = 0, and the
    natural twist set to the current reference twist, so the twist energy is zero
    and every force is unchanged. ``twist_over_bending``: GJ / B of the yarns
    (1 / (1 + nu), :attr:`knitlad.engine.units.Material.twisting_stiffness`).
    """
    if rods.twist:
        raise ValueError("the scene already carries twist")
    if not twist_over_bending > 0:
        raise ValueError(f"twist_over_bending must be > 0, got {twist_over_bending!r}")
    m, s = rods.model, rods.state
    ne = m.edge_a.shape[0]
    e = np.zeros((ne, 3))
    elen = np.zeros(ne)
    edge_vectors(s.x, m.edge_a, m.edge_b, m.edge_shift, e, elen)
    tangent = e / elen[:, None]
    ref_u = _initial_reference_directors(tangent, m.edge_yarn)
    ref_twist = np.zeros(m.hinge_e0.shape[0])
    update_reference_twist(tangent, ref_u, m.hinge_e0, m.hinge_e1, ref_twist)
    model = m._replace(GJ_over_l=m.B_over_l * twist_over_bending, twist_bar=ref_twist.copy())
    state = s.copy()._replace(tangent=tangent, ref_u=ref_u, ref_twist=ref_twist, theta=np.zeros(ne),
                              omega=np.zeros(ne))
    return Rods(model, state, twist=True)


def with_axial_stiffness(rods: Rods, factor: float) -> Rods:
    """A copy whose yarns' stretching stiffness is ``factor`` x EA, every edge keeping its current tension.

    The axial waves (c_E = 44 c_b in the paper's Nylon) and the stiff axial springs set the
    explicit step; the laddering runs at velocities of order c_b and strains below 1 %.
    A softer EA' = factor EA lets the step grow as 1/sqrt(factor) (with the contact springs
    softened alike). The rest lengths are reset so that T = EA (l/l_r - 1) is unchanged at
    the current lengths, l_r' = l / (1 + T/EA'): the state stays at its equilibrium, and the
    axial dashpot keeps its fraction of critical damping (it scales as sqrt(EA)). Measured on
    the laddering, it is not free: EA/4 raises v_lad and f_x^fin by 8 to 18 % (docs/accuracy.md).
    """
    if not 0 < factor <= 1:
        raise ValueError(f"the axial stiffness factor must lie in (0, 1], got {factor!r}")
    m = rods.model
    ne = m.edge_a.shape[0]
    elen = np.zeros(ne)
    edge_vectors(rods.state.x, m.edge_a, m.edge_b, m.edge_shift, np.zeros((ne, 3)), elen)
    tension = m.EA * (elen / m.rest_length - 1.0)
    EA = m.EA * factor
    return rods.replace_model(EA=EA, rest_length=elen / (1.0 + tension / EA),
                              stretch_damping=m.stretch_damping * np.sqrt(factor))
