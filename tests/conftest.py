"""What the whole suite shares: the command line run in this process or in one of its own, and small knits
stretched once per session.

Tiers (pyproject.toml): the default tier is what the README's test command runs; ``slow`` (physics against
references), ``process`` (signals, exit codes, locks between processes, caches), ``cluster`` (Dask) and
``end_to_end`` (whole experiments from the command line) run after it in ``.ci/run``.
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
import subprocess
import sys
import time
import traceback
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
KNITLAD = [sys.executable, "-m", "knitlad.cli"]
DEFAULT_TIER_BUDGET_S = 270.0  # the default tier's wall time on 2 cores, a fresh cache's compilation included [s]


def knitlad_process(*args, cwd=ROOT, **kw) -> subprocess.CompletedProcess:
    """``knitlad ARGS`` in a process of its own (what signals, exit codes under SIGTERM, locks between processes
    and a fresh Numba cache need)."""
    return subprocess.run([*KNITLAD, *map(str, args)], capture_output=True, text=True, cwd=cwd, **kw)


def knitlad(*args, cwd=ROOT, env=None, timeout=None, **process) -> subprocess.CompletedProcess:
    """``knitlad ARGS`` run in this process through :func:`knitlad.cli.main`, as the console would run it: its
    exit code, and what it wrote to stdout and stderr (an uncaught exception as its traceback and exit 1, as
    Python prints it). ``env`` (a whole environment) or another argument of ``subprocess.run`` (``preexec_fn``:
    a limit on the file size) runs it in a process of its own instead."""
    if env is not None or process:
        return knitlad_process(*args, cwd=cwd, env=env, timeout=timeout, **process)
    from knitlad.cli import main

    import numba

    out, err = io.StringIO(), io.StringIO()
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    threads = numba.get_num_threads()
    here, argv = os.getcwd(), sys.argv
    code = 0
    try:
        os.chdir(cwd)
        sys.argv = ["knitlad", *map(str, args)]  # what a run's log records as its command
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                main([str(a) for a in args])
            except SystemExit as e:
                code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
            except Exception:  # what the interpreter would print before exiting with 1
                traceback.print_exc(file=sys.stderr)
                code = 1
    finally:
        os.chdir(here)
        sys.argv = argv
        for s, h in handlers.items():
            signal.signal(s, h)
        numba.set_num_threads(threads)
    return subprocess.CompletedProcess([*KNITLAD, *map(str, args)], code, out.getvalue(), err.getvalue())


@pytest.fixture(scope="session", autouse=True)
def kernels_compiled_on_both_workers():
    """On a fresh cache, the two workers compile the step's two subtrees at once (knitlad.engine.compile_ahead)
    before their first test, instead of both compiling all of it: a fresh clone's suite is a minute shorter."""
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    if worker not in ("gw0", "gw1"):
        return
    from knitlad.engine.compile_ahead import PARTS, compiled_ahead

    if not compiled_ahead():
        PARTS["statics" if worker == "gw0" else "dynamics"]()


def one_line_error(p, code: int = 2) -> str:
    """The one line a refused command writes to stderr (and its exit code ``code``)."""
    assert p.returncode == code, (p.returncode, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    return lines[0]


# ------------------------------------------------------------------ the default tier's time budget
DEFAULT_TIER = "not slow and not process and not cluster and not end_to_end"  # pyproject.toml's addopts
_clock: dict[str, float] = {}


def whole_default_tier(config) -> bool:
    """The run is the README's test command: the default tier, every test file (no paths or -k given)."""
    return (config.getoption("markexpr") == DEFAULT_TIER and not config.getoption("keyword")
            and [Path(a).resolve() for a in config.args] == [ROOT / "tests"])


def pytest_sessionstart(session):
    _clock["start"] = time.perf_counter()


def pytest_sessionfinish(session, exitstatus):
    """The default tier's budget: its wall time, a fresh cache's compilation included, printed; over
    DEFAULT_TIER_BUDGET_S the run fails (exit 1), naming the budget."""
    if "start" not in _clock or not whole_default_tier(session.config):
        return
    wall = time.perf_counter() - _clock["start"]
    _clock["wall"] = wall
    if wall > DEFAULT_TIER_BUDGET_S and session.exitstatus == 0:
        session.exitstatus = 1


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    if "wall" in _clock:
        verdict = "over" if _clock["wall"] > DEFAULT_TIER_BUDGET_S else "within"
        terminalreporter.write_line(f"default tier: {_clock['wall']:.0f} s, {verdict} its budget of "
                                    f"{DEFAULT_TIER_BUDGET_S:.0f} s (tests/conftest.py)")
