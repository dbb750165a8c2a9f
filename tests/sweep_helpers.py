"""Job runners for the sweep tests, importable by spawned pool workers."""

from __future__ import annotations

import os

from knitlad.io.hdf5 import write_record
from knitlad.runner import _record, job_path, summary_row


def fake_runner(job, jobs_dir: str, threads: int = 1) -> dict:
    """Instant job: records ok; the job with mu == 0 kills its worker process instead."""
    if job.params["mu"] == 0.0:
        os._exit(3)  # a segfault or the OOM killer, as the pool sees it
    record = _record(job, "ok", "", 0.0)
    record["fx_ini"] = 10 * job.params["mu"]
    write_record(job_path(jobs_dir, job), record)
    return summary_row(job, record)
