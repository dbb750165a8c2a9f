"""Sweeps: config validation (one line naming the YAML key, exit 2, nothing started), job ids,
the smoke sweep through the CLI (pool and Dask give the same table), resume, failures, Ctrl-C."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pandas as pd
import pytest
import yaml

from knitlad.io.hdf5 import read_attrs
from knitlad.io.summary import TIMING_COLUMNS, read_summary
from knitlad.studies.runner import run_sweep
from knitlad.studies.sweep import Job, SweepConfig, SweepError, expand, job_id, load_sweep
from tests.conftest import knitlad

ROOT = Path(__file__).resolve().parents[2]
KNITLAD = [sys.executable, "-m", "knitlad.cli"]
TINY = {"n_x": 6, "n_y": 8, "preset": "fast", "resolution": 16, "max_time_ms": 3, "arrest_ms": 1}


def write_config(path: Path, cfg: dict) -> Path:
    path.write_text(yaml.safe_dump(cfg))
    return path


# ------------------------------------------------------------------ validation
@pytest.mark.parametrize(
    "cfg, where",
    [
        ({"fixed": TINY, "sweep": {"axes": {"lx": [0.38, 1.2]}}}, "sweep.axes.lx[1]"),
        ({"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": [0.4, -0.1]}}}, "sweep.axes.mu[1]"),
        ({"fixed": {**TINY, "colour": "red"}, "sweep": {"axes": {"lx": [0.38]}}}, "fixed.colour"),
        ({"fixed": TINY, "sweep": {"axes": {"lx": [0.38]}}, "extra": 1}, "extra"),
        ({"fixed": TINY, "sweep": {"axes": {}}}, "empty sweep"),
        ({"fixed": TINY, "sweep": {"axes": {"lx": []}}}, "no values"),
        ({"fixed": TINY, "sweep": {"axes": {"lx": [0.3, 0.4], "mu": [0.4]}, "expand": "zip"}}, "equal length"),
        ({"fixed": TINY, "sweep": {"axes": {"lx": {"start": 0.3, "stop": 0.4}}}}, "num or step"),
        ({"fixed": TINY, "sweep": {"axes": {"mu": [0.4]}}}, "fx (force control) or lx"),
        ({"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"lx": [0.38]}}}, "also given in fixed"),
        ({"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": [0.4, 0.4]}}}, "identical"),
        ({"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": [0.4]}}, "output": {"compression": "zip"}},
         "output.compression"),
    ],
)
def test_a_bad_config_is_refused_naming_its_key(tmp_path, cfg, where):
    path = write_config(tmp_path / "bad.yaml", cfg)
    with pytest.raises(SweepError, match=r".") as e:
        load_sweep(path)
    assert where in str(e.value) and "\n" not in str(e.value)


def test_the_cli_refuses_bad_input_in_one_line_with_exit_2_and_starts_nothing(tmp_path):
    bad = write_config(tmp_path / "bad.yaml", {"fixed": TINY, "sweep": {"axes": {"lx": [0.38, 1.2]}}})
    broken = tmp_path / "broken.yaml"
    broken.write_text("sweep: {axes: {lx: [0.3}\n")
    for args in ([str(bad)], [str(broken)], [str(tmp_path / "missing.yaml")],
                 [str(bad), "--executor", "slurm"], [str(bad), "--workers", "0"]):
        p = knitlad("sweep", *args, "--out", str(tmp_path / "out"))
        assert p.returncode == 2, (args, p.stderr)
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert not (tmp_path / "out").exists()


def test_grid_zip_and_ranges_expand_to_the_right_jobs_with_stable_ids(tmp_path):
    base = {"fixed": {**TINY, "ly": 0.25},
            "sweep": {"axes": {"lx": {"start": 0.30, "stop": 0.40, "step": 0.05}, "mu": [0.0, 0.4]}}}
    _, grid = load_sweep(write_config(tmp_path / "a.yaml", base))
    assert [(j.params["lx"], j.params["mu"]) for j in grid] == [
        (0.3, 0.0), (0.3, 0.4), (0.35, 0.0), (0.35, 0.4), (0.4, 0.0), (0.4, 0.4)]
    _, again = load_sweep(write_config(tmp_path / "b.yaml", base))
    assert [j.id for j in again] == [j.id for j in grid]
    assert len({j.id for j in grid}) == 6
    zipped = {**base, "sweep": {"expand": "zip", "axes": {"lx": [0.3, 0.4], "mu": [0.0, 0.4]}}}
    _, zjobs = load_sweep(write_config(tmp_path / "c.yaml", zipped))
    assert [(j.params["lx"], j.params["mu"]) for j in zjobs] == [(0.3, 0.0), (0.4, 0.4)]
    # the id follows the resolved config: a default spelled out is the same job, a changed value is not
    assert zjobs[0].id == grid[0].id
    _, other = load_sweep(write_config(tmp_path / "d.yaml", {**base, "fixed": {**TINY, "ly": 0.26}}))
    assert not {j.id for j in other} & {j.id for j in grid}


def test_a_field_added_later_keeps_the_ids_of_finished_jobs_at_its_neutral_value():
    """drag_per_s came after the first ladder sweeps: at 0 (the runs before it) a job's id is
    the one computed without the field, so rerunning an old sweep skips its finished jobs."""
    job = expand(SweepConfig.model_validate({"scene": "ladder", "fixed": {**TINY, "lx": 0.35},
                                             "sweep": {"axes": {"mu": [0.4]}}}))[0]
    assert job.params["drag_per_s"] == 0.0
    before = {k: v for k, v in job.params.items() if k not in ("drag_per_s", "twist")}
    assert job.id == job_id("ladder", before, job.output)
    assert job_id("ladder", {**job.params, "drag_per_s": 2e3}, job.output) != job.id
    assert job.params["twist"] is False  # twist came later still
    assert job_id("ladder", {**job.params, "twist": True}, job.output) != job.id


def test_a_finished_job_written_before_a_field_was_added_is_still_trusted(tmp_path):
    """A job file records its resolved config; one written before ``axial_stiffness_factor`` existed
    lacks it. Read in today's terms (the field at its default) it is the same run: trusted, and a
    rerun skips it. The same file with another value of a field is not."""
    import json

    from knitlad.io.hdf5 import write_record
    from knitlad.studies.runner import job_path, trusted_attrs

    job = expand(SweepConfig.model_validate({"scene": "ladder", "fixed": {**TINY, "lx": 0.35},
                                             "sweep": {"axes": {"mu": [0.4]}}}))[0]
    older = json.loads(job.model_dump_json())
    del older["params"]["axial_stiffness_factor"]
    path = job_path(tmp_path, job)
    write_record(path, {"job_id": job.id, "job_json": json.dumps(older), "status": "ok"})
    attrs, why = trusted_attrs(path, job)
    assert attrs is not None, why
    older["params"]["mu"] = 0.0
    write_record(path, {"job_id": job.id, "job_json": json.dumps(older), "status": "ok"})
    assert trusted_attrs(path, job) == (None, "its file records another configuration")


# ------------------------------------------------------------------ smoke sweep
@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    """configs/smoke.yaml through the CLI, as CI runs it."""
    out = tmp_path_factory.mktemp("smoke")
    p = knitlad("sweep", "configs/smoke.yaml", "--out", str(out))
    assert p.returncode == 0, p.stderr
    return out


def test_smoke_sweep_writes_a_summary_of_ladders_and_one_file_per_job(smoke):
    df = read_summary(smoke)
    _, jobs = load_sweep(ROOT / "configs" / "smoke.yaml")
    assert list(df["job_id"]) == [j.id for j in jobs]
    assert (df["status"] == "ok").all()
    assert (df["n_lad_over_ny"] > 0).all()  # the cut loop ladders at these tensions
    assert (df["fx_fin"] < df["fx_ini"]).all()  # and the laddered knit carries less
    for job in jobs:
        attrs = read_attrs(smoke / "jobs" / f"{job.id}.h5")
        assert attrs["status"] == "ok" and attrs["job_id"] == job.id
        assert Job.model_validate(attrs["job_json"]).id == job.id  # enough to rerun it exactly
        assert attrs["scale_f0_N"] > 0 and attrs["knitlad_version"]


def test_rerunning_skips_finished_jobs_and_force_reruns_them(smoke):
    files = sorted((smoke / "jobs").glob("*.h5"))
    stamps = [f.stat().st_mtime_ns for f in files]
    p = knitlad("sweep", "configs/smoke.yaml", "--out", str(smoke))
    assert p.returncode == 0 and "0 jobs run" in p.stdout and f"{len(files)} already done" in p.stdout
    assert [f.stat().st_mtime_ns for f in files] == stamps


@pytest.mark.end_to_end
def test_a_sweep_renders_its_ladder_jobs_on_request(smoke):
    p = knitlad("sweep", "configs/smoke.yaml", "--out", str(smoke), "--render")
    assert p.returncode == 0 and "rendered 2 jobs" in p.stdout, p.stderr
    for job in read_summary(smoke)["job_id"]:
        assert len(list((smoke / "renders" / job).glob("render_front_*.png"))) == 5


def _same_summary_as_the_pool(smoke, out, *options):
    """The smoke sweep run with ``options`` into ``out`` gives the pool's summary (timings and code aside)."""
    p = knitlad("sweep", "configs/smoke.yaml", "--out", str(out), *options)
    assert p.returncode == 0, p.stderr
    ignored = [*TIMING_COLUMNS, "knitlad_code"]
    pd.testing.assert_frame_equal(read_summary(smoke).drop(columns=ignored), read_summary(out).drop(columns=ignored))


@pytest.mark.cluster
def test_dask_on_a_local_cluster_gives_the_same_summary_as_the_pool(smoke, tmp_path):
    pytest.importorskip("distributed")
    _same_summary_as_the_pool(smoke, tmp_path, "--executor", "dask")


@pytest.mark.cluster
def test_a_batch_cluster_file_runs_the_sweep_through_dask_jobqueue(smoke, tmp_path):
    """--cluster configs/cluster/local.yaml: dask-jobqueue's cluster with its workers as local processes (the
    path a Slurm cluster takes, but for the batch system): the same summary as the pool."""
    pytest.importorskip("dask_jobqueue")
    _same_summary_as_the_pool(smoke, tmp_path, "--cluster", "configs/cluster/local.yaml")


def test_the_slurm_example_prints_its_batch_script_and_bad_cluster_files_are_one_line(tmp_path):
    pytest.importorskip("dask_jobqueue")
    p = knitlad("sweep", "configs/smoke.yaml", "--cluster", "configs/cluster/slurm.yaml", "--dry-run")
    assert p.returncode == 0, p.stderr
    assert "#SBATCH -p normal" in p.stdout and "#SBATCH -t 08:00:00" in p.stdout and "dask_worker" in p.stdout
    bad = tmp_path / "bad.yaml"
    for text, says in (("kind: slurmm\njobs: 2\n", "kind"), ("kind: slurm\njobs: 0\n", "jobs"),
                       ("kind: slurm\njobs: 2\nqueue: x\n", "queue"),
                       ("kind: slurm\njobs: 2\noptions: {no_such_option: 1}\n", "not a slurm worker's settings")):
        bad.write_text(text)
        p = knitlad("sweep", "configs/smoke.yaml", "--cluster", str(bad), "--dry-run")
        assert p.returncode == 2 and says in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_plot_draws_the_summary_figures_and_the_diagrams(smoke):
    p = knitlad("plot", str(smoke))
    assert p.returncode == 0, p.stderr
    for name in ("damage_vs_fx.png", "fx_fin_vs_fx_ini.png", "velocity_vs_fx.png"):
        assert (smoke / "plots" / name).stat().st_size > 1000
    assert len(list((smoke / "plots").glob("*.png"))) == 3 + len(read_summary(smoke))
    # the smoke sweep varies lx and mu: each job's diagram is named by them
    assert (smoke / "plots" / "lx=0.36_mu=0.4.png").is_file() and (smoke / "plots" / "lx=0.38_mu=0.png").is_file()


def test_plot_writes_the_format_asked_and_refuses_an_unknown_one(smoke, tmp_path):
    p = knitlad("plot", str(smoke), "--format", "svg", "--no-diagrams")
    assert p.returncode == 0, p.stderr
    assert (smoke / "plots" / "damage_vs_fx.svg").read_text().lstrip().startswith("<?xml")
    p = knitlad("plot", str(smoke), "--format", "bmp")
    assert p.returncode == 2 and "--format" in p.stderr and len(p.stderr.strip().splitlines()) == 1


def test_job_figures_are_named_by_what_varies_and_told_apart_by_id_when_that_is_not_enough():
    from knitlad.viz.plots import job_figure_names

    df = pd.DataFrame({"job_id": ["a1", "b2", "c3"], "scene": "ladder", "n_x": 16, "mu": [0.4, 0.4, 0.0],
                       "fx": [2.0, 2.0, 4.5], "status": "ok", "fx_ini": [2.01, 1.99, 4.49]})
    assert job_figure_names(df) == {"a1": "mu=0.4_fx=2_a1", "b2": "mu=0.4_fx=2_b2", "c3": "mu=0_fx=4.5"}


# ------------------------------------------------------------------ failures
def test_a_failing_job_is_recorded_and_the_others_go_on(tmp_path):
    """No jersey stitch of d/l0 = 1/20 holds l0 at these periodicities: that job fails
    (CourseTooWide, raised by the run, not by the config), the other runs."""
    cfg = write_config(tmp_path / "f.yaml", {"scene": "stitch", "fixed": {"lx": 0.35, "ly": 0.25, "preset": "fast", "resolution": 16},
                                             "sweep": {"axes": {"d_over_l0": [0.05, 1 / 70]}}})
    p = knitlad("sweep", str(cfg), "--out", str(tmp_path / "out"), "--workers", "1")
    assert p.returncode == 1
    df = read_summary(tmp_path / "out")
    assert list(df["status"]) == ["failed", "ok"]
    assert "CourseTooWide" in df["error"][0] and "d/l0 = 0.05" in df["error"][0]
    assert "failed" in p.stderr and "Traceback" not in p.stderr


@pytest.mark.process
def test_a_dead_worker_fails_only_its_job_and_the_pool_is_restarted(tmp_path):
    cfg = {"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": [0.1, 0.0, 0.3, 0.4]}}}
    _, jobs = load_sweep(write_config(tmp_path / "c.yaml", cfg))
    from tests.sweep_helpers import fake_runner

    outcome = run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False)
    df = read_summary(tmp_path / "out")
    assert list(df["status"]) == ["ok", "failed", "ok", "ok"]
    assert "worker process died" in df["error"][1]
    assert outcome.ran == 4 and outcome.failed == 1
    # resume: nothing left to do unless failed jobs are retried
    again = run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False)
    assert again.ran == 0 and again.skipped == 4


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.process
def test_ctrl_c_keeps_finished_jobs_and_a_consistent_summary_and_the_rerun_goes_on(tmp_path, sig):
    """Ctrl-C (SIGINT to the process group) and kill (SIGTERM to the parent): the same clean stop."""
    cfg = write_config(tmp_path / "c.yaml", {"fixed": {**TINY, "lx": 0.38}, "sweep": {"axes": {"mu": [0.1, 0.2, 0.3]}}})
    out = tmp_path / "out"
    proc = subprocess.Popen([*KNITLAD, "sweep", str(cfg), "--out", str(out), "--workers", "1"], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            # a job started in the background (nohup, &) inherits SIGINT ignored: undo that
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 240
    while time.time() < deadline and not list((out / "jobs").glob("*.h5")):
        time.sleep(0.2)
    assert list((out / "jobs").glob("*.h5")), "no job finished in time"
    children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
    workers = [c for c in children if b"spawn_main" in Path(f"/proc/{c}/cmdline").read_bytes()]
    assert workers, "no pool worker found"
    if sig == signal.SIGINT:
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group
    else:
        os.kill(proc.pid, signal.SIGTERM)  # as kill or a batch system: the parent only
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == (130 if sig == signal.SIGINT else 143), err
    assert ("interrupted" if sig == signal.SIGINT else "terminated") in err and "Traceback" not in err
    df = read_summary(out)
    done = set(df.loc[df["status"] == "ok", "job_id"])
    assert 1 <= len(done) < 3 and set(df["status"]) <= {"ok", "pending"}
    assert {f.stem for f in (out / "jobs").glob("*.h5")} == done
    assert not list((out / "jobs").glob("*.tmp"))
    time.sleep(1.0)
    alive = [w for w in workers if Path(f"/proc/{w}").exists()]
    assert not alive, "a worker outlived the sweep"
    p = knitlad("sweep", str(cfg), "--out", str(out))
    assert p.returncode == 0 and f"{len(done)} already done" in p.stdout
    assert (read_summary(out)["status"] == "ok").all()


@pytest.mark.end_to_end
def test_a_single_loop_sweep_tabulates_velocity_against_tension_and_friction(tmp_path):
    cfg = write_config(tmp_path / "loop.yaml", {"scene": "loop", "sweep": {"axes": {"mu": [0.0, 0.8], "fx": [4.0]}}})
    p = knitlad("sweep", str(cfg), "--out", str(tmp_path / "out"), "--workers", "1")
    assert p.returncode == 0, p.stderr
    df = read_summary(tmp_path / "out")
    assert list(df["status"]) == ["ok", "ok"] and df["released"].all()
    assert df["v_lad_over_cb"][0] > df["v_lad_over_cb"][1]  # friction slows the release
    p = knitlad("plot", str(tmp_path / "out"))
    assert p.returncode == 0 and (tmp_path / "out" / "plots" / "loop_velocity_vs_fx.png").stat().st_size > 1000


@pytest.mark.end_to_end
def test_a_stitch_sweep_maps_the_tension_sign(tmp_path):
    cfg = write_config(tmp_path / "s.yaml", {"scene": "stitch", "fixed": {"ly": 0.25},
                                             "sweep": {"axes": {"lx": [0.30, 0.40]}}})
    _, jobs = load_sweep(cfg)
    run_sweep(jobs, tmp_path / "out", workers=1, progress=False)
    df = read_summary(tmp_path / "out")
    assert list(df["status"]) == ["ok", "ok"]
    assert df["fx"][0] < 0 < df["fx"][1]  # compressed at 0.30 l0, stretched at 0.40 l0 (l_y = 0.25 l0)


@pytest.mark.end_to_end
def test_jobs_that_share_a_stretch_stretch_once_and_ladder_as_fresh_runs(tmp_path):
    """A sweep over the dynamics (here mu) stretches its knit once (`<out>/stretched/`); the job
    that reuses it gives the very ladder a fresh run gives."""
    from knitlad.experiments.laddering import run_ladder

    cfg = {"fixed": {**TINY, "lx": 0.38, "max_time_ms": 0.5}, "sweep": {"axes": {"mu": [0.4, 0.0]}}}
    _, jobs = load_sweep(write_config(tmp_path / "c.yaml", cfg))
    run_sweep(jobs, tmp_path / "out", workers=1, progress=False)
    df = read_summary(tmp_path / "out")
    assert list(df["status"]) == ["ok", "ok"] and list(df["stretch_reused"]) == [False, True]
    assert len(list((tmp_path / "out" / "stretched").glob("*.h5"))) == 1
    fresh = run_ladder(jobs[1].scene_config().settings())
    with h5py.File(tmp_path / "out" / "jobs" / f"{jobs[1].id}.h5", "r") as f:
        assert list(f["series/fx"][()]) == fresh.fx_series


def test_job_files_of_another_code_are_kept_counted_and_rerun_on_request(tmp_path):
    """A resumed sweep trusted job files of older code silently; a physics fix could mix with results before it."""
    from tests.sweep_helpers import fake_runner

    cfg = {"fixed": {**TINY, "lx": 0.38}, "sweep": {"axes": {"mu": [0.1, 0.3]}}}
    _, jobs = load_sweep(write_config(tmp_path / "c.yaml", cfg))
    run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False)
    for path in (tmp_path / "out" / "jobs").glob("*.h5"):  # as an older knitlad wrote them
        with h5py.File(path, "r+") as f:
            f.attrs["knitlad_code"] = "0.1.0+older"
    kept = run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False)
    assert kept.ran == 0 and len(kept.stale) == 2
    assert set(read_summary(tmp_path / "out")["knitlad_code"]) == {"0.1.0+older"}
    again = run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False, rerun_stale=True)
    assert again.ran == 2 and not again.stale
    assert "0.1.0+older" not in set(read_summary(tmp_path / "out")["knitlad_code"])


def test_every_example_and_reference_sweep_config_validates():
    """configs/*.yaml (the examples) and docs/reference/*.yaml (the studies' sweeps) load and expand, and each
    job's resolved parameters (every field, defaults too) validate again as the runner reads them."""
    paths = sorted((ROOT / "configs").glob("*.yaml")) + sorted((ROOT / "docs" / "reference").glob("*.yaml"))
    assert len(paths) >= 15
    for path in paths:
        _, jobs = load_sweep(path)
        assert jobs, path
        for job in jobs:
            job.scene_config()


def test_a_mistyped_key_says_which_field_it_resembles_and_every_mistake_is_said(tmp_path):
    """A mistyped YAML key listed all 35 fields instead of "did you mean max_time_ms?", and only the first
    error of a config was reported."""
    from knitlad.studies.sweep import SweepError, load_sweep

    bad = write_config(tmp_path / "a.yaml", {"fixed": {**TINY, "lx": 0.4, "max_time_m": 3},
                                               "sweep": {"axes": {"muu": [0.1]}}})
    with pytest.raises(SweepError) as e:
        load_sweep(bad)
    message = str(e.value)
    assert "fixed.max_time_m: not a field of scene 'ladder'; did you mean max_time_ms?" in message
    assert "sweep.axes.muu: not a field of scene 'ladder'; did you mean mu?" in message
    assert "max_time_us" not in message and "\n" not in message
    two = write_config(tmp_path / "b.yaml", {"fixed": {**TINY, "lx": 0.4, "ly": 5, "mu": -1},
                                               "sweep": {"axes": {"observe_every_us": [20.0]}}})
    with pytest.raises(SweepError, match=r"^fixed.ly: .*; fixed.mu: "):
        load_sweep(two)


def test_an_ensemble_is_a_sweep_axis_of_paired_knits_and_its_plot_draws_means_with_their_errors(tmp_path):
    """The docs said to compare means over knits stretched to targets 0.5 % apart, never single runs, but a
    sweep could not ask for that; only scripts/paper/ could."""
    from knitlad.studies.runner import run_sweep
    from knitlad.studies.sweep import SweepError, load_sweep
    from knitlad.viz.plots import summary_plots
    from tests.sweep_helpers import fake_runner

    cfg = write_config(tmp_path / "e.yaml", {"fixed": {**TINY, "fx": 4.0},
                                              "sweep": {"axes": {"mu": [0.1, 0.3]}, "ensemble": 3}})
    _, jobs = load_sweep(cfg)
    assert len(jobs) == 6
    fx = sorted({job.params["fx"] for job in jobs})
    assert fx == pytest.approx([4.0 * 0.995, 4.0, 4.0 * 1.005])  # each member's knit shared by both mu: paired
    assert {job.fx_nominal for job in jobs} == {4.0} and {job.ensemble_member for job in jobs} == {0, 1, 2}
    assert all(job.params["knit_seed"] == job.ensemble_member for job in jobs)  # each member its own knit
    assert len({job.point for job in jobs}) == 2  # one point per mu, its members' seeds and targets aside
    run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False)
    df = read_summary(tmp_path / "out")
    assert set(df["ensemble_member"]) == {0, 1, 2} and set(df["fx_nominal"]) == {4.0}
    df["v_lad_over_cb"], df["n_lad_over_ny"], df["fx_fin"] = 0.3, 1.0, 2.0
    assert len(summary_plots(df, tmp_path / "plots")) == 3
    with pytest.raises(SweepError, match="sweep.ensemble: needs force control"):
        load_sweep(write_config(tmp_path / "p.yaml", {"fixed": {**TINY, "lx": 0.4},
                                                       "sweep": {"axes": {"mu": [0.1]}, "ensemble": 2}}))


@pytest.mark.end_to_end
def test_a_tensile_sweep_writes_its_summary_and_plot_draws_each_jobs_loops(tmp_path):
    """The sweep scene `tensile` (one 6 x 8 job): its summary columns, its file's readings, and `knitlad plot`
    drawing the job's force-displacement loops."""
    config = tmp_path / "tensile.yaml"
    config.write_text(yaml.safe_dump({
        "scene": "tensile", "fixed": {"n_x": 6, "n_y": 8, "preset": "fast", "lx": 0.36, "lx_max": 0.37,
                                      "readings_per_leg": 2},
        "sweep": {"expand": "grid", "axes": {"mu": [0.4]}}, "output": {"frames": False}}))
    out = tmp_path / "out"
    p = knitlad("sweep", str(config), "--out", str(out))
    assert p.returncode == 0, p.stderr
    df = read_summary(out)
    assert (df["status"] == "ok").all() and (df["fx_top"] > df["fx_start"]).all()
    assert (df["dissipated_per_stitch"] > 0).all()
    with h5py.File(out / "jobs" / f"{df['job_id'][0]}.h5") as f:
        assert f["tensile/readings"].shape == (6, 8)
    p = knitlad("plot", str(out))
    assert p.returncode == 0, p.stderr
    assert len(list((out / "plots").glob("tensile_*.png"))) == 1


@pytest.mark.end_to_end
def test_a_snag_sweep_breaks_worn_loops_and_writes_the_curve_and_the_ladder(tmp_path):
    """The sweep scene `snag` (one 6 x 6 job, a 0.1 N worn spot): its summary says the break and the ladder,
    its file holds the pull-out curve with units and the ladder's series."""
    config = tmp_path / "snag.yaml"
    config.write_text(yaml.safe_dump({
        "scene": "snag", "fixed": {"n_x": 6, "n_y": 6, "preset": "fast", "fx": 4.0, "snag_speed": 3.0,
                                   "max_time_ms": 1.0},
        "sweep": {"expand": "grid", "axes": {"weak_point_force": [0.1]}}, "output": {"frames": False}}))
    out = tmp_path / "out"
    p = knitlad("sweep", str(config), "--out", str(out))
    assert p.returncode == 0, p.stderr
    df = read_summary(out)
    assert (df["status"] == "ok").all() and df["broke"].all() and (df["n_lad_over_ny"] > 0).all()
    with h5py.File(out / "jobs" / f"{df['job_id'][0]}.h5") as f:
        assert f["snag/force"].attrs["unit"] == "N" and f["snag/pull"].shape == f["snag/force"].shape
        assert "series/front_up" in f and f.attrs["scale_f0_N"] > 0
    assert knitlad("sweep", str(config), "--out", str(out)).returncode == 0
    again = read_summary(out)  # the rerun reads the finished job's row back from its file
    for key in ("peak_force_N", "pull_at_break_mm", "break_row"):
        assert again[key][0] == pytest.approx(df[key][0], rel=1e-9), key


@pytest.mark.end_to_end
def test_a_sweep_over_patterns_ladders_each_and_tabulates_its_pattern(tmp_path):
    """The knit's pattern is a sweep axis: jersey and garter 6 x 6 jobs at f_x^ini 3 both ladder; the summary
    says each job's pattern, and the jersey job's id is the one it had before patterns existed."""
    config = write_config(tmp_path / "patterns.yaml", {
        "scene": "ladder", "fixed": {"n_x": 6, "n_y": 6, "preset": "fast", "fx": 3.0, "max_time_ms": 2},
        "sweep": {"expand": "grid", "axes": {"pattern": ["jersey", "garter"]}}, "output": {"frames": False}})
    out = tmp_path / "out"
    p = knitlad("sweep", str(config), "--out", str(out))
    assert p.returncode == 0, p.stderr
    df = read_summary(out).set_index("pattern")
    assert (df["status"] == "ok").all() and sorted(df.index) == ["garter", "jersey"]
    assert (df["n_lad"] >= 1).all() and (abs(df["fx_ini"] - 3.0) < 0.06).all()
    plain = [j for j in load_sweep(config)[1] if j.params["pattern"] == "jersey"][0]
    assert plain.id == job_id("ladder", {k: v for k, v in plain.params.items() if k != "pattern"}, plain.output)


@pytest.mark.parametrize("scene, fixed", [
    ("ladder", {"fx": 3.0}), ("cycle", {"fx": 0.68, "lx_max": 0.36}), ("tensile", {"lx": 0.34, "lx_max": 0.36}),
    ("snag", {"fx": 3.0}), ("resistance", {"fx": 3.0})])
def test_a_field_added_to_the_laddering_config_later_keeps_every_scenes_ids(scene, fixed):
    """band_curvature came after the cycle, tensile, snag and resistance scenes had run sweeps on the laddering
    config: at its default their jobs keep the ids computed without it (a protocol B sweep of 2026-12-06 lost
    its two finished jobs to it)."""
    job = expand(SweepConfig.model_validate({"scene": scene, "fixed": {"n_x": 6, "n_y": 6, **fixed},
                                             "sweep": {"axes": {"mu": [0.4]}}}))[0]
    later = ("band_curvature", "drag_lambda", "spin_drag", "contact_dashpot")  # the last three: the authors' preset's
    before = {k: v for k, v in job.params.items() if k not in later}
    assert job.id == job_id(scene, before, job.output)
    assert job_id(scene, {**job.params, "band_curvature": 2.0}, job.output) != job.id
    assert job_id(scene, {**job.params, "contact_dashpot": "absolute"}, job.output) != job.id


def test_an_ensemble_member_that_stretched_to_another_members_knit_is_said_and_counted_once():
    """Two members of a point with the same f_x^ini, l_x and l_y (to the digit) are one knit: the second says
    which it repeats, its point's mean counts it once, and `knitlad plot` warns."""
    from knitlad.studies.ensemble import with_collapsed_members

    knit = {"fx_ini": 7.990334, "lx_over_l0": 0.3811, "ly_over_l0": 0.2502}
    rows = [{"ensemble_point": "p", "ensemble_member": k, "status": "ok", **knit, "fx_nominal": 8.0} for k in range(3)]
    rows[2]["fx_ini"] = 8.02
    rows.append({"ensemble_point": "q", "ensemble_member": 0, "status": "ok", **knit, "fx_nominal": 8.0})
    marked = with_collapsed_members(rows)
    assert [r["same_knit_as"] for r in marked] == [-1, 0, -1, -1]


def test_a_setting_renamed_in_0_14_is_named_by_its_new_name_not_a_lookalike(tmp_path):
    """Round 4: `lx_over_l0` in a sweep got "did you mean d_over_l0?", `nodes_per_stitch` "did you mean
    stop_after_stitches?"."""
    cfg = write_config(tmp_path / "old.yaml", {"fixed": {**TINY, "lx_over_l0": 0.38}, "sweep": {"axes": {"mu": [0.1]}}})
    with pytest.raises(SweepError, match="fixed.lx_over_l0: not a field of scene 'ladder'; it was renamed lx"):
        load_sweep(cfg)
