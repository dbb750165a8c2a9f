"""Progress lines for long commands: a run's stages, a sweep, a movie, a render.

One class, :class:`ProgressLine`, draws ``label [bar] done/total unit  rate  elapsed  ETA``
on stderr. On a terminal the line is redrawn in place (at most every ``REDRAW_S``); in a log
file (a batch job's output, where a redrawn line would be thousands of lines or nothing) a
new line is written at most every ``log_every_s`` and once at the end. rich's progress bars,
installed with typer, were not used for this reason: off a terminal they print nothing until
the end, and a batch job's log is where a sweep most needs to show it moves.

:class:`ProgressFile` carries the progress of a job run in another process (a pool worker, a
Dask task) to the sweep that waits for it, through a small file beside the job's own.
"""

from __future__ import annotations

import math
import os
import stat
import sys
import threading
import time
from pathlib import Path

REDRAW_S = 0.2  # a terminal line is redrawn at most this often
LOG_EVERY_S = 30.0  # off a terminal, one line at most this often (and at the end)
WIDTH = 20  # characters of the bar
MIN_RATE_S = 1.0  # no rate (nor time left) before this much time has passed


def duration(seconds: float) -> str:
    """``seconds`` as 42 s, 3m05s or 2h07m (``?`` when unknown)."""
    if not math.isfinite(seconds):
        return "?"
    seconds = max(seconds, 0.0)
    if seconds < 100:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{int(seconds // 60)}m{int(seconds % 60):02d}s"
    return f"{int(seconds // 3600)}h{int(seconds % 3600 // 60):02d}m"


class ProgressLine:
    """A progress line: ``update(done)`` towards ``total`` (in ``unit``: jobs, frames, images or %).

    Thread-safe (a sweep redraws it from a watcher thread while jobs finish). ``stream``: where
    it is drawn (default stderr); ``tty`` overrides the stream's own answer (tests)."""

    def __init__(self, label: str, total: float, unit: str = "", stream=None, tty: bool | None = None,
                 log_every_s: float = LOG_EVERY_S) -> None:
        self.label, self.total, self.unit = label, float(total), unit
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty() if tty is None else tty
        self.log_every_s = log_every_s
        self.t0 = time.perf_counter()
        self.done, self.note = 0.0, ""
        self._drawn_at = -math.inf
        self._drawn = None  # (done, note) last drawn
        self._lock = threading.Lock()
        self._open = False

    def update(self, done: float, note: str = "", force: bool = False) -> None:
        """Set the amount done (and a short note after the figures); redraw if it is time."""
        with self._lock:
            self.done, self.note = min(max(float(done), 0.0), self.total), note
            now = time.perf_counter()
            wait = REDRAW_S if self.tty else self.log_every_s
            changed = self._drawn != (self.done, self.note)
            finished = self.done >= self.total and not self.tty  # a log gets the end at once, once
            if (changed and (force or finished)) or now - self._drawn_at >= wait:
                self._draw(now)

    def text(self, now: float | None = None) -> str:
        """The line as drawn: bar, amount, rate, elapsed time and time left."""
        now = time.perf_counter() if now is None else now
        elapsed = now - self.t0
        frac = self.done / self.total if self.total > 0 else 1.0
        filled = int(WIDTH * frac)
        rate = self.done / elapsed if elapsed >= MIN_RATE_S else math.nan  # not from the first instants
        left = (self.total - self.done) / rate if rate > 0 else math.nan
        if self.unit == "%":
            amount = f"{100 * frac:3.0f}%"
            speed = ""
        else:
            done = f"{self.done:g}" if float(self.done).is_integer() else f"{self.done:.1f}"  # a sweep counts parts of jobs
            amount = f"{done}/{self.total:g} {self.unit}".rstrip()
            speed = f"  {rate:.2g} {self.unit}/s" if rate > 0 and self.unit else ""  # rate is NaN early on
        note = f"  {self.note}" if self.note else ""
        return (f"{self.label} [{'#' * filled}{'.' * (WIDTH - filled)}] {amount}{speed}"
                f"  {duration(elapsed)}  ETA {duration(left) if frac < 1 else '0 s'}{note}")

    def _draw(self, now: float) -> None:
        line = self.text(now)
        if self.tty:
            self.stream.write("\r" + line + "\x1b[K")  # erase what a longer previous line left
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
        self._drawn_at, self._open, self._drawn = now, True, (self.done, self.note)

    def close(self) -> None:
        """The final state, and the line ended (a terminal's cursor goes to the next line)."""
        with self._lock:
            if self.tty or self._drawn != (self.done, self.note):  # a log gets the final state once
                self._draw(time.perf_counter())
            if self.tty:
                self.stream.write("\n")
                self.stream.flush()
            self._open = False


class ProgressFile:
    """A job's progress, written for the process that waits for it: ``(stage, fraction)`` as one line
    of ``path``, replaced atomically at most every ``every_s``; removed by :meth:`clear`."""

    MAX_BYTES = 128  # a progress line is a stage and a number

    def __init__(self, path: str | Path, every_s: float = 1.0) -> None:
        self.path = Path(path)
        self.every_s = every_s
        self._written_at = -math.inf

    def __call__(self, stage: str, fraction: float) -> None:
        now = time.monotonic()
        fraction = min(max(fraction, 0.0), 1.0) if math.isfinite(fraction) else 0.0  # a NaN tension reads as NaN
        if now - self._written_at < self.every_s and fraction < 1.0:
            return
        self._written_at = now
        tmp = self.path.with_name(self.path.name + ".tmp")
        try:
            tmp.write_text(f"{stage} {fraction:.4f}\n")
            os.replace(tmp, self.path)
        except OSError:
            pass  # progress is a courtesy: a full disk must not fail the job

    def clear(self) -> None:
        self.path.unlink(missing_ok=True)

    @staticmethod
    def read(path: str | Path) -> tuple[str, float] | None:
        """(stage, fraction in [0, 1]) from a progress file, or None for anything else: gone, half-written, a
        fraction that is not a number in [0, 1], or not a regular file (a folder, a FIFO that would block, a
        link to /dev/zero that would never end); at most ``MAX_BYTES`` are read."""
        try:
            if not stat.S_ISREG(os.stat(path).st_mode):
                return None
            with open(path, "rb") as f:
                stage, fraction = f.read(ProgressFile.MAX_BYTES).decode("ascii").split()
            value = float(fraction)
        except (OSError, ValueError, UnicodeDecodeError):
            return None
        return (stage, value) if 0.0 <= value <= 1.0 else None


STAGE_SHARE = {"stretch": 0.1}  # of a laddering job's wall time (the rest: the ladder); others count whole


def job_fraction(stage: str, fraction: float) -> float:
    """How much of a job is done when its stage ``stage`` is ``fraction`` done (stages run in the order
    stretch, then the rest)."""
    share = STAGE_SHARE.get(stage)
    if share is not None:
        return share * fraction
    before = sum(STAGE_SHARE.values())
    return before + (1.0 - before) * fraction
