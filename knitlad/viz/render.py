"""Pictures of a laddering run from its ``ladder.h5`` (or of one's own scene, from its trajectory file):
renders, a movie and a ParaView file.

* :func:`render_run`: the fabric at chosen instants (default: the knit just cut, then
  four evenly spaced instants of the ladder, as in the paper's figures), yarns drawn as
  shaded tubes of their real diameter coloured by course, the cut course in black and
  the undone cells shaded red; a front view (the x-y plane, as the photographs) and an
  oblique one. VTK renders off screen (EGL or OSMesa: no display, no GPU).
* :func:`movie`: every frame, front view with a time stamp, as MP4 (imageio-ffmpeg, whose
  wheel carries ffmpeg) or GIF.
The ParaView file (``ladder.xdmf``) is written by :func:`knitlad.io.xdmf.write_xdmf`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import h5py
import numpy as np

from knitlad.io.atomic import atomic_path

COURSE_COLOURS = np.array([[0.20, 0.45, 0.75], [0.95, 0.60, 0.15], [0.30, 0.65, 0.35], [0.60, 0.40, 0.70]])
CUT_COLOUR = (0.05, 0.05, 0.05)
LADDERED_COLOUR = (0.85, 0.15, 0.15)
BAND_COLOUR = (0.85, 0.65, 0.1)  # the run-stop band's courses (gold)


@dataclass
class Run:
    """What a picture needs from a run file (SI units): a laddering run, or the trajectory of one's own
    scene (:func:`knitlad.io.hdf5.write_trajectory`: no cells, each yarn its own colour)."""

    path: Path
    positions: h5py.Dataset  # (n_frames, n, 3) [m]
    times_s: np.ndarray
    laddered: np.ndarray  # (n_frames, n_y, n_x)
    edges: np.ndarray  # (ne, 2)
    node_course: np.ndarray
    cut_course: int
    cell_centres: np.ndarray  # (n_y, n_x, 2) [m]
    diameter: float
    l_x: float
    l_y: float
    knit: bool = True  # a laddering run (cells, courses, a cut), else a scene of one's own
    l0: float = 0.0  # the stitch length [m] (the scale bar)
    obstacles: dict | None = None  # a scene of one's own: kind, direction, radius [m], points (frames, k, 3) [m]
    band: tuple[int, ...] = ()  # the courses of a run-stop band (any kind), counted from the bottom

    def field(self, name: str, frame: int) -> np.ndarray:
        """Frame ``frame`` of the per-node dataset ``name`` of the open file (frames/velocities, frames/contact,
        fields/axial_strain); ValueError if the file has none."""
        f = self.positions.file
        if name not in f:
            raise ValueError(f"{self.path}: no {name} to colour by (a file of an older knitlad, or without frames)")
        return f[name][frame]

    @staticmethod
    def open(path: str | Path) -> tuple["Run", h5py.File]:
        from knitlad.io.kinds import is_trajectory

        f = h5py.File(path, "r")
        if is_trajectory(f) and "positions" in f.get("frames", {}):
            n = f["frames/positions"].shape[0]
            run = Run(Path(path), f["frames/positions"], f["frames/time"][()], np.zeros((n, 0, 0), dtype=bool),
                      f["topology/edges"][()], f["topology/node_course"][()], -1, np.zeros((0, 0, 2)),
                      float(f.attrs["scale_d_m"]), 0.0, 0.0, knit=False)
            if "obstacles" in f:
                g = f["obstacles"]
                run.obstacles = {"kind": g["kind"][()], "direction": g["direction"][()], "radius": g["radius"][()],
                                 "points": g["points"]}
            run.check(f)
            return run, f
        if "frames" not in f or "laddered" not in f["frames"]:
            f.close()
            raise ValueError(f"{path}: no frames to draw (the run was written without them, or by an older knitlad)")
        settings = json.loads(f.attrs["settings_json"])
        n_y = settings["stretch"]["n_y"]
        l0 = float(f.attrs["scale_l0_m"])
        run = Run(Path(path), f["frames/positions"], f["frames/time"][()], f["frames/laddered"][()],
                  f["topology/edges"][()], f["topology/node_course"][()], n_y // 2, f["cells/centres"][()],
                  float(f.attrs["scale_d_m"]), float(f.attrs["box_lx_over_l0"]) * l0,
                  float(f.attrs["ly_over_l0"]) * l0, l0=l0, band=band_courses(settings))
        run.check(f)
        return run, f

    def check(self, f) -> None:
        """ValueError (the file closed) if the arrays do not fit each other: an edge of a node the frames do not
        hold, or flattened, made VTK read outside its arrays (a segfault, or images from whatever memory held)."""
        problem = None
        positions, edges = self.positions, self.edges
        if positions.ndim != 3 or positions.shape[2] != 3 or positions.shape[0] == 0:
            problem = f"frames/positions has shape {positions.shape}, not (frames, nodes, 3)"
        elif edges.ndim != 2 or edges.shape[1] != 2 or not np.issubdtype(edges.dtype, np.integer):
            problem = f"topology/edges has shape {edges.shape} ({edges.dtype}), not (edges, 2) integers"
        elif edges.size and (edges.min() < 0 or edges.max() >= positions.shape[1]):
            problem = (f"topology/edges names nodes {edges.min()} to {edges.max()}, the frames hold "
                       f"{positions.shape[1]} nodes")
        elif len(self.times_s) != positions.shape[0] or len(self.node_course) != positions.shape[1]:
            problem = "frames/time or topology/node_course do not match the frames"
        elif self.knit and self.laddered.shape[0] != positions.shape[0]:
            problem = "frames/laddered does not match the frames"
        elif self.obstacles is not None and (self.obstacles["points"].shape[:2] != (positions.shape[0],
                                                                                   len(self.obstacles["kind"]))):
            problem = "obstacles/points does not match the frames and obstacles"
        if problem:
            f.close()
            raise ValueError(f"{self.path}: a damaged run file: {problem}")

    def cell_centres_at(self, frame: int) -> np.ndarray:
        """(n_y, n_x, 2) the cells' centres moved with their course's yarn at ``frame`` [m]: each cell by the mean
        displacement since the first frame of the nodes of its course that started nearest its centre."""
        n_y, n_x = self.cell_centres.shape[:2]
        course = self.node_course
        mine = np.flatnonzero((course >= 0) & (course < n_y))
        if frame == 0 or mine.size == 0:
            return self.cell_centres
        x0 = np.asarray(self.positions[0], dtype=float)[mine, :2]
        moved = np.asarray(self.positions[frame], dtype=float)[mine, :2] - x0
        rows = course[mine]
        columns = np.argmin(np.abs(x0[:, 0, None] - self.cell_centres[rows, :, 0]), axis=1)
        total, count = np.zeros((n_y, n_x, 2)), np.zeros((n_y, n_x))
        np.add.at(total, (rows, columns), moved)
        np.add.at(count, (rows, columns), 1.0)
        return self.cell_centres + total / np.maximum(count, 1.0)[..., None]

    def frame_at(self, t: float) -> int:
        return int(np.argmin(np.abs(self.times_s - t)))

    def label(self, k: int, since: str = " after the cut") -> str:
        """The caption of frame ``k``: its time, and for a laddering run the cells undone."""
        if not self.knit:
            return f"t = {self.times_s[k] * 1e3:.3f} ms"
        return f"t = {self.times_s[k] * 1e3:.3f} ms{since}, {int(self.laddered[k].sum())} cells undone"


def _quiet_vtk() -> None:
    """VTK's log off the terminal: with no display it warns "bad X server connection" before rendering off
    screen anyway, and its XDMF reader reports an element it skips as an error; knitlad says what failed."""
    from vtkmodules.vtkCommonCore import vtkLogger, vtkObject

    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    vtkObject.GlobalWarningDisplayOff()


def _vtk():
    _quiet_vtk()
    import vtkmodules.vtkFiltersCore  # noqa: F401 - tube filter
    import vtkmodules.vtkRenderingFreeType  # noqa: F401 - text
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 - the off-screen render window
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

    return vtkPoints, vtkCellArray, vtkPolyData, numpy_to_vtk, numpy_to_vtkIdTypeArray


COLOURINGS = ("course", "speed", "contact", "strain", "depth")  # what the tubes' colour shows (render --colour)
CONTACT_COLOURS = np.array([[0.75, 0.75, 0.75], [0.20, 0.45, 0.75], [0.85, 0.15, 0.15]])  # free, touching, sliding


def band_courses(settings: dict) -> tuple[int, ...]:
    """The courses of a run file's run-stop band, whatever it is (friction, memory, knitted), from its settings."""
    for where, name in (("dynamics", "friction_band"), ("stretch", "memory_band"), ("stretch", "pattern_band")):
        band = settings.get(where, {}).get(name)
        if band:
            first, courses = (band[1], band[2]) if name == "pattern_band" else (band[0], band[1])
            return tuple(range(int(first), int(first) + int(courses)))
    return ()


def local_depth(run: Run, x: np.ndarray) -> np.ndarray:
    """Each node's height out of the fabric's plane [m] over the fabric's own surface there: the mean height of
    patches of 2 x 2 stitches (a pattern's repeat of knit and purl: rib's two columns, garter's two courses),
    interpolated bilinearly between the patches' centres, so a curl or tilt of the fabric is not read as relief;
    a scene without cells: over its mean."""
    if not run.knit or run.l_x <= 0 or run.l_y <= 0:
        return x[:, 2] - np.nanmean(x[:, 2])
    size = 2.0 * np.array([run.l_x, run.l_y])
    origin = np.nanmin(x[:, :2], axis=0)
    patch = np.floor((x[:, :2] - origin) / size).astype(np.int64)
    shape = tuple(int(n) for n in patch.max(axis=0) + 1)
    key = patch[:, 0] * shape[1] + patch[:, 1]
    count = np.bincount(key, minlength=shape[0] * shape[1]).reshape(shape)
    mean = np.bincount(key, weights=x[:, 2], minlength=count.size).reshape(shape) / np.maximum(count, 1)
    mean[count == 0] = np.nan
    mean = np.where(np.isnan(mean), np.nanmean(mean, axis=0, keepdims=True), mean)  # an empty patch: its row's
    mean = np.where(np.isnan(mean), np.nanmean(mean), mean)

    def between(coordinate, n):  # the lower patch centre's index and the weight of the upper one (beyond the outer
        f = coordinate - 0.5  # centres: extrapolated, so a tilt leaves no residual at the knit's border)
        i = np.clip(np.floor(f).astype(np.int64), 0, max(n - 2, 0))
        return i, (f - i) if n > 1 else np.zeros_like(f)

    i, s = between((x[:, 0] - origin[0]) / size[0], shape[0])
    j, t = between((x[:, 1] - origin[1]) / size[1], shape[1])
    i1, j1 = np.minimum(i + 1, shape[0] - 1), np.minimum(j + 1, shape[1] - 1)
    surface = ((1 - s) * (1 - t) * mean[i, j] + s * (1 - t) * mean[i1, j] + (1 - s) * t * mean[i, j1]
               + s * t * mean[i1, j1])
    return x[:, 2] - surface


def node_colours(run: Run, frame: int, colouring: str) -> tuple[np.ndarray, str]:
    """(n, 3) colours in [0, 1] of the nodes at ``frame``, and the key that says what they mean: the course
    (four colours in turn, the held edge courses grey, the cut course black), the speed or the axial strain
    (viridis, from the lowest to the highest of the frame), or the contact state."""
    course = run.node_course
    if colouring == "course":
        colours = COURSE_COLOURS[np.mod(course, len(COURSE_COLOURS))]
        key = "colour: the course (four in turn)" if run.knit else "colour: the yarn (four colours in turn)"
        if run.knit:
            colours[(course < 0) | (course >= run.cell_centres.shape[0])] = 0.6  # the held edge courses: grey
            colours[course == run.cut_course] = CUT_COLOUR
            key += ", grey the held edge courses, black the cut course"
            if run.band:
                colours[np.isin(course, run.band)] = BAND_COLOUR
                key += f", gold the run-stop band (courses {run.band[0]} to {run.band[-1]})"
        return colours, key
    if colouring == "contact":
        state = np.asarray(run.field("frames/contact", frame), dtype=int)
        return CONTACT_COLOURS[np.clip(state, 0, 2)], "colour: grey free, blue touching another yarn, red sliding on it"
    import matplotlib

    if colouring == "depth":  # knit and purl apart in a front view: which yarn lies in front of which
        z = local_depth(run, np.asarray(run.positions[frame], dtype=float)) * 1e3
        reach = float(np.nanpercentile(np.abs(z), 98)) or 1.0
        colours = matplotlib.colormaps["viridis"](np.clip(0.5 + 0.5 * z / reach, 0.0, 1.0))[:, :3]
        return colours, (f"colour: depth against the fabric around, dark {-reach:.2g} mm (behind) to yellow "
                         f"{reach:.2g} mm (in front): a knit stitch shows its legs in front, a purl stitch its heads")
    if colouring == "speed":
        value = np.linalg.norm(run.field("frames/velocities", frame), axis=1)
        what, unit = "speed", "m/s"
    else:
        value = np.asarray(run.field("fields/axial_strain", frame), dtype=float)
        what, unit = "axial strain (tension / EA)", ""
    lo, hi = float(np.nanmin(value)), float(np.nanmax(value))
    scaled = (value - lo) / (hi - lo) if hi > lo else np.zeros_like(value)
    colours = matplotlib.colormaps["viridis"](scaled)[:, :3]
    return colours, f"colour: {what}, dark {lo:.3g} to yellow {hi:.3g} {unit}".rstrip()


def _fabric_actor(run: Run, x: np.ndarray, window: np.ndarray | None, colours: np.ndarray):
    """Tubes of the yarn's diameter along every edge (edges outside ``window`` [x0, x1, y0, y1] left out),
    coloured node by node (``colours``: :func:`node_colours`)."""
    from vtkmodules.vtkFiltersCore import vtkTubeFilter
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

    vtkPoints, vtkCellArray, vtkPolyData, numpy_to_vtk, numpy_to_vtkIdTypeArray = _vtk()
    edges = run.edges
    if window is not None:
        mid = 0.5 * (x[edges[:, 0]] + x[edges[:, 1]])
        inside = (mid[:, 0] > window[0]) & (mid[:, 0] < window[1]) & (mid[:, 1] > window[2]) & (mid[:, 1] < window[3])
        edges = edges[inside]
    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(x, dtype=np.float64), deep=True))
    cells = np.column_stack([np.full(len(edges), 2), edges]).astype(np.int64).ravel()
    lines = vtkCellArray()
    lines.ImportLegacyFormat(numpy_to_vtkIdTypeArray(cells, deep=True))  # (2, i, j) per edge
    poly = vtkPolyData()
    poly.SetPoints(points)
    poly.SetLines(lines)
    rgb = numpy_to_vtk((255 * colours).astype(np.uint8), deep=True)
    rgb.SetName("colour")
    poly.GetPointData().SetScalars(rgb)
    tubes = vtkTubeFilter()
    tubes.SetInputData(poly)
    tubes.SetRadius(0.5 * run.diameter)
    tubes.SetNumberOfSides(6)
    tubes.CappingOn()
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(tubes.GetOutputPort())
    mapper.SetColorModeToDirectScalars()
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetSpecular(0.3)
    return actor


def _cell_actor(run: Run, laddered: np.ndarray, depth: float, centres: np.ndarray):
    """Red squares behind the undone cells, about ``centres`` ((n_y, n_x, 2) [m])."""
    from vtkmodules.vtkFiltersSources import vtkPlaneSource
    from vtkmodules.vtkFiltersCore import vtkAppendPolyData
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

    append = vtkAppendPolyData()
    for r, i in zip(*np.nonzero(laddered)):
        cx, cy = centres[r, i]
        plane = vtkPlaneSource()
        plane.SetOrigin(cx - 0.5 * run.l_x, cy - 0.5 * run.l_y, depth)
        plane.SetPoint1(cx + 0.5 * run.l_x, cy - 0.5 * run.l_y, depth)
        plane.SetPoint2(cx - 0.5 * run.l_x, cy + 0.5 * run.l_y, depth)
        plane.Update()
        append.AddInputData(plane.GetOutput())
    if not laddered.any():
        return None
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(append.GetOutputPort())
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(*LADDERED_COLOUR)
    actor.GetProperty().SetOpacity(0.35)
    actor.GetProperty().LightingOff()
    return actor


OBSTACLE_COLOUR = (0.55, 0.6, 0.65)


def _obstacle_actors(run: Run, frame: int, x: np.ndarray) -> list:
    """The obstacles of a scene of one's own at ``frame``, translucent grey: a plane as a square about the yarns'
    centre, 1.4 x their extent; a cylinder of its radius, as long as the yarns' extent along its axis and more."""
    from vtkmodules.vtkFiltersSources import vtkCylinderSource, vtkPlaneSource
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper
    from vtkmodules.vtkCommonTransforms import vtkTransform

    o = run.obstacles
    centre = np.nanmean(x, axis=0)
    extent = float(np.nanmax(np.ptp(x, axis=0))) + 4 * run.diameter
    actors = []
    for k, kind in enumerate(o["kind"]):
        point, direction = np.asarray(o["points"][frame, k], dtype=float), np.asarray(o["direction"][k], dtype=float)
        along = centre - point
        if kind == 0:  # the plane's point nearest the yarns' centre
            source = vtkPlaneSource()
            middle = centre - np.dot(along, direction) * direction
            u = np.cross(direction, [1.0, 0.0, 0.0] if abs(direction[0]) < 0.9 else [0.0, 1.0, 0.0])
            u /= np.linalg.norm(u)
            w = np.cross(direction, u)
            half = 0.7 * extent
            source.SetOrigin(*(middle - half * u - half * w))
            source.SetPoint1(*(middle + half * u - half * w))
            source.SetPoint2(*(middle - half * u + half * w))
            mapper = vtkPolyDataMapper()
            mapper.SetInputConnection(source.GetOutputPort())
        else:  # VTK's cylinder stands along y through the origin: turned onto the axis and moved
            length = float(np.ptp(x @ direction)) + 2 * float(o["radius"][k]) + 4 * run.diameter
            source = vtkCylinderSource()
            source.SetRadius(float(o["radius"][k]))
            source.SetHeight(length)
            source.SetResolution(48)
            middle = point + np.dot(along, direction) * direction
            turn = np.cross([0.0, 1.0, 0.0], direction)
            angle = np.degrees(np.arctan2(np.linalg.norm(turn), direction[1]))
            transform = vtkTransform()
            transform.Translate(*middle)
            if np.linalg.norm(turn) > 1e-12:
                transform.RotateWXYZ(angle, *turn)
            elif direction[1] < 0:
                transform.RotateWXYZ(180.0, 1.0, 0.0, 0.0)
            mapper = vtkPolyDataMapper()
            mapper.SetInputConnection(source.GetOutputPort())
        actor = vtkActor()
        actor.SetMapper(mapper)
        if kind != 0:
            actor.SetUserTransform(transform)
        actor.GetProperty().SetColor(*OBSTACLE_COLOUR)
        actor.GetProperty().SetOpacity(0.35)
        actors.append(actor)
    return actors


def _text(renderer, text: str, x: int, y: int, size: int, top: bool = False) -> None:
    from vtkmodules.vtkRenderingCore import vtkTextActor

    actor = vtkTextActor()
    actor.SetInput(text)
    actor.GetTextProperty().SetFontSize(size)
    actor.GetTextProperty().SetColor(0.0, 0.0, 0.0)
    if top:
        actor.GetTextProperty().SetVerticalJustificationToTop()
        actor.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        actor.SetPosition(0.01, 0.99)
    else:
        actor.SetPosition(x, y)
    renderer.AddViewProp(actor)


def _scale_bar(renderer, x: np.ndarray, length: float, label: str) -> None:
    """A black bar of ``length`` [m] above the fabric's upper right corner, with its length written above it
    (above: the time stamp sits in the lower left corner)."""
    from vtkmodules.vtkFiltersSources import vtkLineSource
    from vtkmodules.vtkRenderingCore import vtkActor, vtkBillboardTextActor3D, vtkPolyDataMapper

    x1, y1, z = float(np.nanmax(x[:, 0])), float(np.nanmax(x[:, 1])), float(np.nanmax(x[:, 2]))
    y = y1 + 0.03 * max(y1 - float(np.nanmin(x[:, 1])), float(np.ptp(x[:, 0])))
    line = vtkLineSource()
    line.SetPoint1(x1 - length, y, z)
    line.SetPoint2(x1, y, z)
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(line.GetOutputPort())
    bar = vtkActor()
    bar.SetMapper(mapper)
    bar.GetProperty().SetColor(0, 0, 0)
    bar.GetProperty().SetLineWidth(4)
    renderer.AddActor(bar)
    text = vtkBillboardTextActor3D()
    text.SetInput(label)
    text.SetPosition(x1 - length, y, z)
    text.GetTextProperty().SetFontSize(18)
    text.GetTextProperty().SetColor(0, 0, 0)
    text.GetTextProperty().SetVerticalJustificationToBottom()
    renderer.AddViewProp(text)


def _scene(run: Run, frame: int, view: str, window=None, label: str = "", colouring: str = "course"):
    """A renderer of ``frame``: the yarn as tubes, the undone cells, the obstacles, the key, the caption, the scale
    bar (front view) and the camera."""
    from vtkmodules.vtkRenderingCore import vtkRenderer

    _vtk()  # the OpenGL and FreeType overrides must be registered before any renderer is made
    x = np.asarray(run.positions[frame], dtype=np.float64)
    renderer = vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    colours, key = node_colours(run, frame, colouring)
    renderer.AddActor(_fabric_actor(run, x, window, colours))
    cells = _cell_actor(run, run.laddered[frame], float(x[:, 2].min()) - 2 * run.diameter, run.cell_centres_at(frame))
    if cells is not None:
        renderer.AddActor(cells)
        key += "; red squares: cells undone, moved with their course's yarn"
    if run.obstacles is not None and len(run.obstacles["kind"]):
        for actor in _obstacle_actors(run, frame, x):
            renderer.AddActor(actor)
        key += "; grey: the obstacles"
    return renderer, x, key


def _draw(win, run: Run, frame: int, view: str, window=None, label: str = "", colouring: str = "course"):
    """Render ``frame`` into the off-screen window ``win`` (its size set) and return its pixels, (h, w, 3) uint8."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

    renderer, x, key = _scene(run, frame, view, window, label, colouring)
    width = win.GetSize()[0]
    _text(renderer, key, 0, 0, max(11, width // 90), top=True)
    if label:
        _text(renderer, label, 12, 12, 22)
    if view == "front":  # lengths read off a parallel projection: a bar of one stitch length, or of 1 mm
        l0 = run.l0 if run.knit else 1e-3
        _scale_bar(renderer, x, l0, f"l0 = {l0 * 1e3:.2f} mm" if run.knit else "1 mm")
    camera = renderer.GetActiveCamera()
    if view == "front":
        camera.ParallelProjectionOn()
        camera.SetViewUp(0, 1, 0)
    else:  # from below and the side: the fabric's relief, the loops standing out of its plane
        camera.Elevation(-60)
        camera.Azimuth(40)
        camera.SetViewUp(0, 1, 0.3)
    renderer.ResetCamera()
    if view == "front":
        camera.Zoom(1.15)
    renderers = win.GetRenderers()
    while renderers.GetNumberOfItems():  # the last frame's scene out, this one's in
        win.RemoveRenderer(renderers.GetFirstRenderer())
    win.AddRenderer(renderer)
    win.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.ShouldRerenderOff()  # the window was just rendered: read its pixels, do not draw them a second time
    grab.ReadFrontBufferOff()
    grab.Update()
    image = grab.GetOutput()
    w, h, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3]
    return np.ascontiguousarray(pixels)


def _window(size):
    """An off-screen render window of ``size`` (width, height)."""
    from vtkmodules.vtkRenderingCore import vtkRenderWindow

    _vtk()
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(*size)
    return win


def _picture(run: Run, frame: int, path: Path, view: str, size=(1200, 900), window=None, label: str = "",
             colouring: str = "course") -> Path:
    """``frame`` drawn as a PNG at ``path`` (:func:`_draw`), written whole or not at all."""
    import imageio.v2 as imageio

    win = _window(size)
    try:
        pixels = _draw(win, run, frame, view, window, label, colouring)
    finally:
        win.Finalize()
    with atomic_path(path, suffix=".png") as tmp:
        imageio.imwrite(tmp, pixels, format="png")
        whole_png(tmp)
    return path


PNG_END = b"IEND\xaeB`\x82"  # the last chunk of every complete PNG


def whole_png(path: Path) -> None:
    """OSError unless ``path`` is a complete PNG: VTK's writer only prints libpng's errors (a full disk
    left truncated images that were renamed into place and reported written)."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            f.seek(max(size - len(PNG_END), 0))
            end = f.read()
    except OSError as e:
        raise OSError(f"{path.name}: the image was not written ({e.strerror or e})") from None
    if size < 64 or end != PNG_END:
        raise OSError(f"{path.name}: the image was not written whole ({size} bytes; a full disk?)")


def default_instants(run: Run) -> list[float]:
    """The first frame (a laddering run: the knit just cut), then four evenly spaced instants to the last."""
    t0, t_end = float(run.times_s[0]), float(run.times_s[-1])
    return [t0 + (t_end - t0) * k / 4 for k in range(5)]


def render_run(h5: str | Path, out_dir: str | Path, times_s: list[float] | None = None,
               views: tuple[str, ...] = ("front", "oblique"), size=(1200, 900),
               progress: Callable[[int, int], None] | None = None, colouring: str = "course") -> list[Path]:
    """PNGs of the fabric at ``times_s`` [s since the cut] (default :func:`default_instants`), coloured by
    ``colouring`` (:data:`COLOURINGS`). ``progress(done, total)`` is called after each image."""
    run, f = Run.open(h5)
    out = Path(out_dir)
    paths = []
    try:
        instants = times_s if times_s is not None else default_instants(run)
        frames = list(dict.fromkeys(run.frame_at(t) for t in instants))  # each stored frame once
        for k in frames:
            label = run.label(k)
            for view in views:
                paths.append(_picture(run, k, out / f"render_{view}_{run.times_s[k] * 1e6:08.1f}us.png", view,
                                      size, label=label, colouring=colouring))
                if progress:
                    progress(len(paths), len(frames) * len(views))
    finally:
        f.close()
    return paths


def movie(h5: str | Path, path: str | Path, fps: int = 12, size=(960, 720),
          progress: Callable[[int, int], None] | None = None, colouring: str = "course") -> Path:
    """Every frame of the run, front view with a time stamp, as MP4 (or GIF if ``path`` ends so), coloured by
    ``colouring``. ``progress(done, total)`` is called after each frame."""
    import io

    import imageio.v2 as imageio

    run, f = Run.open(h5)
    path = Path(path)
    try:
        win = _window(size)  # one window for every frame: a new one costs an OpenGL context each
        with atomic_path(path, suffix=path.suffix) as out:
            kwargs = dict(fps=fps, macro_block_size=8) if path.suffix == ".mp4" else dict(duration=1 / fps)
            # a GIF is made in memory and written in one go: a write that fails (a full disk) then fails once, here,
            # not again in the writer's finaliser
            gif = io.BytesIO() if path.suffix == ".gif" else None
            with imageio.get_writer(gif if gif is not None else out, format=path.suffix[1:].upper() if gif else None,
                                    **kwargs) as writer:
                for k in range(len(run.times_s)):
                    writer.append_data(_draw(win, run, k, "front", label=run.label(k, since=""), colouring=colouring))
                    if progress:
                        progress(k + 1, len(run.times_s))
            if gif is not None:
                Path(out).write_bytes(gif.getvalue())
        win.Finalize()
    finally:
        f.close()
    return path
