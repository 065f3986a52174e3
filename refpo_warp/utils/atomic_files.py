"""Crash-safe file writes: every file the project writes goes through here.

``atomic_write`` writes to a temp file in the destination's folder and renames it over the destination
(``os.replace``), so a reader (or a process killed mid-write) sees either the previous file or the new one, never a
part. ``append_line`` appends one whole line with a single ``write`` call, so an append-only log never holds half a
line unless the disk fills up (its readers still tolerate a torn last line). Temp files are named
``.<name>.<random>.tmp``; ``remove_stale_temp_files`` deletes the ones an interrupted writer left behind.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

TEMP_SUFFIX = ".tmp"


@contextlib.contextmanager
def atomic_write(path: str | Path, mode: str = "wb") -> Iterator[IO]:
    """Open a temp file next to ``path`` for writing; on success it replaces ``path``, on error it is removed.

    ``mode`` is ``"wb"`` or ``"w"`` (text, UTF-8). The data is flushed and fsync'ed before the rename.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=TEMP_SUFFIX)
    try:
        with os.fdopen(fd, mode, encoding=None if "b" in mode else "utf-8") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; keep the usual permissions of a written file
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temp path next to ``path`` for a writer that takes a file name (e.g. ffmpeg); on success it replaces
    ``path``, on error it is removed."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=TEMP_SUFFIX)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_text(path: str | Path, text: str) -> None:
    with atomic_write(path, "w") as f:
        f.write(text)


def write_json(data, path: str | Path) -> None:
    write_text(path, json.dumps(data, indent=2))


def save_figure(fig, path: str | Path, **savefig_kwargs) -> Path:
    """``fig.savefig`` through a temp file; the format comes from ``path``'s suffix (the temp name has none)."""
    path = Path(path)
    with atomic_write(path, "wb") as f:
        fig.savefig(f, format=path.suffix.lstrip(".") or "png", **savefig_kwargs)
    return path


def append_line(path: str | Path, line: str) -> None:
    """Append ``line`` plus a newline to ``path`` with one ``write`` call (O_APPEND)."""
    data = (line.rstrip("\n") + "\n").encode("utf-8")
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        written = os.write(fd, data)
        if written != len(data):  # only on a full disk: report it instead of leaving a silent half line
            raise OSError(f"{path}: only {written} of {len(data)} bytes could be appended (disk full?)")
    finally:
        os.close(fd)


def remove_stale_temp_files(folder: str | Path, names: tuple[str, ...] = ("*",)) -> list[Path]:
    """Delete the temp files an interrupted ``atomic_write`` of a file matching one of ``names`` (glob patterns)
    left in ``folder``; returns what was removed."""
    removed = []
    for pattern in names:
        for tmp in Path(folder).glob(f".{pattern}.*{TEMP_SUFFIX}"):
            if tmp.is_file():
                with contextlib.suppress(OSError):
                    tmp.unlink()
                    removed.append(tmp)
    return removed
