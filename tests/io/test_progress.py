"""Progress lines (knitlad.io.progress) and the sweep's line that moves inside a running job."""

from __future__ import annotations

import io

import pytest

from knitlad.io import progress as pg
from knitlad.io.progress import ProgressFile, ProgressLine, duration, job_fraction


def test_durations_read_as_seconds_minutes_or_hours():
    assert (duration(42.4), duration(185), duration(7620), duration(float("nan"))) == ("42 s", "3m05s", "2h07m", "?")


def test_a_log_gets_a_line_at_most_every_interval_and_the_end_once(monkeypatch):
    clock = [0.0]
    monkeypatch.setattr(pg.time, "perf_counter", lambda: clock[0])
    out = io.StringIO()
    line = ProgressLine("sweep", 10, "jobs", stream=out, tty=False, log_every_s=30.0)
    for k in range(1, 11):
        clock[0] = 5.0 * k
        line.update(k)
    line.close()
    lines = out.getvalue().splitlines()
    # the first update, one at 30 s (after 25 s of silence: 35 s), and the end (50 s), drawn once
    assert [ln.split("]")[1].split()[0] for ln in lines] == ["1/10", "7/10", "10/10"], lines
    assert "0.2 jobs/s" in lines[-1] and "ETA 0 s" in lines[-1]


def test_no_rate_or_time_left_is_claimed_from_the_first_instants(monkeypatch):
    clock = [0.0]
    monkeypatch.setattr(pg.time, "perf_counter", lambda: clock[0])
    line = ProgressLine("movie", 100, "frames", stream=io.StringIO(), tty=False)
    clock[0] = 0.01
    line.update(1)
    assert "/s" not in line.text() and "ETA ?" in line.text()
    clock[0] = 2.0
    line.update(50)
    assert "25 frames/s" in line.text() and "ETA 2 s" in line.text()


def test_a_terminal_line_is_redrawn_in_place():
    out = io.StringIO()
    line = ProgressLine("stretch", 1.0, "%", stream=out, tty=True)
    line.update(0.5, force=True)
    line.close()
    assert out.getvalue().startswith("\r") and out.getvalue().endswith("\n") and out.getvalue().count("\n") == 1
    assert "100%" not in out.getvalue() and " 50%" in out.getvalue()


def test_a_progress_file_carries_stage_and_fraction_and_a_torn_one_reads_as_none(tmp_path):
    path = tmp_path / "job.progress"
    report = ProgressFile(path, every_s=0.0)
    report("propagate", 0.25)
    assert ProgressFile.read(path) == ("propagate", 0.25)
    path.write_text("propag")  # as a reader could see it, were the write not atomic
    assert ProgressFile.read(path) is None
    report.clear()
    assert not path.exists() and ProgressFile.read(path) is None


def test_a_job_is_a_tenth_done_when_its_stretch_ends():
    assert job_fraction("stretch", 1.0) == pytest.approx(0.1)
    assert job_fraction("propagate", 0.5) == pytest.approx(0.55)


def test_the_sweep_line_counts_the_running_jobs_own_progress(tmp_path):
    from knitlad.studies.runner import SweepProgress

    ProgressFile(tmp_path / "a.progress", every_s=0.0)("propagate", 0.5)
    ProgressFile(tmp_path / "b.progress", every_s=0.0)("stretch", 1.0)
    bar = SweepProgress(5, 1, stream=io.StringIO(), jobs_dir=tmp_path)
    bar.update("ok")
    try:
        assert bar.line.done == pytest.approx(1 + 0.55 + 0.1)
        assert "running: propagate 55% stretch 10%" in bar.line.note and "1 already done" in bar.line.note
    finally:
        bar.close()
    assert bar.line.done == 1


def test_a_laddering_job_reports_its_stages_and_leaves_no_progress_file(tmp_path, monkeypatch):
    """run_job hands the scene a progress file; the stretch and the ladder report through it."""
    from knitlad.studies import runner
    from knitlad.studies.sweep import Job, Output

    seen = []

    class Recording(ProgressFile):
        def __call__(self, stage, fraction):
            seen.append((stage, fraction))
            super().__call__(stage, fraction)

    monkeypatch.setattr(runner, "ProgressFile", Recording)
    job = Job(scene="ladder", params={"n_x": 4, "n_y": 6, "lx": 0.40, "preset": "fast", "resolution": 12,
                                      "max_time_ms": 0.05, "observe_every_us": 5.0, "arrest_ms": 0.05},
              output=Output(frames=False))
    (tmp_path / "jobs").mkdir()
    row = runner.run_job(job, str(tmp_path / "jobs"), 1)
    assert row["status"] == "ok", row["error"]
    stages = [s for s, _ in seen]
    assert stages[0] == "stretch" and "propagate" in stages
    assert all(0.0 <= f <= 1.0 for _, f in seen)
    assert not list((tmp_path / "jobs").glob("*.progress*"))


def test_a_progress_file_that_is_not_a_stage_and_a_fraction_is_ignored_never_raised_on(tmp_path):
    """A progress file holding ``stretch nan`` (a NaN tension in the stretch wrote exactly that), an infinite
    fraction, a link to /dev/zero (read_text never ended), a folder, or a FIFO (open blocked forever) reads as
    None, at once; a NaN fraction is written as 0."""
    import math
    import os

    cases = {"nan": "stretch nan\n", "inf": "stretch inf\n", "big": "stretch 2.5\n", "junk": "x" * 10_000}
    for name, text in cases.items():
        (tmp_path / f"{name}.progress").write_text(text)
        assert ProgressFile.read(tmp_path / f"{name}.progress") is None, name
    (tmp_path / "zero.progress").symlink_to("/dev/zero")
    (tmp_path / "dir.progress").mkdir()
    os.mkfifo(tmp_path / "fifo.progress")
    for name in ("zero", "dir", "fifo"):
        assert ProgressFile.read(tmp_path / f"{name}.progress") is None, name
    report = ProgressFile(tmp_path / "job.progress", every_s=0.0)
    report("stretch", math.nan)
    assert ProgressFile.read(tmp_path / "job.progress") == ("stretch", 0.0)


def test_a_bad_progress_file_never_touches_a_finished_job(tmp_path):
    """The sweep's progress line, redrawn as jobs finish, read a ``stretch nan`` progress file and raised inside
    ``finish``; the pool took that for the job's failure and wrote a ``failed`` record over the finished job's
    file, and the sweep died with three jobs left. Progress is a courtesy: every job ends ok."""
    from knitlad.studies.runner import run_sweep
    from knitlad.studies.sweep import load_sweep
    from tests.studies.test_sweep import TINY, read_summary, write_config
    from tests.sweep_helpers import progress_spoiling_runner

    _, jobs = load_sweep(write_config(tmp_path / "c.yaml", {"fixed": {**TINY, "lx": 0.4},
                                                             "sweep": {"axes": {"mu": [0.1, 0.3, 0.4, 0.5]}}}))
    outcome = run_sweep(jobs, tmp_path / "out", workers=1, runner=progress_spoiling_runner, progress=True)
    assert outcome.failed == 0 and list(read_summary(tmp_path / "out")["status"]) == ["ok"] * 4


def test_folders_named_like_progress_or_temporary_files_do_not_stop_a_sweep(tmp_path):
    """A folder ``jobs/x.progress`` or ``jobs/x.h5.tmp`` raised IsADirectoryError where the sweep clears the
    files its killed jobs left; it is left alone now, and the jobs run."""
    from knitlad.studies.runner import run_sweep
    from knitlad.studies.sweep import load_sweep
    from tests.studies.test_sweep import TINY, read_summary, write_config
    from tests.sweep_helpers import fake_runner

    _, jobs = load_sweep(write_config(tmp_path / "c.yaml", {"fixed": {**TINY, "lx": 0.4},
                                                             "sweep": {"axes": {"mu": [0.1, 0.3]}}}))
    for name in ("x.progress", "x.h5.tmp"):
        (tmp_path / "out" / "jobs" / name).mkdir(parents=True)
    outcome = run_sweep(jobs, tmp_path / "out", workers=1, runner=fake_runner, progress=True)
    assert outcome.failed == 0 and list(read_summary(tmp_path / "out")["status"]) == ["ok"] * 2
