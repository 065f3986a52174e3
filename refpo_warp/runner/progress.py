"""``progress.jsonl``: one JSON object per training iteration, appended as whole lines, read back tolerantly.

A process killed while appending can leave a torn last line; readers skip it (it is the iteration that did not
finish). Any other unreadable line is an error naming the file and the line. On resume the file is cut back to the
checkpoint's iteration (atomically), so it never repeats an iteration and its ``env_steps`` continue.
"""

from __future__ import annotations

import json
from pathlib import Path

from refpo_warp.utils.atomic_files import append_line, write_text
from refpo_warp.utils.errors import DataFileError

PROGRESS_FILE = "progress.jsonl"


def progress_path(run_dir: str | Path) -> Path:
    return Path(run_dir) / PROGRESS_FILE


def append_row(run_dir: str | Path, row: dict) -> None:
    append_line(progress_path(run_dir), json.dumps(row))


def read_rows(run_dir: str | Path) -> list[dict]:
    """All complete rows; a torn last line is skipped, any other bad line raises ``DataFileError``."""
    path = progress_path(run_dir)
    if not path.is_file():
        raise DataFileError(f"{path}: not found (train with `refpo train` first)")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise DataFileError(f"{path}: cannot be read ({err})") from err
    lines = text.split("\n")
    rows = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
            if not isinstance(row, dict) or not isinstance(row.get("iteration"), int):
                raise ValueError("not an object with an integer 'iteration'")
        except ValueError as err:
            if number == len(lines):  # the last line, without its newline: a write that was cut off
                break
            raise DataFileError(
                f"{path}: line {number} is not a progress row ({err}); the file was edited or damaged"
            ) from err
        rows.append(row)
    return rows


def truncate_after(run_dir: str | Path, iteration: int) -> dict | None:
    """Keep only the rows up to ``iteration`` (drops later and torn rows); returns the row of ``iteration``."""
    path = progress_path(run_dir)
    if not path.exists():
        return None
    rows = [r for r in read_rows(run_dir) if r["iteration"] <= iteration]
    write_text(path, "".join(json.dumps(r) + "\n" for r in rows))
    return next((r for r in reversed(rows) if r["iteration"] == iteration), None)
