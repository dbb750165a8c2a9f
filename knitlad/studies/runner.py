"""Running sweep jobs: one job in a worker, many in a process pool or on a Dask cluster.

Layout of a sweep folder::

    DIR/jobs/<id>.h5     one file per job (its resolved config, status, error, results)
    DIR/summary.csv      one row per job of the config (pending, ok or failed)
    DIR/summary.parquet  the same, when pyarrow is installed
    DIR/sweep.yaml       the config that was run

A job's file appears only when the job has finished (atomic rename), so the
folder never holds a half-written result: after a crash or Ctrl-C, rerunning the
same command runs only the jobs without a file.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
import traceback
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Callable

from knitlad import __version__
from knitlad.studies.cluster import ClusterConfig
from knitlad.io.atomic import atomic_path
from knitlad.io.folders import FolderLock, lock_holds, writable_folder
from knitlad.io.hdf5 import read_attrs, verify_datasets, write_record
from knitlad.io.summary import write_summary
from knitlad.studies.ensemble import with_collapsed_members
from knitlad.io.progress import ProgressFile, ProgressLine, job_fraction
from knitlad.studies.columns import write_column_dictionary
from knitlad.io.provenance import code_identity
from knitlad.studies.registry import EXPERIMENTS
from knitlad.studies.sweep import Job, SweepError


def job_path(jobs_dir: str | Path, job: Job) -> Path:
    return Path(jobs_dir) / f"{job.id}.h5"


def _record(job: Job, status: str, error: str = "", wall_s: float = float("nan")) -> dict:
    return {
        "job_id": job.id,
        "status": status,
        "error": error,
        "job_json": job.model_dump_json(),
        "knitlad_version": __version__,
        "knitlad_code": code_identity(),
        "job_wall_s": wall_s,
    }


ABANDONED = "abandoned: the sweep that started this job has stopped; its result was not written"


def _one_line(e: BaseException) -> str:
    return f"{type(e).__name__}: {e}".splitlines()[0]


def run_job(job: Job, jobs_dir: str, threads: int | None = 1, token: str | None = None) -> dict:
    """Run one job and write its file; returns its summary row. Never raises for a failed run.

    ``threads``: Numba threads for this job (1 in a pool: the pool is the parallelism).
    ``token``: the sweep's folder lock; the file is written only while the lock holds it
    (a job that outlives its sweep writes nothing). A failed write fails this job alone.
    """
    import numba

    if threads:
        numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    path = job_path(jobs_dir, job)
    t0 = time.perf_counter()
    progress = ProgressFile(path.with_suffix(".progress"))  # read by the sweep's progress line
    try:
        finished = EXPERIMENTS[job.scene].run(job.scene_config(), job.output, Path(jobs_dir).parent, progress)
        summary, write = finished.summary, finished.write  # a job keeps the run file alone, not its companions
        record = _record(job, "ok", "", time.perf_counter() - t0)
    except KeyboardInterrupt:
        raise
    except Exception as e:  # noqa: BLE001 - any failure of one job is recorded and the sweep goes on
        record = _record(job, "failed", _one_line(e), time.perf_counter() - t0)
        record["traceback"] = traceback.format_exc()
        summary, write = {}, lambda p, r: write_record(p, r)
    finally:
        progress.clear()
    if token is not None and not lock_holds(Path(jobs_dir).parent, token):
        return summary_row(job, None) | {"error": ABANDONED}
    try:
        write(path, record)
    except Exception as e:  # noqa: BLE001 - a full disk or an I/O error: this job fails, the sweep goes on
        record = _record(job, "failed", f"cannot write the job's file: {_one_line(e)}", time.perf_counter() - t0)
        try:
            write_record(path, record)
        except Exception:  # noqa: BLE001 - not even the failure could be recorded: the row says it
            pass
        return summary_row(job, record)
    return summary_row(job, {**summary, **record})


def summary_row(job: Job, attrs: dict | None) -> dict:
    """One table row: the job's inputs, then its status and results."""
    # a yarn's mapping as one JSON cell, not a Python repr
    row = {"job_id": job.id, "scene": job.scene,
           **{k: json.dumps(v) if isinstance(v, dict) else v for k, v in job.params.items()}}
    if job.fx_nominal is not None:  # a member of an ensemble: its point's target, and which knit
        row.update(fx_nominal=job.fx_nominal, ensemble_member=job.ensemble_member, ensemble_point=job.point)
    if attrs is None:
        return {**row, "status": "pending", "error": ""}
    row["status"] = attrs.get("status", "ok")
    row["error"] = attrs.get("error", "")
    row["knitlad_code"] = made_by(attrs)
    for key in EXPERIMENTS[job.scene].summary_keys:
        value = attrs.get(key, float("nan"))
        row[key] = json.dumps(value) if isinstance(value, (list, dict)) else value
    return row


def trusted_attrs(path: Path, job: Job) -> tuple[dict | None, str]:
    """(the file's attributes, "") if ``path`` is ``job``'s file and intact, else (None, why not).

    Its file: the recorded id and resolved config are the job's (a copied or left-over file
    is not). Intact: every dataset reads back with its checksum (fletcher32)."""
    if not path.exists():
        return None, ""
    try:
        attrs = read_attrs(path)
        verify_datasets(path)
    except Exception as e:  # noqa: BLE001 - any unreadable file is not trusted
        return None, f"its file was unreadable or damaged ({_one_line(e)})"
    if attrs.get("job_id") != job.id:
        return None, f"its file belongs to job {attrs.get('job_id')!r}"
    raw = attrs.get("job_json")
    try:
        recorded = Job.model_validate(raw) if isinstance(raw, dict) else Job.model_validate_json(raw or "")
        same = recorded == job or same_configuration(recorded, job)
    except ValueError:
        same = False
    if not same:
        return None, "its file records another configuration"
    return attrs, ""


def same_configuration(recorded: Job, job: Job) -> bool:
    """The two jobs are one run in today's terms: a file written before a field was added to the
    scene's config records no value for it, and reads as that field's default."""
    return (recorded.scene, recorded.output) == (job.scene, job.output) and \
        recorded.scene_config() == job.scene_config()


# ---------------------------------------------------------------------- driver
@dataclass
class SweepOutcome:
    rows: dict[str, dict] = field(default_factory=dict)  # job id -> row, in config order
    ran: int = 0
    failed: int = 0
    skipped: int = 0
    interrupted: bool = False
    terminated: bool = False  # by SIGTERM (exit 143), else Ctrl-C (exit 130)
    stale: list[str] = field(default_factory=list)  # finished jobs whose file another code made, kept

    @property
    def failed_rows(self) -> list[dict]:
        """Every failed job of the sweep, run this time or before."""
        return [row for row in self.rows.values() if row["status"] == "failed"]


class SweepProgress:
    """The sweep's progress line on stderr (:class:`~knitlad.io.progress.ProgressLine`): jobs done, counting the
    running jobs' own progress (read from their progress files in ``jobs_dir`` by a watcher thread, so
    that the line moves inside a job of an hour), failed and skipped jobs, rate and time left."""

    WATCH_S = 1.0

    def __init__(self, total: int, skipped: int, stream=None, jobs_dir: Path | None = None) -> None:
        self.skipped, self.done, self.failed = skipped, 0, 0
        self.line = ProgressLine("sweep", total - skipped, "jobs", stream)
        self.jobs_dir = jobs_dir
        self._stop = threading.Event()
        self._watcher = None
        self.draw(force=True)
        if jobs_dir is not None:
            self._watcher = threading.Thread(target=self._watch, name="knitlad-sweep-progress", daemon=True)
            self._watcher.start()

    def running(self) -> list[tuple[str, float]]:
        """(stage, fraction of the job) of each job that reports its progress now."""
        if self.jobs_dir is None:
            return []
        found = (ProgressFile.read(p) for p in sorted(Path(self.jobs_dir).glob("*.progress")))
        return [(stage, job_fraction(stage, frac)) for stage, frac in (r for r in found if r is not None)]

    def update(self, status: str) -> None:
        self.done += 1
        self.failed += status != "ok"
        self.draw(force=not self.line.tty)

    def draw(self, force: bool = False) -> None:
        running = self.running()
        note = f"{self.failed} failed" + (f", {self.skipped} already done" if self.skipped else "")
        if running:
            note += ", running: " + " ".join(f"{stage} {100 * frac:.0f}%" for stage, frac in running[:4])
        self.line.update(self.done + sum(frac for _, frac in running), note, force=force)

    def _watch(self) -> None:
        while not self._stop.wait(self.WATCH_S):
            self.draw()

    def close(self) -> None:
        self._stop.set()
        if self._watcher is not None:
            self._watcher.join()
        self.line.update(self.done, self.line.note.split(", running")[0])
        self.line.close()


def _init_worker() -> None:
    """Pool worker set-up: leave Ctrl-C to the parent, and die with it.

    Ctrl-C goes to the whole process group: the parent alone decides what to
    keep. If the parent is killed outright (SIGKILL, OOM killer), Linux sends the
    worker SIGTERM (PR_SET_PDEATHSIG) instead of leaving it to compute on as an
    orphan (seen: orphans finishing stale jobs an hour later).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass


class _Terminated(KeyboardInterrupt):
    """SIGTERM (kill, a batch system ending the job): handled as Ctrl-C."""


def _on_sigterm(signum, frame):
    raise _Terminated()


def compile_kernels() -> None:
    """Compile (or load from Numba's cache) every kernel a laddering job uses, on a tiny knit.

    Run once in the parent before a pool starts, so that on a fresh clone the
    workers load the cache instead of each compiling the same kernels.
    """
    from knitlad.experiments.config import CutConfig
    from knitlad.experiments.laddering import run_ladder

    run_ladder(CutConfig(n_x=4, n_y=6, lx=0.40, preset="fast", resolution=12, steps_per_increment=5, max_time_ms=5e-3,
                         observe_every_us=5.0, arrest_ms=5e-3).settings())


Runner = Callable[[Job, str, int, str], dict]  # (job, jobs folder, threads, lock token) -> summary row
WORKER_DIED = "worker process died (killed, out of memory or crashed)"


def made_by(attrs: dict) -> str:
    """The code that wrote a job file (files older than the record hold their version only)."""
    return str(attrs.get("knitlad_code", attrs.get("knitlad_version", "")))


def _plan(jobs: list[Job], jobs_dir: Path, force: bool, retry_failed: bool, outcome: SweepOutcome,
          rerun_stale: bool = False) -> list[Job]:
    """The jobs to run; the rows of the others. A job file that is not the job's own or is
    damaged is not trusted: the job runs again and its row says why until then. One that
    another code made is kept and listed in ``outcome.stale`` (run again with ``rerun_stale``)."""
    todo = []
    for job in jobs:
        attrs, why = (None, "") if force else trusted_attrs(job_path(jobs_dir, job), job)
        if attrs is not None and made_by(attrs) != code_identity():
            if rerun_stale:
                attrs, why = None, f"made by knitlad {made_by(attrs)}"
            else:
                outcome.stale.append(job.id)
        if attrs is not None and (attrs.get("status") == "ok" or not retry_failed):
            outcome.rows[job.id] = summary_row(job, attrs)
            outcome.skipped += 1
        else:
            outcome.rows[job.id] = summary_row(job, None) | ({"error": f"to rerun: {why}"} if why else {})
            todo.append(job)
    return todo


def _sharing_first(todo: list[Job]) -> list[Job]:
    """The first job of each group that shares work (a stretched knit) first, then the others:
    by the time a job that can reuse the work starts, the work is usually done."""
    rank, seen = {}, {}
    for job in todo:
        share = EXPERIMENTS[job.scene].shared_work
        key = (job.scene, share(job.scene_config())) if share else (job.scene, job.id)
        rank[job.id] = seen.get(key, 0)
        seen[key] = rank[job.id] + 1
    return sorted(todo, key=lambda job: rank[job.id])  # stable: config order within a rank


def run_sweep(
    jobs: list[Job],
    out_dir: str | Path,
    executor: str = "pool",
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    retry_failed: bool = False,
    progress: bool = True,
    runner: Runner = run_job,
    config_text: str | None = None,
    rerun_stale: bool = False,
) -> SweepOutcome:
    """Run the jobs that have no trusted file yet (all with ``force``; failed ones too with ``retry_failed``).

    The folder is checked and locked first (:mod:`knitlad.io.folders`: one sweep at a time;
    :class:`~knitlad.io.folders.FolderError` before anything runs). The summary is rewritten
    every few seconds and once more at the end, also after Ctrl-C or SIGTERM (then
    ``interrupted`` is set, the workers are stopped and the unfinished jobs stay pending).
    Finished jobs whose file another code made are kept and listed in ``outcome.stale``, or
    run again with ``rerun_stale``.
    """
    outcome = SweepOutcome()
    # SIGTERM is handled as Ctrl-C from the start: one arriving while the folder is being
    # locked or planned stops the sweep as cleanly as one arriving while jobs run
    previous = signal.getsignal(signal.SIGTERM)
    main_thread = threading.current_thread() is threading.main_thread()
    if main_thread:
        signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        _locked_sweep(jobs, writable_folder(out_dir), executor, workers, scheduler, (force, retry_failed, rerun_stale),
                      progress, runner, config_text, outcome)
    except KeyboardInterrupt as e:
        outcome.interrupted = True
        outcome.terminated = isinstance(e, _Terminated)
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)
    return outcome


def _locked_sweep(jobs, out: Path, executor, workers, scheduler, rerun: tuple[bool, bool, bool], progress, runner,
                  config_text, outcome: SweepOutcome) -> None:
    """run_sweep with the folder locked; KeyboardInterrupt (Ctrl-C, SIGTERM) leaves a consistent folder.
    ``rerun``: (force, retry_failed, rerun_stale)."""
    force, retry_failed, rerun_stale = rerun
    jobs_dir = writable_folder(out / "jobs")
    with FolderLock(out) as lock:
        _remove_files(jobs_dir.glob("*.tmp"))  # left by a job killed while writing (the lock says none runs)
        if force:  # every job again, from a fresh stretch: cached knits are not reused
            for knit in (out / "stretched").glob("*.h5"):
                knit.unlink(missing_ok=True)
        if config_text is not None:
            with atomic_path(out / "sweep.yaml") as tmp:
                tmp.write_text(config_text)
        todo = _sharing_first(_plan(jobs, jobs_dir, force, retry_failed, outcome, rerun_stale))
        write_summary(out, with_collapsed_members(list(outcome.rows.values())))
        write_column_dictionary(out, [job.scene for job in jobs])  # what each column of summary.csv means
        _remove_files(jobs_dir.glob("*.progress"))  # of a job killed mid-run: no job runs now
        bar = SweepProgress(len(jobs), outcome.skipped, jobs_dir=jobs_dir) if progress else None
        written = [time.monotonic()]

        def finish(job: Job, row: dict) -> None:
            outcome.rows[job.id] = row
            outcome.ran += 1
            outcome.failed += row["status"] != "ok"
            # the job files are the record; the table follows them at most every SUMMARY_EVERY_S (a
            # 10,000-job sweep spent 36 min rewriting it) and always at the end, also after Ctrl-C
            if time.monotonic() - written[0] >= SUMMARY_EVERY_S:
                write_summary(out, with_collapsed_members(list(outcome.rows.values())))
                written[0] = time.monotonic()
            if bar:
                try:
                    bar.update(row["status"])
                except Exception:  # noqa: BLE001 - progress is a courtesy: it never touches a job's result
                    pass

        try:
            if todo:
                run = _run_dask if executor == "dask" else _run_pool
                run(todo, jobs_dir, workers, scheduler, runner, finish, lock.token)
        finally:
            lock.release()  # from here on, a job still running elsewhere writes nothing
            _remove_files(jobs_dir.glob("*.tmp"))
            _take_late_files(todo, jobs_dir, outcome)
            write_summary(out, with_collapsed_members(list(outcome.rows.values())))
            if bar:
                bar.close()


def _remove_files(paths) -> None:
    """Remove the files among ``paths``: a folder of that name (not knitlad's) is left alone, not a traceback."""
    for path in paths:
        if not path.is_dir():
            path.unlink(missing_ok=True)


def _take_late_files(todo: list[Job], jobs_dir: Path, outcome: SweepOutcome) -> None:
    """Rows for the jobs whose trusted file appeared while an interrupted sweep was stopping its
    workers (a Dask task that finished after the cancel), so the summary lists what was written."""
    for job in todo:
        if outcome.rows[job.id]["status"] == "pending":
            attrs, _ = trusted_attrs(job_path(jobs_dir, job), job)
            if attrs is not None:
                outcome.rows[job.id] = summary_row(job, attrs)


SUMMARY_EVERY_S = 5.0


def _failed_row(jobs_dir: Path, job: Job, message: str) -> dict:
    """Record a job whose worker died (killed, out of memory, segfault)."""
    record = _record(job, "failed", message)
    write_record(job_path(jobs_dir, job), record)
    return summary_row(job, record)


def _run_pool(todo: list[Job], jobs_dir: Path, workers: int | None, scheduler, runner: Runner, finish,
              token: str) -> None:
    """At most ``workers`` jobs in flight. When a worker dies the pool breaks and every job
    in flight is lost with it: a lone one is the job that killed it and fails; several
    are run again one at a time, so that only the job that kills its worker fails."""
    workers = max(1, min(workers or os.cpu_count() or 1, len(todo)))
    if workers > 1 and runner is run_job:
        compile_kernels()
    queue = list(reversed(todo))
    suspects: list[Job] = []  # in flight when a pool broke: each runs alone
    ctx = get_context("spawn")  # a fresh interpreter per worker: no forked Numba thread pools
    while queue or suspects:
        alone = bool(suspects)
        pool = ProcessPoolExecutor(max_workers=1 if alone else workers, mp_context=ctx, initializer=_init_worker)
        running: dict = {}
        try:
            while (suspects if alone else queue) or running:
                source = suspects if alone else queue
                lost = []
                while source and len(running) < (1 if alone else workers):
                    job = source.pop()
                    try:
                        with _interrupts_deferred():
                            running[pool.submit(runner, job, str(jobs_dir), 1, token)] = job
                    except BrokenProcessPool:  # a worker died since the last wait: this job never started
                        source.append(job)
                        break
                done, _ = wait(running, return_when=FIRST_COMPLETED) if running else (set(), None)
                for fut in done:
                    job = running.pop(fut)
                    try:
                        row = fut.result()
                    except BrokenProcessPool:
                        lost.append(job)
                        continue
                    except Exception as e:  # noqa: BLE001 - this job's task failed outside run_job
                        row = _failed_row(jobs_dir, job, _one_line(e))
                    finish(job, row)  # outside the try: what happens after a job ran never rewrites its file
                if lost or not done:
                    lost += list(running.values())
                    running.clear()
                    if len(lost) == 1:
                        finish(lost[0], _failed_row(jobs_dir, lost[0], WORKER_DIED))
                    elif lost:
                        suspects.extend(reversed(lost))
                    break
        except BaseException:
            _stop_pool(pool)
            raise
        pool.shutdown(wait=True, cancel_futures=True)


@contextmanager
def _interrupts_deferred():
    """Hold Ctrl-C and SIGTERM until the block ends, then hand the first one to its usual handler.

    A submit may spawn a worker, writing its start-up data down a pipe: an interrupt in the
    middle left the new interpreter reading a truncated pickle, and its EOFError traceback
    on the user's terminal (seen when SIGTERM came as the first worker started). Python runs
    signal handlers in the main thread, so they are swapped there (a thread's signal mask would
    not do: the kernel hands a process's signal to any thread that does not block it)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []
    held = (signal.SIGINT, signal.SIGTERM)
    previous = {s: signal.signal(s, lambda signum, frame: pending.append(signum)) for s in held}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        if pending:
            handler = previous[pending[0]]
            if callable(handler):
                handler(pending[0], None)
            elif handler == signal.SIG_DFL:
                os.kill(os.getpid(), pending[0])


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """Stop the workers now (Ctrl-C): they ignore SIGINT, so terminate them."""
    if hasattr(pool, "terminate_workers"):  # Python >= 3.14
        pool.terminate_workers()
        return
    for p in list(getattr(pool, "_processes", {}).values()):
        p.terminate()
    pool.shutdown(wait=True, cancel_futures=True)


class SchedulerError(RuntimeError):
    """The Dask scheduler cannot be reached or its address is malformed (one line)."""


SCHEDULER_TIMEOUT_S = 5


def connect(scheduler: str):
    """A Dask client of ``scheduler``, or :class:`SchedulerError` within SCHEDULER_TIMEOUT_S seconds.

    The client is made in a thread of its own with a hard deadline: an address that accepts the
    connection but never speaks Dask's protocol (a stalled server, a dashboard's HTTP port) kept
    ``Client`` waiting for ever, or answered with garbage it tried to allocate (3 EiB)."""
    try:
        from distributed import Client
    except ImportError:
        raise SchedulerError("--executor dask needs the optional extra: pip install 'knitlad[dask]'") from None
    outcome: dict = {}

    def attempt() -> None:
        try:
            outcome["client"] = Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S}s")
        except BaseException as e:  # noqa: BLE001 - whatever a wrong peer makes of it: said in one line
            outcome["error"] = e

    thread = threading.Thread(target=attempt, name="knitlad-dask-connect", daemon=True)
    thread.start()
    thread.join(SCHEDULER_TIMEOUT_S + 2)
    if thread.is_alive():
        raise SchedulerError(f"--scheduler {scheduler}: no Dask scheduler answered within {SCHEDULER_TIMEOUT_S} s")
    if "error" in outcome:
        raise SchedulerError(f"--scheduler {scheduler}: cannot connect ({_one_line(outcome['error'])})")
    return outcome["client"]


LOCAL_WORKER_START_S = 120.0


def _client_of_batch_cluster(cluster, kind: str):
    """A client of a batch cluster just started; a local cluster's first worker waited for, since its workers start
    here at once or never. A worker that cannot start is a :class:`SweepError` of one line, the cluster closed
    without the tracebacks distributed and dask-jobqueue print for a worker that never had a job id."""
    from distributed import Client

    try:
        client = Client(cluster)
    except Exception as e:  # noqa: BLE001 - the worker's own error, whatever its type
        _close_failed_cluster(cluster)
        raise SweepError(f"--cluster: its worker did not start ({_one_line(e)}; check the options, e.g. python "
                         "and memory)") from None
    if kind == "local":
        reason = _first_local_worker(client, cluster)
        if reason:
            client.close()
            _close_failed_cluster(cluster)
            raise SweepError(f"--cluster: {reason} (check the options, e.g. python, memory, worker_extra_args)")
    return client


def _first_local_worker(client, cluster) -> str:
    """Wait for a local cluster's first worker: '' once one has registered, else why not (every worker process
    has exited, or none registered within LOCAL_WORKER_START_S)."""
    deadline = time.monotonic() + LOCAL_WORKER_START_S
    while time.monotonic() < deadline:
        try:
            client.wait_for_workers(1, timeout=1.0)
            return ""
        except Exception:  # noqa: BLE001 - distributed's TimeoutError, by version
            pass
        exits = [job.process.proc.poll() for job in cluster.workers.values()
                 if getattr(getattr(job, "process", None), "proc", None) is not None]
        if exits and len(exits) == len(cluster.workers) and all(code is not None for code in exits):
            return f"every local worker exited at its start (exit code {exits[0]})"
    return f"no local worker started within {LOCAL_WORKER_START_S:g} s"


@contextmanager
def _quiet_dask():
    """distributed, tornado and dask-jobqueue log every failed worker start with its traceback: not the user's to
    read, since the failure is reported in one line."""
    import logging

    before = logging.root.manager.disable
    logging.disable(logging.CRITICAL)
    try:
        yield
    finally:
        logging.disable(before)


def _close_failed_cluster(cluster) -> None:
    """Close a cluster whose workers failed: dask-jobqueue cannot cancel a job that never got an id (it raises, and
    again at exit)."""
    from distributed.core import Status

    try:
        for name, job in list(getattr(cluster, "workers", {}).items()):
            if getattr(job, "job_id", "") is None:  # never submitted: nothing to cancel
                cluster.workers.pop(name, None)
                cluster.worker_spec.pop(name, None)
        cluster.close()
    except Exception:  # noqa: BLE001 - the cluster is being given up either way
        pass
    finally:
        cluster.status = Status.closed  # distributed's exit hook would try once more


def _run_dask(todo: list[Job], jobs_dir: Path, workers: int | None, scheduler: str | None, runner: Runner, finish,
              token: str) -> None:
    """The same jobs on a Dask cluster at ``scheduler``, a batch cluster it describes (a
    :class:`~knitlad.studies.cluster.ClusterConfig`), or a local one. ``DIR`` must be on a
    file system the workers share (as on a Slurm cluster with dask-jobqueue). On Ctrl-C the
    tasks are cancelled and the folder's lock released: a task still running writes nothing."""
    from distributed import Client, LocalCluster, as_completed

    if len(todo) > 1 and runner is run_job:
        compile_kernels()  # the workers then load Numba's on-disk cache
    cluster = None
    if isinstance(scheduler, ClusterConfig):  # a batch cluster started for this sweep (knitlad.studies.cluster)
        with _quiet_dask():  # a worker that fails to start is said once, in the SweepError
            cluster = scheduler.start()
            client = _client_of_batch_cluster(cluster, scheduler.kind)
    elif scheduler:
        client = connect(scheduler)
    else:
        n = max(1, min(workers or os.cpu_count() or 1, len(todo)))
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    futures = {}
    try:
        futures = {client.submit(runner, job, str(jobs_dir.resolve()), 1, token, key=f"knitlad-{job.id}", pure=False):
                   job for job in todo}
        for fut in as_completed(futures):
            job = futures[fut]
            try:
                row = fut.result()
            except Exception as e:  # noqa: BLE001 - a worker died (KilledWorker) or the task failed outside run_job
                row = _failed_row(jobs_dir, job, _one_line(e))
            finish(job, row)
    except BaseException:
        client.cancel(list(futures))
        raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
