"""Output folders: checked before any compute, and owned by one sweep at a time.

* :func:`writable_folder` makes the folder (and its parents) and writes a probe file
  in it, so that a regular file in the way, a read-only disk or a missing permission
  is found before a run of hours, not after it.
* :class:`FolderLock` is the lock file ``<folder>/.lock`` (pid, host, start time and
  a token), created atomically. A second sweep on the same folder is refused; a lock
  whose process is gone (same host, pid not alive) is stale and taken over. Jobs
  carry the token and write their file only while the lock still holds it, so a task
  that outlives its sweep (a Dask worker after Ctrl-C) leaves no file the summary does
  not know of.
"""

from __future__ import annotations

import json
import os
import socket
import time
import uuid
from pathlib import Path

LOCK_NAME = ".lock"


class FolderError(RuntimeError):
    """An output folder cannot be used: one line saying why."""


def writable_folder(path: str | Path) -> Path:
    """``path`` as a folder that exists and takes files; :class:`FolderError` otherwise."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise FolderError(f"{path}: exists and is not a folder")
    for part in (path, *path.parents):  # mkdir says "File exists" of a link to nowhere: say what it is
        if part.is_symlink() and not part.exists():
            raise FolderError(f"{path}: {part} is a symbolic link that leads nowhere (a loop, or its target gone)")
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".probe.{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as e:
        raise FolderError(f"{path}: cannot write there ({e.strerror or e})") from None
    return path


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def lock_owner(folder: str | Path) -> dict | None:
    """The lock's record (pid, host, started, token), or None if the folder is not locked."""
    try:
        return json.loads((Path(folder) / LOCK_NAME).read_text())
    except (OSError, ValueError):
        return None


def lock_holds(folder: str | Path, token: str) -> bool:
    owner = lock_owner(folder)
    return owner is not None and owner.get("token") == token


class FolderLock:
    """``with FolderLock(folder) as lock:`` owns ``folder`` for the block (``lock.token``)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.path = self.folder / LOCK_NAME
        self.token = uuid.uuid4().hex
        self.took_over: dict | None = None  # the stale lock this one replaced

    def check_free(self) -> None:
        """:class:`FolderError` if a live sweep holds the folder now (nothing is taken)."""
        owner = lock_owner(self.folder)
        if owner is not None and not (owner.get("host") == socket.gethostname() and not _alive(int(owner["pid"]))):
            raise FolderError(self._busy(owner))

    def _busy(self, owner: dict) -> str:
        return (f"{self.folder}: in use by another knitlad run (pid {owner.get('pid')} on {owner.get('host')}, "
                f"since {owner.get('started')}); wait for it, or remove {self.path} if that process is gone")

    def acquire(self) -> "FolderLock":
        record = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "token": self.token,
                             "started": time.strftime("%Y-%m-%d %H:%M:%S")})
        for _ in range(2):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                owner = lock_owner(self.folder)
                if owner is None or (owner.get("host") == socket.gethostname() and not _alive(int(owner["pid"]))):
                    self.took_over = owner or {}
                    self.path.unlink(missing_ok=True)  # stale: its process is gone
                    continue
                raise FolderError(self._busy(owner)) from None
            with os.fdopen(fd, "w") as f:
                f.write(record)
            return self
        raise FolderError(f"{self.folder}: could not take the lock {self.path}")

    def release(self) -> None:
        if lock_holds(self.folder, self.token):
            self.path.unlink(missing_ok=True)

    def __enter__(self) -> "FolderLock":
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
