"""No lost work and no silently wrong result: concurrency, faults and bad input (small, seconds each)."""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

from knitlad.io.folders import LOCK_NAME, FolderError, FolderLock
from knitlad.io.summary import read_summary
from knitlad.studies.runner import ABANDONED, job_path, run_job, run_sweep, trusted_attrs
from knitlad.studies.sweep import SweepError, load_sweep
from tests.conftest import knitlad, knitlad_process, one_line_error

ROOT = Path(__file__).resolve().parents[1]
KNITLAD = [sys.executable, "-m", "knitlad.cli"]
TINY = {"n_x": 6, "n_y": 8, "preset": "fast", "resolution": 16, "max_time_ms": 3, "arrest_ms": 1}




def config(tmp_path: Path, cfg: dict, name: str = "c.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(cfg))
    return path


def fake_jobs(tmp_path: Path, mus: list[float]):
    return load_sweep(config(tmp_path, {"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": mus}}}))[1]


# ------------------------------------------------------------------ work lost
@pytest.mark.process
def test_a_second_sweep_on_the_same_folder_is_refused_and_the_first_runs_every_job_once(tmp_path):
    cfg = config(tmp_path, {"fixed": {**TINY, "lx": 0.38}, "sweep": {"axes": {"mu": [0.1, 0.2]}}})
    out = tmp_path / "out"
    first = subprocess.Popen([*KNITLAD, "sweep", str(cfg), "--out", str(out), "--workers", "1"], cwd=ROOT,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and not (out / LOCK_NAME).exists():
        time.sleep(0.05)
    second = knitlad("sweep", str(cfg), "--out", str(out), "--workers", "1")
    assert "in use by another knitlad run" in one_line_error(second)
    stdout, stderr = first.communicate(timeout=300)
    assert first.returncode == 0, stderr
    assert "2 jobs run (0 failed), 0 already done" in stdout
    assert (read_summary(out)["status"] == "ok").all() and not (out / LOCK_NAME).exists()


def test_a_stale_lock_of_a_dead_process_is_taken_over(tmp_path):
    dead = subprocess.Popen(["true"])
    dead.wait()
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / LOCK_NAME).write_text(json.dumps({"pid": dead.pid, "host": os.uname().nodename,
                                                          "token": "old", "started": "then"}))
    lock = FolderLock(tmp_path / "out").acquire()
    assert lock.took_over["token"] == "old"
    with pytest.raises(FolderError, match="in use by another knitlad run"):
        FolderLock(tmp_path / "out").acquire()  # a live owner (this process) is respected
    lock.release()
    assert not (tmp_path / "out" / LOCK_NAME).exists()


@pytest.mark.parametrize("command", [["cut", "--stitches", "6x8", "--lx", "0.38"], ["diagram", "--ly", "0.25"],
                                     ["sweep", "configs/smoke.yaml"]])
def test_an_output_path_that_cannot_be_a_folder_is_refused_before_any_compute(tmp_path, command):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    for out in (blocker, blocker / "sub"):
        p = knitlad(*command, "--out", str(out))
        assert str(out) in one_line_error(p)
        assert "stretch" not in p.stdout and "f_x = 0 at" not in p.stdout


def test_a_job_whose_file_cannot_be_written_fails_alone(tmp_path, monkeypatch):
    """A full disk or an I/O error while writing: the job is failed, with the reason; the
    sweep goes on (below, in a pool)."""
    from knitlad.studies import registry

    job = fake_jobs(tmp_path, [0.4])[0]
    (tmp_path / "jobs").mkdir()

    def no_space(cfg, output, folder=None, progress=None):
        def write(path, record):
            raise OSError(28, "No space left on device")

        return registry.Finished(None, {"fx_ini": 1.0}, write)

    monkeypatch.setitem(registry.EXPERIMENTS, "ladder", dataclasses.replace(registry.EXPERIMENTS["ladder"], run=no_space))
    row = run_job(job, str(tmp_path / "jobs"))
    assert row["status"] == "failed" and "No space left on device" in row["error"]
    assert trusted_attrs(job_path(tmp_path / "jobs", job), job)[0]["status"] == "failed"


@pytest.mark.process
def test_a_failing_task_and_a_dead_worker_fail_only_their_jobs_and_a_rerun_says_so(tmp_path):
    """Two jobs in flight when a worker dies: the pool breaks and both are lost with it; each
    is run again alone, and only the one that kills its worker fails. A task that raises (a
    failed write outside the job) fails alone too."""
    from tests.sweep_helpers import fake_runner

    jobs = fake_jobs(tmp_path, [0.1, 0.0, 0.2, 0.3, 0.4])
    outcome = run_sweep(jobs, tmp_path / "out", workers=2, runner=fake_runner, progress=False)
    df = read_summary(tmp_path / "out")
    assert list(df["status"]) == ["ok", "failed", "failed", "ok", "ok"]
    assert "worker process died" in df["error"][1] and "No space left" in df["error"][2]
    assert outcome.failed == 2 and len(outcome.failed_rows) == 2
    again = run_sweep(jobs, tmp_path / "out", workers=2, runner=fake_runner, progress=False)
    assert again.ran == 0 and len(again.failed_rows) == 2  # the CLI exits 1 on these (below)


def test_a_rerun_that_leaves_failed_jobs_exits_1_and_names_them(tmp_path):
    cfg = config(tmp_path, {"scene": "stitch", "fixed": {"lx": 0.35, "ly": 0.25, "preset": "fast", "resolution": 16},
                            "sweep": {"axes": {"d_over_l0": [0.05]}}})
    for _ in range(2):
        p = knitlad("sweep", str(cfg), "--out", str(tmp_path / "out"), "--workers", "1")
        assert p.returncode == 1 and "1 of 1 jobs failed" in p.stderr and "--retry-failed" in p.stderr


# ------------------------------------------------------------------ silently wrong
def _real_job_file(tmp_path: Path, job):
    """A job file written as a finished ladder job's is, with datasets (and their checksums)."""
    from knitlad.io.hdf5 import _set_attrs
    from knitlad.studies.runner import _record

    path = job_path(tmp_path / "jobs", job)
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as f:
        _set_attrs(f, _record(job, "ok", "", 1.0))
        f.create_dataset("series/fx", data=np.linspace(0, 1, 4096), fletcher32=True)
    return path


def test_a_job_file_that_is_another_jobs_or_damaged_is_not_trusted_and_the_job_runs_again(tmp_path):
    a, b = fake_jobs(tmp_path, [0.1, 0.3])
    path_a = _real_job_file(tmp_path, a)
    assert trusted_attrs(path_a, a)[0] is not None
    path_b = job_path(tmp_path / "jobs", b)
    path_b.write_bytes(path_a.read_bytes())  # left over or copied: a's file under b's name
    assert "belongs to job" in trusted_attrs(path_b, b)[1]
    with h5py.File(path_a, "r") as f:
        offset = f["series/fx"].id.get_chunk_info(0).byte_offset
    raw = bytearray(path_a.read_bytes())
    raw[offset + 100] ^= 0xFF  # one damaged byte in the data
    path_a.write_bytes(bytes(raw))
    assert "damaged" in trusted_attrs(path_a, a)[1]
    from tests.sweep_helpers import fake_runner

    outcome = run_sweep([a, b], tmp_path, workers=1, runner=fake_runner, progress=False)
    assert outcome.ran == 2 and outcome.skipped == 0
    assert all(trusted_attrs(job_path(tmp_path / "jobs", j), j)[0] is not None for j in (a, b))


def test_plot_checks_the_summary_against_the_job_files(tmp_path):
    from tests.sweep_helpers import fake_runner

    jobs = fake_jobs(tmp_path, [0.1, 0.3, 0.4])
    run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False,
              config_text=(tmp_path / "c.yaml").read_text())
    summary = tmp_path / "out" / "summary.csv"
    summary.write_text("".join(summary.read_text().splitlines(keepends=True)[:2]))  # truncated: one row left
    p = knitlad("plot", str(tmp_path / "out"), "--no-diagrams")
    assert p.returncode == 1 and p.stderr.count("missing from summary.csv") == 2
    summary.write_bytes(os.urandom(256))
    (tmp_path / "out" / "sweep.yaml").unlink()
    assert "summary.csv" in one_line_error(knitlad("plot", str(tmp_path / "out")))


def test_a_job_that_outlives_its_sweep_writes_nothing(tmp_path):
    """After Ctrl-C the sweep releases its folder's lock; a task still running on a cluster
    then finds the lock gone and leaves no file the summary does not know of."""
    job = fake_jobs(tmp_path, [0.4])[0]
    jobs_dir = tmp_path / "out" / "jobs"
    jobs_dir.mkdir(parents=True)
    with FolderLock(tmp_path / "out"):
        pass  # the sweep has stopped: its token no longer holds the folder
    from tests.sweep_helpers import fast_ladder_scene

    with fast_ladder_scene():
        row = run_job(job, str(jobs_dir), token="the stopped sweep's")
    assert row["status"] == "pending" and row["error"] == ABANDONED and not list(jobs_dir.iterdir())


@pytest.mark.parametrize("cfg, where", [
    ({"fixed": {**{k: v for k, v in TINY.items() if k != "preset"}, "lx": 0.4, "resolution": 16, "sagitta_radius": 0,
                "implicit_axial": False, "dt_safety": 0.35}, "sweep": {"axes": {"preset": ["fast", "accurate"]}}},
     "preset"),
    ({"fixed": {**TINY, "lx": 0.4, "observe_every_us": 50}, "sweep": {"axes": {"mu": [0.4]}},
      "output": {"frame_every_us": 20}}, "output.frame_every_us: 20 is shorter"),  # was "fixed: frame_every_us"
    ({"fixed": {**TINY, "lx": 0.4, "n_x": True}, "sweep": {"axes": {"mu": [0.4]}}}, "n_x"),
    ({"fixed": {**TINY, "lx": float("nan")}, "sweep": {"axes": {"mu": [0.4]}}}, "finite number"),
    ({"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": {"start": 0, "stop": 1, "step": 1e-300}}}}, "jobs"),
    ({"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": {"start": 0, "stop": float("inf"), "step": 1}}}},
     "finite number"),
    ({"fixed": {**TINY}, "sweep": {"axes": {"lx": {"start": 0.3, "stop": 0.4, "num": 1000},
                                            "mu": {"start": 0, "stop": 1, "num": 1000}}}}, "1e+06 jobs"),
])
def test_settings_that_would_be_taken_silently_or_hang_are_refused_at_once(tmp_path, cfg, where):
    t = time.perf_counter()
    with pytest.raises(SweepError) as e:
        load_sweep(config(tmp_path, cfg))
    assert where in str(e.value) and "\n" not in str(e.value)
    assert time.perf_counter() - t < 5


def test_a_duplicated_yaml_key_is_refused(tmp_path):
    path = tmp_path / "dup.yaml"
    path.write_text("fixed: {n_x: 6, n_y: 8, lx: 0.4}\nsweep: {axes: {mu: [0.4]}}\nsweep: {axes: {mu: [0.0]}}\n")
    with pytest.raises(SweepError, match="given twice"):
        load_sweep(path)


# ------------------------------------------------------------------ hangs, resources, tracebacks
def test_a_knit_larger_than_the_memory_is_refused_before_allocating(tmp_path):
    p = knitlad("cut", "--stitches", "200x200", "--resolution", "280", "--lx", "0.4", "--out", str(tmp_path / "o"))
    assert "GiB" in one_line_error(p) and not (tmp_path / "o").exists()


@pytest.mark.process
def test_bad_files_and_schedulers_are_one_line_within_seconds(tmp_path):
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(bytes(range(256)))
    assert "not a text file" in one_line_error(knitlad("sweep", str(binary)))
    t = time.perf_counter()
    for address in ("tcp://127.0.0.1:9", "nonsense://host"):
        p = knitlad("sweep", "configs/smoke.yaml", "--executor", "dask", "--scheduler", address,
                    "--out", str(tmp_path / "o"))
        assert "--scheduler" in one_line_error(p)
    assert time.perf_counter() - t < 60 and not (tmp_path / "o").exists()
    assert "finite number" in one_line_error(knitlad("cut", "--fx", "nan", "--stitches", "6x8"))


@pytest.mark.process
def test_sigterm_ends_a_sweep_with_exit_code_143(tmp_path):
    cfg = config(tmp_path, {"fixed": {**TINY, "lx": 0.38}, "sweep": {"axes": {"mu": [0.1, 0.2]}}})
    proc = subprocess.Popen([*KNITLAD, "sweep", str(cfg), "--out", str(tmp_path / "out"), "--workers", "1"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and not (tmp_path / "out" / LOCK_NAME).exists():
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "terminated" in err and "Traceback" not in err



def test_a_sigterm_during_a_submit_arrives_after_it():
    """The pool's submit runs with Ctrl-C and SIGTERM held, and the signal comes after the block."""
    from knitlad.studies.runner import _interrupts_deferred

    seen = []

    def note(signum, frame):
        seen.append(time.monotonic())

    previous = signal.signal(signal.SIGTERM, note)
    try:
        with _interrupts_deferred():
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
            held_until = time.monotonic()
            assert not seen
        assert signal.getsignal(signal.SIGTERM) is note and len(seen) == 1 and seen[0] >= held_until
    finally:
        signal.signal(signal.SIGTERM, previous)


# ------------------------------------------------------------------ hostile YAML
def alias_bomb(levels: int) -> str:
    """A few hundred bytes whose aliases of aliases expand to 9**levels values."""
    lines = ["a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, levels)]
    return "\n".join(lines + ["scene: ladder", f"fixed: {{lx: 0.4, n_x: *a{levels - 1}}}", "sweep: {axes: {mu: [0.4]}}"])


@pytest.mark.parametrize("text, reason", [
    (alias_bomb(9), "expands to more than"),  # 3.9e8 values: 58 s and 5.6 GB before the check
    ("scene: ladder\nfixed: " + "[" * 20_000 + "]" * 20_000 + "\n", "nested deeper than"),  # was RecursionError
    ("scene: ladder\nfixed: {lx: 0.4}\nsweep:\n  axes:\n    ? [mu]\n    : [0.4]\n", "mapping key must be a plain value"),
])
def test_hostile_yaml_is_refused_in_one_line_before_it_is_built(tmp_path, text, reason):
    path = tmp_path / "hostile.yaml"
    path.write_text(text)
    t = time.perf_counter()
    with pytest.raises(SweepError, match=reason):
        load_sweep(path)
    assert time.perf_counter() - t < 5.0
    assert reason in one_line_error(knitlad("sweep", str(path), "--dry-run"))


def test_a_validation_error_never_formats_the_whole_input(monkeypatch):
    """one_line reads the first error's message: str(ValidationError) formats the whole input, which took
    most of the 58 s of an alias bomb's one-line error."""
    from pydantic import ValidationError

    from knitlad.experiments.config import CutConfig, one_line

    with pytest.raises(ValidationError) as info:
        CutConfig(lx=0.4, n_x=list(range(1000)))

    def formatted(self):
        raise AssertionError("the whole input was formatted")

    monkeypatch.setattr(ValidationError, "__str__", formatted)
    assert one_line(info.value).startswith("n_x:")


# ------------------------------------------------------------------ absurd but valid physics
@pytest.mark.parametrize("option", ["--contact-damping-ratio", "--stretch-damping-ratio"])
def test_a_run_of_absurdly_many_steps_is_refused_before_its_first_step(option, tmp_path):
    """A dashpot of 1e6 x critical makes the step 5e-14 s: 5e11 steps for 30 ms (it ran silently for ever)."""
    p = knitlad("cut", "--stitches", "6x8", "--lx", "0.38", "--preset", "fast", option, "1e6",
                "--out", str(tmp_path / "o"))
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert "steps, over" in p.stderr.strip().splitlines()[-1]  # after the stretch's progress line
    assert not (tmp_path / "o").exists()


def test_a_step_longer_than_the_observation_interval_is_refused():
    """d/l0 = 1e-6 gave a 1.2 ms step against 20 us between observations: the run 'finished' in 2 steps."""
    from knitlad.experiments.config import CutConfig
    from knitlad.experiments.laddering import check_feasible
    from knitlad.fabric.preparation import InfeasibleRun

    dynamics = CutConfig(lx=0.38, preset="fast").dynamics_settings()
    check_feasible(1e-8, dynamics)
    with pytest.raises(InfeasibleRun, match="longer than the observation interval"):
        check_feasible(1.2e-3, dynamics)


# ------------------------------------------------------------------ the stretched-knit cache
@pytest.fixture(scope="module")
def tiny_knit():
    from knitlad.experiments.config import CutConfig
    from knitlad.fabric.preparation import stretch

    settings = CutConfig(n_x=4, n_y=4, lx=0.34, preset="fast", resolution=16).stretch_settings()
    return settings, stretch(settings)


def test_a_cache_that_cannot_be_written_costs_a_warning_not_the_job(tmp_path, tiny_knit):
    from knitlad.io.knit_cache import cached_stretch

    settings, knit = tiny_knit
    (tmp_path / "stretched").write_text("a regular file where the cache folder goes")
    with pytest.warns(RuntimeWarning, match="not kept"):
        got, reused = cached_stretch(settings, tmp_path / "stretched", lambda s, p: knit)
    assert got is knit and not reused


def test_a_read_only_cache_costs_a_warning_not_the_job(tmp_path, tiny_knit):
    from knitlad.io.knit_cache import cached_stretch

    settings, knit = tiny_knit
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("running as a user who writes into read-only folders")
        with pytest.warns(RuntimeWarning, match="not kept"):
            assert cached_stretch(settings, folder, lambda s, p: knit)[0] is knit
    finally:
        folder.chmod(0o700)


def test_a_cached_knit_with_an_edited_attribute_is_made_again_and_stale_temporaries_go(tmp_path, tiny_knit):
    """An fx_ini edited in the file came back as 99, exit 0; a .tmp of a killed writer stayed for ever."""
    from knitlad.io.knit_cache import cached_stretch, stretch_key

    settings, knit = tiny_knit
    folder = tmp_path / "stretched"
    made = []

    def stretch_again(s, p):
        made.append(1)
        return knit

    cached_stretch(settings, folder, stretch_again)
    path = folder / f"{stretch_key(settings)}.h5"
    with h5py.File(path, "r+") as f:
        f.attrs["fx_ini"] = 99.0
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = folder / f"{path.name}.{int(dead.stdout)}.tmp"
    stale.write_bytes(b"half a file")
    got, reused = cached_stretch(settings, folder, stretch_again)
    assert not reused and len(made) == 2 and got.fx_ini == knit.fx_ini
    assert not stale.exists()
    assert cached_stretch(settings, folder, stretch_again)[1]  # the remade file is reused


def test_the_cache_key_follows_the_code(tiny_knit, monkeypatch):
    """Keyed by the settings and the version only, a knit stretched by older code was reused after a fix."""
    from knitlad.io import knit_cache

    settings, _ = tiny_knit
    before = knit_cache.stretch_key(settings)
    monkeypatch.setattr(knit_cache, "source_hash", lambda: "other code")
    assert knit_cache.stretch_key(settings) != before


def test_an_absurd_count_is_said_briefly_and_max_jobs_lifts_every_limit(tmp_path):
    """A step of 1e-300 printed a 300-digit count; --max-jobs 20000 could not lift a per-axis cap of 10,000."""
    tiny = config(tmp_path, {"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": {"start": 0, "stop": 1,
                                                                                      "step": 1e-300}}}})
    with pytest.raises(SweepError) as e:
        load_sweep(tiny)
    assert len(str(e.value)) < 120 and "1e+300 jobs" in str(e.value)
    big = config(tmp_path, {"scene": "stitch", "fixed": {"ly": 0.25},
                            "sweep": {"axes": {"lx": {"start": 0.3, "stop": 0.4, "num": 15_000}}}}, "big.yaml")
    with pytest.raises(SweepError, match="max-jobs"):
        load_sweep(big)
    assert len(load_sweep(big, max_jobs=20_000)[1]) == 15_000


@pytest.mark.parametrize("field, text", [("mu", "0.4"), ("twist", "yes"), ("resolution", "24")])
def test_quoted_text_is_not_taken_for_a_number_or_a_yes(tmp_path, field, text):
    """mu: "0.4" and twist: "yes" were coerced silently."""
    cfg = config(tmp_path, {"fixed": {**TINY, "lx": 0.4, field: text}, "sweep": {"axes": {"mu" if field != "mu" else
                                                                                         "ly": [0.25]}}})
    with pytest.raises(SweepError, match=f"fixed.{field}: .* needed, got the text"):
        load_sweep(cfg)


@pytest.mark.process
def test_sigterm_to_cut_says_so_and_leaves_nothing(tmp_path):
    """It exited with no message. The signal is sent once the laddering runs (a fixed sleep let a cached
    stretch and a quick run finish first)."""
    out = tmp_path / "o"
    proc = subprocess.Popen([*KNITLAD, "cut", "--stitches", "6x8", "--lx", "0.38", "--preset", "fast", "--max-time-ms",
                             "3000", "--arrest-ms", "3000", "--out", str(out)],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = []
    reader = threading.Thread(target=lambda: seen.extend(iter(lambda: proc.stderr.read(1), "")), daemon=True)
    reader.start()
    deadline = time.monotonic() + 300
    while "propagate" not in "".join(seen) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=60)
    finally:
        proc.kill()
    reader.join(timeout=10)
    err = "".join(seen)
    assert proc.returncode == 143, err
    assert err.strip().splitlines()[-1] == "knitlad: terminated; nothing written" and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("reply", [None, b"HTTP/1.1 200 OK\r\nContent-Length: 5\r\n\r\nhello" * 3])
@pytest.mark.cluster
def test_an_address_that_answers_but_is_no_dask_scheduler_is_one_line_in_seconds(reply):
    """A server that accepts and stalls hung `--executor dask` for ever; an HTTP port gave a 40-line traceback."""
    import socket
    import threading

    pytest.importorskip("distributed")
    from knitlad.studies.runner import SCHEDULER_TIMEOUT_S, SchedulerError, connect

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held = []

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            held.append(conn)
            if reply:
                conn.recv(100)
                conn.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    t = time.perf_counter()
    try:
        with pytest.raises(SchedulerError) as e:
            connect(f"tcp://127.0.0.1:{server.getsockname()[1]}")
    finally:
        server.close()
    assert time.perf_counter() - t < SCHEDULER_TIMEOUT_S + 5
    assert "\n" not in str(e.value) and "--scheduler" in str(e.value)


def test_a_job_file_written_while_the_sweep_stopped_is_in_the_summary(tmp_path):
    """After Ctrl-C on Dask, tasks already past the cancel wrote their files 1-2 s later, and the summary
    still listed them as pending: the rows are taken from the trusted files once the workers are stopped."""
    from knitlad.studies.runner import SweepOutcome, _take_late_files, summary_row
    from tests.sweep_helpers import fast_ladder_scene

    jobs = fake_jobs(tmp_path, [0.1, 0.2])
    jobs_dir = tmp_path / "out" / "jobs"
    jobs_dir.mkdir(parents=True)
    with fast_ladder_scene():
        run_job(jobs[0], str(jobs_dir))  # finished after the interrupt: no row was made for it
    outcome = SweepOutcome(rows={job.id: summary_row(job, None) for job in jobs})
    _take_late_files(jobs, jobs_dir, outcome)
    assert [outcome.rows[job.id]["status"] for job in jobs] == ["ok", "pending"]


def test_the_summary_is_not_rewritten_after_every_job_and_is_whole_at_the_end(tmp_path, monkeypatch):
    """A 10,000-job sweep rewrote summary.csv after each job (0.22 s each, 36 min in all)."""
    from knitlad.studies import runner
    from tests.sweep_helpers import fake_runner

    writes = []
    real = runner.write_summary
    monkeypatch.setattr(runner, "write_summary", lambda out, rows: (writes.append(len(rows)), real(out, rows)))
    jobs = fake_jobs(tmp_path, [round(0.3 + 0.01 * k, 2) for k in range(30)])
    run_sweep(jobs, tmp_path / "out", workers=2, runner=fake_runner, progress=False)
    assert len(writes) < 10  # the plan, the end, and at most one per SUMMARY_EVERY_S
    assert list(read_summary(tmp_path / "out")["status"]) == ["ok"] * 30


def test_a_knit_stretched_until_it_comes_apart_is_no_result(tmp_path):
    """--lx 0.999 exited 0 with f_x^ini = -0.98: a compressive reading of a nearly straight yarn."""
    out = tmp_path / "o"
    p = knitlad("cut", "--stitches", "6x8", "--lx", "0.999", "--preset", "fast", "--resolution", "16", "--out", str(out))
    assert p.returncode == 1 and "Traceback" not in p.stderr, p.stderr
    assert "came apart" in p.stderr.strip().splitlines()[-1]
    assert not out.exists()


def test_force_stretches_again(tmp_path):
    """--force reran every job but reused the cached stretched knits."""
    from knitlad.studies.runner import run_sweep as sweep

    cached = tmp_path / "out" / "stretched"
    cached.mkdir(parents=True)
    (cached / "0123456789abcdef.h5").write_bytes(b"a knit stretched by older code")
    jobs = fake_jobs(tmp_path, [0.4])
    from tests.sweep_helpers import fake_runner

    sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False)
    assert (cached / "0123456789abcdef.h5").exists()
    sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=False, force=True)
    assert not list(cached.glob("*.h5"))


# ------------------------------------------------------------------ knitlad cut's folder (round 3)
CUT_TINY = ["cut", "--stitches", "6x8", "--lx", "0.40", "--preset", "fast", "--resolution", "16", "--max-time-ms",
            "0.3"]


def test_a_second_cut_into_a_folder_in_use_is_refused_in_one_line(tmp_path):
    """Two `cut` runs into one folder 2 s apart both exited 0 and the first printed 'wrote ladder.h5' while the
    folder held only the second's files. A run now owns its folder while it runs."""
    out = tmp_path / "out"
    out.mkdir()
    with FolderLock(out):  # a live run holds it (this process)
        p = knitlad(*CUT_TINY, "--out", str(out))
    assert "in use by another knitlad run" in one_line_error(p) and not (out / "ladder.h5").exists()
    p = knitlad(*CUT_TINY, "--out", str(out))  # free again: it runs, and leaves no lock behind
    assert p.returncode == 0, p.stderr
    assert (out / "ladder.h5").exists() and not (out / LOCK_NAME).exists()


@pytest.mark.process
def test_overwrite_on_a_full_disk_keeps_the_earlier_run(tmp_path):
    """`cut --overwrite` onto an earlier run, on a nearly full disk, deleted the earlier run first and then
    could not write the new one: only summary.json was left. The new run is written beside it first now."""
    import resource

    out = tmp_path / "out"
    assert knitlad(*CUT_TINY, "--out", str(out)).returncode == 0
    (out / "render").mkdir()
    before = {f.name: f.read_bytes() for f in out.iterdir() if f.is_file()}

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, 100_000))

    p = knitlad(*CUT_TINY, "--mu", "0.2", "--out", str(out), "--overwrite", preexec_fn=small_files)
    assert p.returncode == 1 and "could not be written" in p.stderr and "earlier run" in p.stderr
    assert {f.name: f.read_bytes() for f in out.iterdir() if f.is_file()} == before
    assert (out / "render").is_dir() and not list(out.glob(".new-*"))
    p = knitlad(*CUT_TINY, "--mu", "0.2", "--out", str(out), "--overwrite")  # room again: replaced, renders gone
    assert p.returncode == 0 and not (out / "render").exists() and (out / "ladder.h5").read_bytes() != before["ladder.h5"]


def test_a_cycle_whose_stretch_passes_its_lx_max_is_refused_after_the_stretch_in_one_line(tmp_path):
    """`cycle --fx 20 --lx-max 0.25` exited 0 with a negative stroke (Delta x_max - Delta x_min = -8.6 mm,
    f_x^ini -0.47); with --lx the same case was refused. Force control finds Delta x_min only by stretching:
    the run is refused then, naming lx_max, before any cycle."""
    p = knitlad("cycle", "--stitches", "6x8", "--preset", "fast", "--resolution", "16", "--fx", "20", "--lx-max", "0.3",
                "--out", str(tmp_path / "out"))
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    line = p.stderr.strip().splitlines()[-1]  # after the stretch's progress lines
    assert line.startswith("knitlad: error: lx_max: 0.3 is not above") and "the bars would move inwards" in line
    assert not (tmp_path / "out" / "cycle.h5").exists()


@pytest.mark.process
def test_a_cycle_keeps_an_earlier_runs_readings_and_says_a_full_disk_in_one_line(tmp_path):
    """A second `cycle` into a folder holding only an interrupted run's cycle.csv replaced it; on a full disk
    `cycle` ended in an OSError traceback, f_x^ini, delta l and the cut's result lost."""
    import resource

    out = tmp_path / "out"
    out.mkdir()
    (out / "cycle.csv").write_text("cycle,leg,t_s,box_lx_over_l0,fx\n0,0,0.0,0.3,0.68\n")
    args = ["cycle", "--stitches", "6x8", "--preset", "fast", "--resolution", "16", "--lx-max", "0.36", "--cycles", "1",
            "--hold-ms", "0.5", "--no-cut", "--fx-thr", "0.5"]
    assert "cycle.csv" in one_line_error(knitlad(*args, "--out", str(out)))
    assert (out / "cycle.csv").read_text().endswith("0.68\n")

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (300, 300))

    p = knitlad(*args, "--out", str(tmp_path / "full"), preexec_fn=small_files)
    assert p.returncode == 1 and "Traceback" not in p.stderr, p.stderr
    assert "could not be written" in p.stderr.strip().splitlines()[-1]
    # the stretched knit could not be kept either: said in one line, not as Python's warning with its source line
    assert "knitlad: warning: stretched knit not kept" in p.stderr and "RuntimeWarning" not in p.stderr, p.stderr
    summary = json.loads(p.stdout.strip().splitlines()[-1])
    assert summary["fx_ini"] > 0 and summary["delta_l_over_l0"] > 0


@pytest.mark.parametrize("what", ["dev_zero", "fifo", "folder", "huge"])
def test_a_sweep_or_cluster_file_that_is_no_config_file_is_refused_at_once(tmp_path, what):
    """`sweep /dev/zero` and `--cluster /dev/zero` read until memory ran out; a FIFO as the cluster file blocked
    forever. Both are refused in one line, at once (exit 2)."""
    path = tmp_path / "c.yaml"
    if what == "dev_zero":
        path = Path("/dev/zero")
    elif what == "fifo":
        os.mkfifo(path)
    elif what == "folder":
        path.mkdir()
    else:
        path.write_text("# " + "x" * (2 << 20))
    good = config(tmp_path, {"fixed": {**TINY, "lx": 0.4}, "sweep": {"axes": {"mu": [0.1]}}}, "good.yaml")
    for args in (["sweep", str(path), "--out", str(tmp_path / "o")],
                 ["sweep", str(good), "--cluster", str(path), "--dry-run", "--out", str(tmp_path / "o2")]):
        p = knitlad(*args, timeout=60)
        line = one_line_error(p)
        assert str(path) in line and ("not a config file" in line or "over the" in line), line


def test_a_cut_of_a_compressed_knit_is_refused_after_the_stretch_and_json_is_valid_json(tmp_path):
    """`cut --lx 0.2001` exited 0 with f_x^ini -2.03 (the knit in compression), and `loop --json` wrote
    `Infinity`, which is not JSON."""
    p = knitlad("cut", "--stitches", "4", "--lx", "0.2001", "--preset", "fast", "--max-time-ms", "0.1", "--out",
                str(tmp_path / "c"))
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert "not in tension" in p.stderr.strip().splitlines()[-1]
    p = knitlad("loop", "--max-time-ms", "1e-12", "--json")
    assert p.returncode == 0
    summary = json.loads(p.stdout.strip().splitlines()[-1], parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
    assert summary["tau_s"] is None and summary["released"] is False


def test_an_output_folder_that_is_a_link_to_nowhere_is_named_as_such(tmp_path):
    """A symbolic-link loop as --out was reported as "File exists"."""
    loop = tmp_path / "loop"
    loop.symlink_to(tmp_path / "loop")
    line = one_line_error(knitlad(*CUT_TINY, "--out", str(loop / "run")))
    assert "is a symbolic link that leads nowhere" in line


def test_a_kill_while_the_run_is_written_leaves_no_half_written_file(tmp_path, monkeypatch):
    """A SIGTERM while ladder.h5 was written left a 1.6 MB .tmp beside the run."""
    from knitlad import cli

    def killed(out_dir, result):
        (out_dir / "ladder.h5").write_bytes(b"half")
        raise cli.Terminated()

    monkeypatch.setattr(cli, "_write_run_outputs", killed)
    with pytest.raises(cli.Terminated):
        cli._replace_run_outputs(tmp_path, None, [])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.process
def test_a_cycle_stopped_by_ctrl_c_resumes_from_its_last_leg_to_the_same_curve(tmp_path):
    """`cycle` had no resume after Ctrl-C. After each leg it keeps a checkpoint; `--resume` goes on from it
    (with the same settings only) and reads the same curve, to the bit, as a run never stopped."""
    args = ["cycle", "--stitches", "6x8", "--preset", "fast", "--resolution", "16", "--lx-max", "0.36", "--cycles", "2",
            "--readings-per-leg", "2", "--hold-ms", "0.5", "--no-cut", "--fx-thr", "0.5"]
    whole = knitlad(*args, "--out", str(tmp_path / "whole"))
    assert whole.returncode == 0, whole.stderr
    out = tmp_path / "stopped"
    run = subprocess.Popen([*KNITLAD, *args, "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, cwd=ROOT)
    deadline = time.monotonic() + 600
    while not (out / "cycle.checkpoint.h5").exists() and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    run.send_signal(signal.SIGINT)
    _, stderr = run.communicate(timeout=120)
    assert run.returncode == 130 and "--resume" in stderr, stderr
    assert "--resume continues it" in one_line_error(knitlad(*args, "--out", str(out)))
    assert "other settings (mu)" in one_line_error(knitlad(*args, "--mu", "0.3", "--out", str(out), "--resume"))
    resumed = knitlad(*args, "--out", str(out), "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert (out / "cycle.csv").read_bytes() == (tmp_path / "whole" / "cycle.csv").read_bytes()
    assert not (out / "cycle.checkpoint.h5").exists() and not (out / "stretched").exists()
    assert "nothing to continue" in one_line_error(knitlad(*args, "--out", str(out), "--resume"))
    assert "no stopped run" in one_line_error(knitlad(*args, "--out", str(tmp_path / "new"), "--resume"))


@pytest.mark.parametrize("command", [["cycle", "--lx-max", "0.38"], ["tensile", "--lx-max", "0.38"], ["snag"],
                                     ["resistance"], ["cut"]])
def test_every_experiment_command_takes_the_folder_lock_before_any_compute(tmp_path, command):
    """Round 4: two `cycle` runs into one folder both exited 0 (only `cut` took the lock). A folder another run holds
    is refused in one line, exit 2, by every command (one prologue: cli._prologue), the lock left to its owner."""
    out = tmp_path / "busy"
    out.mkdir()
    with FolderLock(out):
        line = one_line_error(knitlad(*command, "--stitches", "6x8", "--preset", "fast", "--out", str(out)))
        assert "in use by another knitlad run" in line
        assert (out / LOCK_NAME).exists()


@pytest.mark.parametrize("command, files", [(["tensile", "--lx-max", "0.38"], ["tensile.csv"]),
                                            (["cycle", "--lx-max", "0.38"], ["cycle.csv"]),
                                            (["snag"], ["snag.h5"]), (["resistance"], ["resistance.h5"])])
def test_a_folder_holding_an_earlier_run_is_refused_by_every_command(tmp_path, command, files):
    """Round 4: `tensile` run twice into one folder replaced the first run's files without a word."""
    for name in files:
        (tmp_path / name).write_text("an earlier run\n")
    line = one_line_error(knitlad(*command, "--stitches", "6x8", "--preset", "fast", "--out", str(tmp_path)))
    assert "holds an earlier" in line
    assert all((tmp_path / name).read_text() == "an earlier run\n" for name in files)


@pytest.mark.parametrize("args, says", [
    (["snag", "--weak-point-force", "100", "--breaking-force", "1"], "--weak-point-force:"),
    (["snag", "--snag-row", "7", "--snag-column", "3"], "--snag-row:"),
    (["snag", "--snag-row", "3", "--snag-column", "0"], "--snag-column:"),
    (["cut", "--max-time-ms", "0.000001"], "--max-time-ms:"),
])
def test_settings_that_would_run_for_nothing_are_refused_before_anything_runs(tmp_path, args, says):
    """Round 4: a weak point stronger than the yarn, a snag on the knit's edge (146 s, "no break within 10 mm")
    and a run shorter than one observation (exit 0) were accepted without a word. The refusal names the option
    as it was given."""
    line = one_line_error(knitlad(*args, "--stitches", "8", "--preset", "fast", "--out", str(tmp_path / "o")))
    assert says in line and not (tmp_path / "o").exists()


def test_a_threshold_or_a_velocity_without_a_value_is_said_in_words_not_nan():
    """Round 4: "threshold: between nan and 2.00" and "v_lad/c_b = nan up"."""
    from knitlad.cli import _bracket_words, _speed_words

    nan = float("nan")
    assert _bracket_words(nan, 2.0) == "below 2.00 (every cut laddered)"
    assert _bracket_words(4.0, nan) == "above 4.00 (no cut laddered)"
    assert _bracket_words(2.0, 4.0) == "between 2.00 and 4.00"
    assert "nan" not in _speed_words({"v_lad_over_cb": nan}, "v_lad_over_cb")


@pytest.mark.process
def test_plot_into_a_folder_that_takes_no_figure_is_one_line_and_exit_1(tmp_path):
    """Round 4: `knitlad plot` on a read-only folder ended in tracebacks (OSError); here no file may grow."""
    import resource

    run = tmp_path / "run"
    assert knitlad("cut", "--stitches", "4x6", "--lx", "0.36", "--preset", "fast", "--resolution", "12",
                   "--max-time-ms", "0.1", "--out", str(run)).returncode == 0
    for png in run.glob("*.png"):
        png.unlink()

    def no_growth():
        resource.setrlimit(resource.RLIMIT_FSIZE, (0, 0))

    line = one_line_error(knitlad_process("plot", str(run), preexec_fn=no_growth), code=1)
    assert "the figures could not be written" in line


def test_a_tensile_top_below_its_start_is_refused_as_the_cycles_is(tmp_path):
    """Round 4: `tensile --fx 20 --lx-max 0.25` ran (top f_x -0.467); `--lx 0.36 --lx-max 0.30` likewise."""
    line = one_line_error(knitlad("tensile", "--stitches", "6x8", "--preset", "fast", "--lx", "0.36", "--lx-max",
                                  "0.30", "--out", str(tmp_path / "a")))
    assert "--lx-max: 0.3 is not above the start lx" in line
    p = knitlad("tensile", "--stitches", "6x8", "--preset", "fast", "--fx", "20", "--lx-max", "0.25", "--out",
                str(tmp_path / "b"))
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    line = p.stderr.strip().splitlines()[-1]  # after the stretch's progress lines: force control finds the start
    assert "the bars would move inwards" in line and not (tmp_path / "b" / "tensile.csv").exists()


@pytest.mark.end_to_end
def test_a_resume_trusts_no_part_of_an_edited_checkpoint(tmp_path, monkeypatch):
    """Round 4: an edited but valid checkpoint gave tracebacks (config_json not JSON, cycle/done 99, a dataset
    deleted) or wrong names (NaN in state/x: "by_m or rails_by_m ..."; clock -1: "drag must be >= 0"), and NaN
    readings ran on into cycle.csv. Each is now one line naming what is wrong, exit 2, nothing run."""
    import knitlad.io.hdf5 as hdf5

    args = ["cycle", "--stitches", "6x8", "--preset", "fast", "--resolution", "16", "--lx-max", "0.36", "--cycles", "2",
            "--readings-per-leg", "2", "--hold-ms", "0.5", "--no-cut", "--fx-thr", "0.5"]
    write = hdf5.write_arrays

    def stopped_after_the_first(path, arrays, attrs=None):
        write(path, arrays, attrs)
        raise KeyboardInterrupt  # Ctrl-C once the first leg's checkpoint is kept

    monkeypatch.setattr(hdf5, "write_arrays", stopped_after_the_first)
    out = tmp_path / "stopped"
    assert knitlad(*args, "--out", str(out)).returncode == 130
    monkeypatch.setattr(hdf5, "write_arrays", write)
    kept = (out / "cycle.checkpoint.h5").read_bytes()

    def edited(change) -> str:
        (out / "cycle.checkpoint.h5").write_bytes(kept)
        with h5py.File(out / "cycle.checkpoint.h5", "r+") as f:
            change(f)
        return one_line_error(knitlad(*args, "--out", str(out), "--resume"))

    def replace(name, value):
        def change(f):
            del f[name]
            f[name] = value
        return change

    readings = np.array(h5py.File(out / "cycle.checkpoint.h5", "r")["cycle/readings"])
    x = np.array(h5py.File(out / "cycle.checkpoint.h5", "r")["state/x"])
    clock = np.array(h5py.File(out / "cycle.checkpoint.h5", "r")["clock"])
    assert "cycle/readings holds NaN" in edited(replace("cycle/readings", np.full_like(readings, np.nan)))
    assert "cycle/done is [99, 1]" in edited(replace("cycle/done", np.array([99, 1])))
    assert "has no cycle/box_lx" in edited(lambda f: f.__delitem__("cycle/box_lx"))
    assert "state/x holds NaN" in edited(replace("state/x", np.where(x == x, np.nan, x)))
    assert "clock holds a negative" in edited(replace("clock", np.concatenate([[-1.0], clock[1:]])))
    assert "is damaged" in edited(lambda f: f.attrs.__setitem__("config_json", "{not json"))
    assert not (out / "cycle.h5").exists()


@pytest.mark.process
def test_a_tensile_test_that_cannot_write_its_files_leaves_none_of_them(tmp_path):
    """Round 4: on a 64 kB disk `tensile` said "files could not be written" yet left tensile.csv and tensile.h5."""
    import resource

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))

    out = tmp_path / "out"
    p = knitlad_process("tensile", "--stitches", "6x8", "--preset", "fast", "--lx", "0.36", "--lx-max", "0.37",
                        "--readings-per-leg", "2", "--hold-ms", "0.2", "--out", str(out), preexec_fn=small_files)
    assert p.returncode == 1 and "could not be written" in p.stderr.strip().splitlines()[-1], p.stderr
    assert not out.exists() or not [f.name for f in out.iterdir() if f.name.startswith("tensile")]


def test_a_preset_axis_with_the_authors_preset_changes_what_the_accuracy_settings_leave_open(tmp_path):
    """The four settings every preset fills are given; the authors' preset fills more (twist, its drag, its
    dashpots), so an axis over fast and crassous2023 still changes the runs: expanded, not refused."""
    fixed = {**{k: v for k, v in TINY.items() if k != "preset"}, "lx": 0.4, "resolution": 16, "sagitta_radius": 0,
             "implicit_axial": False, "dt_safety": 0.35}
    jobs = load_sweep(config(tmp_path, {"fixed": fixed, "sweep": {"axes": {"preset": ["fast", "crassous2023"]}}}))[1]
    assert len(jobs) == 2 and {j.params["preset"] for j in jobs} == {"fast", "crassous2023"}
