"""Atomic file writes: a reader (or a resumed sweep) never sees a half-written file."""

from __future__ import annotations

import os
import stat
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator


@contextmanager
def atomic_path(path: str | Path, suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; when the block ends without error, rename it onto ``path``.

    The temporary name carries the process id, so two processes writing the same file
    never write into each other's temporary file; it ends in ``.tmp`` (then ``suffix``,
    for writers that read the format off the extension, e.g. ``.png``). On an error the
    temporary file is removed and ``path`` is left as it was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp{suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


MAX_CONFIG_BYTES = 1 << 20  # a YAML config is a few hundred bytes; a megabyte is no config


def read_config_text(path: str | Path, max_bytes: int = MAX_CONFIG_BYTES) -> str:
    """The text of a config file, read only if it is a regular file of at most ``max_bytes``: a FIFO would
    block the reader forever and /dev/zero feed it until memory runs out. ValueError (one line, the reason)
    otherwise; OSError if it cannot be read; UnicodeDecodeError if it is not text."""
    path = Path(path)
    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode):
        kind = "a folder" if stat.S_ISDIR(info.st_mode) else "a pipe" if stat.S_ISFIFO(info.st_mode) else \
            "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode) else "not a regular file"
        raise ValueError(f"{kind}, not a config file")
    if info.st_size > max_bytes:
        raise ValueError(f"{info.st_size} bytes, over the {max_bytes} a config file may hold")
    with open(path, "rb") as f:
        return f.read(max_bytes + 1).decode("utf-8")
