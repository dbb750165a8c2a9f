"""Job runners for the sweep tests, importable by spawned pool workers."""

from __future__ import annotations

import contextlib
import dataclasses
import os

from knitlad.io.hdf5 import write_record
from knitlad.studies.runner import _record, job_path, summary_row


def fake_runner(job, jobs_dir: str, threads: int = 1, token=None) -> dict:
    """Instant job: records ok; the job with mu == 0 kills its worker process instead, the one
    with mu == 0.2 fails to write its file (a full disk)."""
    if job.params["mu"] == 0.0:
        os._exit(3)  # a segfault or the OOM killer, as the pool sees it
    if job.params["mu"] == 0.2:
        raise OSError(28, "No space left on device")
    record = _record(job, "ok", "", 0.0)
    record["fx_ini"] = 10 * job.params["mu"]
    write_record(job_path(jobs_dir, job), record)
    return summary_row(job, record)


def progress_spoiling_runner(job, jobs_dir: str, threads: int = 1, token=None) -> dict:
    """:func:`fake_runner`, having first left beside its job a progress file holding ``stretch nan``, as a
    stretch whose tension went NaN wrote one."""
    with open(os.path.join(jobs_dir, "other.progress"), "w") as f:
        f.write("stretch nan\n")
    return fake_runner(job, jobs_dir, threads, token)


@contextlib.contextmanager
def fast_ladder_scene():
    """In this process, the ladder scene's runner returns at once (a summary and a writer of a record)."""
    from knitlad.studies import registry

    def instant(cfg, output, folder=None, progress=None):
        return registry.Finished(None, {"fx_ini": 1.0}, lambda path, record: write_record(path, record))

    saved = registry.EXPERIMENTS["ladder"]
    registry.EXPERIMENTS["ladder"] = dataclasses.replace(saved, run=instant)
    try:
        yield
    finally:
        registry.EXPERIMENTS["ladder"] = saved
