"""Pictures of a run: renders (off screen), a movie, the ParaView file read back by VTK, the midline diagram."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from tests.conftest import knitlad

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "cut"
    p = knitlad("cut", "--stitches", "6x8", "--lx", "0.40",
                        "--preset", "fast", "--resolution", "16", "--max-time-ms", "0.3", "--out", str(out))
    assert p.returncode == 0, p.stderr
    return out


def test_a_render_shows_the_fabric_as_tubes_with_the_cut_course_marked(run_folder):
    import imageio.v2 as imageio

    from knitlad.viz.render import render_run

    paths = render_run(run_folder / "ladder.h5", run_folder / "render", [0.0, 0.2e-3], ("front", "oblique"), (320, 240))
    assert len(paths) == 4
    for path in paths:
        image = imageio.imread(path)[..., :3].astype(int)
        assert image.shape == (240, 320, 3)
        drawn = (image < 235).any(axis=2)
        assert 0.02 < drawn.mean() < 0.9  # a fabric, not a blank or a filled frame
        assert (image.max(axis=2) < 60).sum() > 20  # the cut course, drawn black
        assert len({tuple(c) for c in image[drawn][::7]}) > 20  # shaded tubes, several courses' colours


def test_the_first_frame_is_the_knit_just_cut_and_the_last_the_stop(run_folder):
    with h5py.File(run_folder / "ladder.h5", "r") as f:
        t = f["frames/time"][()]
        assert t[0] == 0.0 and t[-1] == pytest.approx(f["series/time"][-1])
        assert f["frames/velocities"].shape == f["frames/positions"].shape
        assert not f["frames/laddered"][0].any()


def test_a_movie_has_every_frame(run_folder):
    import imageio.v2 as imageio

    from knitlad.viz.render import movie

    seen = []
    path = movie(run_folder / "ladder.h5", run_folder / "ladder.gif", size=(160, 120),
                 progress=lambda done, total: seen.append((done, total)))
    with h5py.File(run_folder / "ladder.h5", "r") as f:
        n = f["frames/time"].shape[0]
    assert len(imageio.mimread(path)) == n
    assert seen == [(k, n) for k in range(1, n + 1)]  # the progress line's count, frame by frame


@pytest.mark.end_to_end
def test_movie_and_render_show_their_progress_in_a_log(run_folder):
    """Off a terminal (a batch job's log) each prints a progress line that ends at the whole count."""
    for command in (["movie", "--gif", "--width", "96"], ["render", "--width", "96", "--view", "front"]):
        p = knitlad(command[0], str(run_folder), *command[1:])
        assert p.returncode == 0, p.stderr
        last = p.stderr.strip().splitlines()[-1]
        done, total = last.split("]")[1].split()[0].split("/")
        assert last.startswith(command[0]) and done == total and int(total) >= 5, p.stderr


def test_paraview_opens_the_trajectory_with_its_fields(run_folder):
    """The XDMF written by knitlad cut, read with VTK's own reader: one step per frame, the nodes
    and edges of the knit, and the per-node fields, the velocity equal to the stored one."""
    import vtk
    from vtkmodules.util.numpy_support import vtk_to_numpy

    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(run_folder / "ladder.xdmf"))
    reader.UpdateInformation()
    steps = reader.GetOutputInformation(0).Get(vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    with h5py.File(run_folder / "ladder.h5", "r") as f:
        times = f["frames/time"][()]
        velocity = f["frames/velocities"][2]
        n_nodes, n_edges = f["frames/positions"].shape[1], f["topology/edges"].shape[0]
        positions = f["frames/positions"][2]
    assert np.allclose(steps, times)
    reader.UpdateTimeStep(steps[2])
    grid = reader.GetOutputDataObject(0)
    assert grid.GetNumberOfPoints() == n_nodes and grid.GetNumberOfCells() == n_edges
    data = grid.GetPointData()
    contact_name = "contact (0 free, 1 touching, 2 sliding)"  # the codes said where ParaView lists the array
    assert {data.GetArrayName(i) for i in range(data.GetNumberOfArrays())} >= {"course", "velocity", "axial_strain",
                                                                               "curvature", contact_name}
    contact = vtk_to_numpy(data.GetArray(contact_name))
    assert set(np.unique(contact)) <= {0, 1, 2} and (contact > 0).mean() > 0.2  # a knit: most nodes touch
    assert np.allclose(vtk_to_numpy(data.GetArray("velocity")), velocity)
    assert np.allclose(vtk_to_numpy(grid.GetPoints().GetData()), positions)


@pytest.mark.end_to_end
def test_plot_of_a_run_folder_draws_its_diagrams_and_renders(run_folder):
    p = knitlad("plot", str(run_folder))
    assert p.returncode == 0, p.stderr
    assert (run_folder / "midline_diagram.png").stat().st_size > 5000
    assert (run_folder / "tension_history.png").stat().st_size > 5000
    with h5py.File(run_folder / "ladder.h5", "r") as f:  # the stretch's readings end at f_x^ini
        assert f["stretch/fx"][-1] == pytest.approx(f.attrs["fx_ini"], rel=0.05)
    assert len(list((run_folder / "render").glob("render_front_*.png"))) >= 5


def test_render_of_a_folder_without_a_run_is_one_line(tmp_path):
    p = knitlad("render", str(tmp_path))
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "no ladder.h5" in p.stderr


def _damaged(run_folder, tmp_path, how: str) -> Path:
    import shutil

    path = tmp_path / "ladder.h5"
    shutil.copy(run_folder / "ladder.h5", path)
    if how == "truncated":
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "checksum":
        with h5py.File(path, "r") as f:
            dataset = f["frames/positions"].id
            offset = dataset.get_offset() if dataset.get_offset() is not None else \
                dataset.get_chunk_info(0).byte_offset + 8
        data = bytearray(path.read_bytes())
        data[offset] ^= 0xFF  # one byte of a checksummed dataset
        path.write_bytes(bytes(data))
    elif how == "no dataset":
        with h5py.File(path, "r+") as f:
            del f["topology/edges"]
    elif how == "no attribute":
        with h5py.File(path, "r+") as f:
            del f.attrs["scale_l0_m"]
    elif how == "short laddered":
        with h5py.File(path, "r+") as f:
            laddered = f["frames/laddered"][()][:-1]
            del f["frames/laddered"]
            f["frames/laddered"] = laddered
    elif how == "no frame":
        with h5py.File(path, "r+") as f:
            for name in ("positions", "time", "laddered"):
                shape = f[f"frames/{name}"].shape
                dtype = f[f"frames/{name}"].dtype
                del f[f"frames/{name}"]
                f.create_dataset(f"frames/{name}", shape=(0, *shape[1:]), dtype=dtype)
    return path


@pytest.mark.parametrize("how", ["truncated", "empty", "checksum", "no dataset", "no attribute", "short laddered",
                                 "no frame"])
@pytest.mark.parametrize("command", ["render", "movie", "plot"])
def test_a_damaged_run_file_is_one_line_and_exit_2_for_every_picture(run_folder, tmp_path, how, command):
    """Each of these ended in a traceback (a KeyError, an IndexError, a FileNotFoundError of the movie's gif)."""
    path = _damaged(run_folder, tmp_path, how)
    p = knitlad(command, str(path.parent))
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert str(path) in p.stderr


def _file_size_limit(limit: int):
    import resource

    return lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


def test_a_render_that_runs_out_of_room_says_so_and_leaves_no_broken_image(run_folder, tmp_path):
    """On a full disk VTK printed libpng's errors, renamed the truncated PNGs into place and said 'wrote 10 images'."""
    import shutil

    folder = tmp_path / "run"
    shutil.copytree(run_folder, folder, ignore=shutil.ignore_patterns("render", "*.mp4", "*.gif"))
    p = knitlad("render", str(folder), "--width", "640", preexec_fn=_file_size_limit(20_000))
    assert p.returncode == 1, p.stderr
    assert "render stopped" in p.stderr and "Traceback" not in p.stderr
    for png in (folder / "render").glob("*.png"):
        assert png.read_bytes().endswith(b"IEND\xaeB`\x82"), png
    assert not list((folder / "render").glob("*.tmp*"))


@pytest.mark.process
def test_a_cut_that_cannot_write_its_files_keeps_its_summary(tmp_path):
    """A file-size limit under ladder.h5's size: it was about 20 tracebacks of h5py and a segmentation fault."""
    out = tmp_path / "out"
    p = knitlad("cut", "--stitches", "6x8", "--lx", "0.40", "--preset",
                        "fast", "--resolution", "16", "--max-time-ms", "0.3", "--out", str(out), preexec_fn=_file_size_limit(100_000))
    assert p.returncode == 1, p.stderr
    assert "could not be written" in p.stderr.strip().splitlines()[-1] and "Traceback" not in p.stderr
    assert json.loads((out / "summary.json").read_text())["n_lad"] >= 0
    assert sorted(f.name for f in out.iterdir()) == ["summary.json"]


def test_every_dataset_of_a_run_file_carries_its_unit(run_folder):
    """Units were written only in a docstring."""
    from knitlad.io.hdf5 import RUN_UNITS

    missing = []
    with h5py.File(run_folder / "ladder.h5", "r") as f:
        f.visititems(lambda name, obj: missing.append(name) if isinstance(obj, h5py.Dataset) and
                     obj.attrs.get("unit") not in RUN_UNITS.values() else None)
        assert f["frames/positions"].attrs["unit"] == "m" and f["series/fx"].attrs["unit"] == "f0"
        assert f.attrs["knitlad_code"]
    assert not missing, missing


@pytest.mark.process
def test_a_render_without_a_display_prints_no_vtk_noise(run_folder, tmp_path):
    """With no X display VTK printed a coloured 'WARN| bad X server connection' before every render."""
    import os
    import shutil

    folder = tmp_path / "run"
    shutil.copytree(run_folder, folder, ignore=shutil.ignore_patterns("render", "*.mp4", "*.gif"))
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    p = knitlad("render", str(folder), "--width", "160", "--view", "front", env=env)
    noise = [line for line in p.stderr.splitlines() if not line.startswith("render [")]  # its progress line
    assert p.returncode == 0 and not noise, p.stderr


def test_a_scene_of_one_s_own_renders_and_films_from_its_trajectory_file(tmp_path):
    """A cantilever let go, recorded and written by the public API, drawn by `knitlad render` and `movie`."""
    import imageio.v2 as imageio

    import knitlad as kl

    s = np.linspace(0.0, 0.02, 21)
    scene = kl.Scene(kl.NYLON)
    rod = scene.add_yarn(np.column_stack([s, 0 * s, 0 * s]), start=np.column_stack([s, 2e-3 * (s / 0.02) ** 2, 0 * s]))
    scene.hold(rod, [0, 1])
    recorder = kl.TrajectoryRecorder()
    kl.Simulation(scene.build()).run(1e-3, observe=recorder, observe_every_s=2.5e-4)
    path = kl.write_trajectory(tmp_path / "mine.h5", recorder)
    p = knitlad("render", str(path), "--view", "front", "--width", "160")
    assert p.returncode == 0, p.stderr
    pictures = sorted((tmp_path / "mine_render").glob("render_front_*.png"))  # beside the file, its own folder
    # five evenly spaced instants from the first frame to the last, each frame drawn once
    assert 3 <= len(pictures) <= 5
    assert [f"{t * 1e6:08.1f}us" in q.name for t, q in zip(recorder.times[::len(recorder.times) - 1],
                                                          pictures[::len(pictures) - 1])] == [True, True]
    first, last = (imageio.imread(q)[..., :3].astype(int) for q in (pictures[0], pictures[-1]))
    assert (first < 200).any(axis=2).mean() > 0.002  # the rod is drawn
    assert np.abs(first - last).sum() > 0  # and it moved
    p = knitlad("movie", str(path), "--gif", "--width", "96")
    assert p.returncode == 0, p.stderr
    assert len(imageio.mimread(tmp_path / "mine.gif")) == len(recorder.times)


def test_the_contact_pairs_of_one_s_own_scene_open_in_paraview_as_points_with_their_forces(tmp_path):
    """A yarn dragged over two crossing yarns (examples/coulomb_slide.py's scene), recorded: VTK's XDMF reader
    gives, beside the yarns, a "contacts" grid per frame whose points are the touching pairs' contact points
    and whose normal and friction forces are the ones Simulation.contact_pairs gave at that frame."""
    import vtk
    from vtkmodules.util.numpy_support import vtk_to_numpy

    import knitlad as kl

    d = kl.NYLON.diameter
    t = np.linspace(-10 * d, 10 * d, 21)
    scene = kl.Scene(kl.NYLON)
    dragged = scene.add_yarn(np.column_stack([t, 0 * t, np.full_like(t, 0.8 * d)]))
    scene.hold(dragged, range(t.size), velocity=(1.0, 0.0, 0.0))
    for x0 in (-3 * d, 3 * d):
        scene.hold(scene.add_yarn(np.column_stack([np.full_like(t, x0), t, 0 * t])), range(t.size))
    sim = kl.Simulation(scene.build(), contact=kl.ContactModel(stiffness=1e3, mu=0.4), dt_s=1e-6)
    recorder = kl.TrajectoryRecorder()
    sim.run(4e-5, observe=recorder, observe_every_s=1e-5)
    path = kl.write_trajectory(tmp_path / "slide.h5", recorder)
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(path.with_suffix(".xdmf")))
    reader.UpdateInformation()
    k = len(recorder.times) - 1
    reader.UpdateTimeStep(recorder.times[k])
    blocks = reader.GetOutputDataObject(0)
    names = [blocks.GetMetaData(i).Get(vtk.vtkCompositeDataSet.NAME()) for i in range(blocks.GetNumberOfBlocks())]
    contacts = blocks.GetBlock(names.index("contacts"))
    pairs = recorder.pairs[k]
    assert contacts.GetNumberOfPoints() == len(pairs.overlap_m) == 2
    np.testing.assert_allclose(vtk_to_numpy(contacts.GetPoints().GetData()), pairs.points_m, rtol=1e-6)
    data = contacts.GetPointData()
    np.testing.assert_allclose(vtk_to_numpy(data.GetArray("normal_force")), pairs.normal_N, rtol=1e-5)
    np.testing.assert_allclose(vtk_to_numpy(data.GetArray("friction_force")), pairs.friction_N, rtol=1e-5)
    assert vtk_to_numpy(data.GetArray("sliding")).tolist() == pairs.sliding.astype(int).tolist()
    yarns = blocks.GetBlock(names.index("yarns"))
    assert yarns.GetNumberOfPoints() == 63


@pytest.mark.parametrize("damage", ["edges out of range", "edges flattened", "fewer positions"])
def test_a_damaged_run_file_is_refused_in_one_line_not_drawn_from_stray_memory(run_folder, tmp_path, damage):
    """Edges out of range or flattened segfaulted `render` and `movie`; fewer positions than the edges name gave
    images from out-of-bounds reads, exit 0."""
    import shutil

    import h5py

    folder = tmp_path / "run"
    shutil.copytree(run_folder, folder, ignore=shutil.ignore_patterns("render", "*.mp4", "*.gif"))
    with h5py.File(folder / "ladder.h5", "r+") as f:
        if damage == "fewer positions":
            kept = f["frames/positions"][:, :-10]
            del f["frames/positions"]
            f["frames/positions"] = kept
        else:
            edges = f["topology/edges"][()]
            del f["topology/edges"]
            f["topology/edges"] = edges + 10 ** 6 if damage == "edges out of range" else edges.ravel()
    for command in ("render", "movie"):
        p = knitlad(command, str(folder))
        assert p.returncode == 2, (command, p.returncode, p.stderr)
        assert "a damaged run file" in p.stderr.strip().splitlines()[-1] and "Traceback" not in p.stderr
    assert not list((folder / "render").glob("*.png")) if (folder / "render").exists() else True


@pytest.mark.parametrize("args, says", [(["--width", "1000000"], "--width: 64 to 8192"),
                                        (["--at-ms", "nan"], "--at-ms: finite"),
                                        (["--colour", "rainbow"], "--colour: one of course, speed")])
def test_render_refuses_a_width_no_memory_holds_and_a_nan_instant(run_folder, args, says):
    """`--width 1000000` aborted with std::bad_alloc; `--at-ms nan` drew an image and exited 0."""
    p = knitlad("render", str(run_folder), *args)
    assert p.returncode == 2 and says in p.stderr and "Traceback" not in p.stderr, p.stderr


@pytest.mark.end_to_end
def test_two_job_files_of_one_folder_render_into_folders_of_their_own(run_folder, tmp_path):
    """Rendering two job files of one sweep wrote both into jobs/render/, the second's frames over the first's;
    `render` had no --out."""
    import shutil

    jobs = tmp_path / "jobs"
    jobs.mkdir()
    for name in ("a.h5", "b.h5"):
        shutil.copy(run_folder / "ladder.h5", jobs / name)
        p = knitlad("render", str(jobs / name), "--view", "front",
                            "--width", "320")
        assert p.returncode == 0, p.stderr
    assert list((jobs / "a_render").glob("*.png")) and list((jobs / "b_render").glob("*.png"))
    assert not (jobs / "render").exists()
    p = knitlad("render", str(jobs / "a.h5"), "--view", "front", "--width",
                        "320", "--out", str(tmp_path / "mine"))
    assert p.returncode == 0 and list((tmp_path / "mine").glob("*.png"))


def test_a_run_records_when_where_and_with_what_it_ran(run_folder):
    """The HDF5 had no timestamp, host, or numpy/numba/python versions, and there was no plain run.log with the
    command line."""
    import h5py

    with h5py.File(run_folder / "ladder.h5") as f:
        for key in ("created_utc", "host", "python", "numpy", "numba", "h5py", "code"):
            assert f.attrs[f"provenance_{key}"], key
    log = (run_folder / "run.log").read_text()
    assert log.startswith("command: knitlad cut --stitches 6x8") and "numba: " in log and "summary: {" in log


@pytest.mark.end_to_end
def test_plot_of_a_run_file_without_its_stretch_says_so_and_draws_the_rest(run_folder, tmp_path):
    """`knitlad plot` on a run whose ladder.h5 lacked /stretch ended in a KeyError traceback."""
    import shutil

    import h5py

    folder = tmp_path / "run"
    shutil.copytree(run_folder, folder, ignore=shutil.ignore_patterns("render", "*.mp4", "*.gif", "*.png"))
    with h5py.File(folder / "ladder.h5", "r+") as f:
        del f["stretch"]
    p = knitlad("plot", str(folder))
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    assert "no tension_history.png" in p.stderr and "stretch" in p.stderr
    assert (folder / "spatio_temporal.png").exists() and (folder / "energy.png").exists()


def test_a_gif_on_a_full_disk_is_one_line_not_two_ignored_tracebacks(run_folder, tmp_path):
    import shutil

    folder = tmp_path / "run"
    shutil.copytree(run_folder, folder, ignore=shutil.ignore_patterns("render", "*.mp4", "*.gif"))
    p = knitlad("movie", str(folder), "--gif", "--width", "320", preexec_fn=_file_size_limit(20_000))
    assert p.returncode == 1 and "Exception ignored" not in p.stderr and "Traceback" not in p.stderr, p.stderr
    assert "movie not written" in p.stderr.strip().splitlines()[-1] and not list(folder.glob("*.gif*"))


def test_the_paraview_file_reads_without_an_error_in_the_log(run_folder):
    """Every XDMF read logged `ERR| vtkXdmfReader: Cannot find DataItem element in geometry xml`."""
    code = ("from vtkmodules.vtkIOXdmf2 import vtkXdmfReader\n"
            f"r = vtkXdmfReader(); r.SetFileName({str(run_folder / 'ladder.xdmf')!r}); r.Update()\n"
            "o = r.GetOutputDataObject(0); print(o.GetNumberOfCells(), o.GetNumberOfPoints())\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0 and "ERR" not in p.stderr, p.stderr
    cells, points = map(int, p.stdout.split())
    import h5py

    with h5py.File(run_folder / "ladder.h5") as f:  # the contact codes said beside the data too
        assert f["frames/contact"].attrs["meaning"].startswith("0 free, 1 touching")
    assert cells > 0 and points > cells


@pytest.mark.parametrize("colouring", ["speed", "contact", "strain"])
def test_a_render_colours_the_yarn_by_what_was_asked_and_says_so(run_folder, tmp_path, colouring):
    """The colour key is written on the image and the colours follow the stored field, frame by frame."""
    import imageio.v2 as imageio

    from knitlad.viz.render import Run, node_colours, render_run

    run, f = Run.open(run_folder / "ladder.h5")
    try:
        last = len(run.times_s) - 1
        colours, key = node_colours(run, last, colouring)
        assert colours.shape == (run.positions.shape[1], 3) and np.all((0 <= colours) & (colours <= 1))
        assert key.startswith("colour: ")
        if colouring == "speed":  # the fastest node is drawn yellow, the slowest dark
            speed = np.linalg.norm(f["frames/velocities"][last], axis=1)
            assert colours[np.argmax(speed)].sum() > colours[np.argmin(speed)].sum() + 0.5
        if colouring == "contact":  # as many colours as contact states in the frame
            states = set(np.clip(f["frames/contact"][last], 0, 2).tolist())
            assert len({tuple(c) for c in colours}) == len(states)
    finally:
        f.close()
    paths = render_run(run_folder / "ladder.h5", tmp_path, [0.2e-3], ("front",), (320, 240), colouring=colouring)
    image = imageio.imread(paths[0])[..., :3].astype(int)
    assert ((image < 235).any(axis=2)).mean() > 0.02


def test_a_front_render_carries_a_scale_bar_of_one_stitch_length(run_folder, tmp_path):
    """The bar over the fabric is as long, in pixels, as l0 is in the parallel projection, measured against
    the fabric's drawn width."""
    import imageio.v2 as imageio

    from knitlad.viz.render import Run, render_run

    path = render_run(run_folder / "ladder.h5", tmp_path, [0.0], ("front",), (640, 480))[0]
    run, f = Run.open(run_folder / "ladder.h5")
    x = f["frames/positions"][0]
    f.close()
    image = imageio.imread(path)[..., :3].astype(int)
    drawn = (image < 235).any(axis=2)
    middle = np.flatnonzero(drawn[160:320].any(axis=0))  # the fabric's columns, clear of the texts
    metres_per_pixel = (x[:, 0].max() - x[:, 0].min()) / (middle.max() - middle.min() + 1)

    def longest_run(row):
        best = n = 0
        for b in row:
            n = n + 1 if b else 0
            best = max(best, n)
        return best

    black = image.max(axis=2) < 40
    bar = max(longest_run(row) for row in black[: 480 // 6])
    assert bar * metres_per_pixel == pytest.approx(run.l0, rel=0.05)


def test_the_obstacles_of_one_s_own_scene_are_stored_and_drawn(tmp_path):
    """A yarn pushed onto a cylinder under a plate coming down: the file keeps each obstacle's shape and where it
    was at each frame (with units), and a render draws them (more of the picture covered than without them)."""
    import imageio.v2 as imageio

    import knitlad as kl
    from knitlad.viz.render import render_run

    s = np.linspace(-6e-3, 6e-3, 49)
    scene = kl.Scene(kl.NYLON)
    yarn = scene.add_yarn(np.column_stack([s, 0 * s, 1.1e-3 + 0 * s]))
    scene.hold(yarn, [0, 48], velocity=(0, 0, -2.0))
    obstacles = [kl.Cylinder(stiffness=50.0, mu=0.3, axis=(0, 1, 0), radius_m=1e-3),
                 kl.Plane(stiffness=50.0, point_m=(0, 0, 2e-3), normal=(0, 0, -1), velocity_m_s=(0, 0, -1.0))]
    sim = kl.Simulation(scene.build(), obstacles=obstacles)
    recorder = kl.TrajectoryRecorder()
    sim.run(4e-4, observe=recorder, observe_every_s=1e-4)
    path = kl.write_trajectory(tmp_path / "mine.h5", recorder)
    with h5py.File(path, "r") as f:
        assert f["obstacles/kind"][()].tolist() == [1, 0] and "plane" in f["obstacles/kind"].attrs["meaning"]
        assert f["obstacles/radius"][()] == pytest.approx([1e-3, 0.0])
        points = f["obstacles/points"][()]
        assert points.shape == (len(recorder.times), 2, 3) and f["obstacles/points"].attrs["unit"] == "m"
        assert points[-1, 1, 2] - points[0, 1, 2] == pytest.approx(-1.0 * (recorder.times[-1] - recorder.times[0]))
        bare = tmp_path / "bare.h5"
        with h5py.File(bare, "w") as g:
            for name in f:
                if name != "obstacles":
                    f.copy(name, g)
            g.attrs.update(f.attrs)
    covered = {}
    for name, file in (("with", path), ("without", bare)):
        picture = render_run(file, tmp_path / name, [recorder.times[-1]], ("oblique",), (320, 240))[0]
        covered[name] = ((imageio.imread(picture)[..., :3] < 235).any(axis=2)).mean()
    assert covered["with"] > covered["without"] + 0.1


def test_undone_cells_move_with_their_courses_yarn(run_folder):
    """A knit carried along as a whole carries its cells: every centre moves by the same vector; at the first frame
    the centres are where the cut left them."""
    from dataclasses import replace

    from knitlad.viz.render import Run

    run, f = Run.open(run_folder / "ladder.h5")
    with f:
        x = np.asarray(run.positions[:2])
        assert np.array_equal(run.cell_centres_at(0), run.cell_centres)
        shifted = replace(run, positions=np.stack([x[0], x[0] + np.array([1e-3, -2e-3, 5e-4])]))
        assert np.allclose(shifted.cell_centres_at(1) - run.cell_centres, [1e-3, -2e-3])
        still = replace(run, positions=np.stack([x[0], x[0]]))
        assert np.allclose(still.cell_centres_at(1), run.cell_centres)


def test_a_run_stop_band_of_any_kind_is_coloured_and_named_in_the_key(run_folder):
    from dataclasses import replace

    from knitlad.viz.render import BAND_COLOUR, Run, band_courses, node_colours

    assert band_courses({"stretch": {"pattern_band": ["rib", 5, 2]}, "dynamics": {}}) == (5, 6)
    assert band_courses({"stretch": {"memory_band": [3, 3, 2.0]}, "dynamics": {}}) == (3, 4, 5)
    assert band_courses({"stretch": {}, "dynamics": {"friction_band": [6, 1, 2.0]}}) == (6,)
    assert band_courses({"stretch": {"pattern_band": None}, "dynamics": {"friction_band": None}}) == ()
    run, f = Run.open(run_folder / "ladder.h5")
    with f:
        colours, key = node_colours(replace(run, band=(1, 2)), 0, "course")
        assert np.all(colours[np.isin(run.node_course, (1, 2))] == BAND_COLOUR) and "band (courses 1 to 2)" in key
        assert not np.any(np.all(node_colours(run, 0, "course")[0] == BAND_COLOUR, axis=1))


def test_the_depth_colouring_tells_columns_in_front_from_columns_behind_through_the_fabrics_curl(run_folder):
    """Knit and purl apart: columns alternately 0.1 mm in front and behind, on a fabric tilted by 5 mm over its
    width (a curl larger than the relief), read as two colours, the front ones yellow; the key says what it shows."""
    from dataclasses import replace

    from knitlad.viz.render import Run, local_depth, node_colours

    run, f = Run.open(run_folder / "ladder.h5")
    with f:
        x = np.asarray(run.positions[0], dtype=float).copy()
        column = np.floor((x[:, 0] - x[:, 0].min()) / run.l_x).astype(int)
        front = column % 2 == 0
        x[:, 2] = np.where(front, 1e-4, -1e-4) + 5e-3 * (x[:, 0] - x[:, 0].min()) / np.ptp(x[:, 0])
        ribbed = replace(run, positions=x[None])
        depth = local_depth(ribbed, x)
        assert np.median(depth[front]) > 5e-5 and np.median(depth[~front]) < -5e-5
        colours, key = node_colours(ribbed, 0, "depth")
        yellow = colours[:, 0] + colours[:, 1]  # viridis: yellow has both red and green
        assert np.median(yellow[front]) > np.median(yellow[~front]) + 0.5 and "depth" in key and "purl" in key
