"""knitlad/studies/cluster.py: a batch cluster's file, refused in one line when it cannot work; a dry run starts
nothing."""

import sys
import time
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
KNITLAD = [sys.executable, "-m", "knitlad.cli"]
SWEEP = {"scene": "ladder", "fixed": {"n_x": 4, "n_y": 6, "preset": "fast", "resolution": 12, "lx": 0.40,
                                      "max_time_ms": 0.05}, "sweep": {"axes": {"mu": [0.4]}}}


def knitlad(*args, env=None):
    from tests.conftest import knitlad as run

    return run(*args, env=env, timeout=120)


def files(tmp_path, cluster: dict):
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(SWEEP))
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(cluster))
    return str(tmp_path / "s.yaml"), str(tmp_path / "c.yaml")




def one_line(p, code=2) -> str:
    assert p.returncode == code, (p.returncode, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert "Traceback" not in p.stderr, p.stderr
    return lines[-1]


def test_a_batch_cluster_without_its_submit_command_is_refused_before_anything_starts(tmp_path):
    """With no sbatch, `--cluster` printed three tracebacks and the sweep hung at 0/1."""
    import os
    import shutil

    if shutil.which("sbatch"):
        pytest.skip("this machine has sbatch")
    sweep, cluster = files(tmp_path, {"kind": "slurm", "jobs": 1, "options": {"walltime": "00:10:00"}})
    p = knitlad("sweep", sweep, "--cluster", cluster, "--out", str(tmp_path / "o"), env={**os.environ})
    assert "sbatch, which is not on this machine's PATH" in one_line(p)


def test_a_dry_run_prints_the_workers_script_and_starts_no_scheduler(tmp_path):
    """`--cluster --dry-run` started a Dask scheduler and a dashboard listening on all interfaces."""
    sweep, cluster = files(tmp_path, {"kind": "slurm", "jobs": 2, "options": {"walltime": "00:10:00"}})
    t0 = time.perf_counter()
    p = knitlad("sweep", sweep, "--cluster", cluster, "--dry-run", "--out", str(tmp_path / "o"))
    assert p.returncode == 0, p.stderr
    assert "#SBATCH -t 00:10:00" in p.stdout and "tcp://SCHEDULER:8786" in p.stdout
    assert "dashboard" not in p.stderr.lower() and "scheduler at" not in p.stderr.lower()
    assert time.perf_counter() - t0 < 60


@pytest.mark.parametrize("change, says", [({"jobs": True}, "jobs"), ({"options": {"walltime": 5}}, "walltime"),
                                          ({"executor": "pool"}, "--executor pool")])
def test_settings_taken_silently_before_are_refused(tmp_path, change, says):
    """`--cluster` with `--executor pool`, `jobs: true` (read as 1) and `walltime: 5` were accepted."""
    cfg = {"kind": "slurm", "jobs": 1, "options": {"walltime": "00:10:00"}}
    executor = change.pop("executor", None)
    cfg.update(change)
    sweep, cluster = files(tmp_path, cfg)
    args = ["sweep", sweep, "--cluster", cluster, "--dry-run", "--out", str(tmp_path / "o")]
    p = knitlad(*args, *(["--executor", executor] if executor else []))
    assert says in one_line(p)


def test_the_dashboard_of_a_cluster_listens_on_loopback_unless_asked():
    from knitlad.studies.cluster import ClusterConfig

    assert ClusterConfig(kind="local", jobs=1)._options()["scheduler_options"]["dashboard_address"].startswith("127.0.0.1")
    asked = ClusterConfig(kind="local", jobs=1, options={"scheduler_options": {"dashboard_address": ":8787"}})
    assert asked._options()["scheduler_options"]["dashboard_address"] == ":8787"


def test_a_local_clusters_python_that_is_not_on_this_machine_is_refused_before_anything_starts(tmp_path):
    sweep, cluster = files(tmp_path, {"kind": "local", "jobs": 1, "options": {"python": "/nonexistent/python"}})
    p = knitlad("sweep", sweep, "--cluster", cluster, "--out", str(tmp_path / "o"))
    assert "options: python: '/nonexistent/python' is not an executable" in one_line(p)
    assert not (tmp_path / "o").exists()


@pytest.mark.cluster
def test_a_local_worker_that_cannot_start_is_one_line_at_once(tmp_path):
    """A local worker that failed at its start gave five tracebacks of distributed and dask-jobqueue (ending in
    "int() argument must be ... not 'NoneType'") and exit 1, or a two-minute wait."""
    sweep, cluster = files(tmp_path, {"kind": "local", "jobs": 1,
                                      "options": {"worker_extra_args": ["--nthreads", "banana"]}})
    t0 = time.perf_counter()
    p = knitlad("sweep", sweep, "--cluster", cluster, "--out", str(tmp_path / "o"))
    assert "every local worker exited at its start" in one_line(p)
    assert "ERROR" not in p.stderr and "NoneType" not in p.stderr, p.stderr
    assert time.perf_counter() - t0 < 60
