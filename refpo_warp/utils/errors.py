"""Error types and the 'did you mean' helper shared by configs, the task registry and data loaders.

Every foreseeable failure is one of these types; ``refpo_warp.cli.guard`` maps each to a message and an exit code
(``docs/cli.md``): ``ConfigError`` 2, ``NonFiniteLossError`` 3, ``DataFileError`` (and its subclasses) 4,
``SystemRefusedError`` 5.
"""

from __future__ import annotations

import contextlib
import difflib
from collections.abc import Iterable, Iterator
from pathlib import Path

# The exit code of each (docs/cli.md); a sweep reads a run's to tell a non-finite loss, a result, from a crash.
EXIT_OK, EXIT_UNEXPECTED, EXIT_USAGE, EXIT_NONFINITE, EXIT_BAD_FILE, EXIT_SYSTEM = 0, 1, 2, 3, 4, 5
EXIT_INTERRUPTED = 130
# What a run stopped by a non-finite loss leaves in its run dir (and exits EXIT_NONFINITE): where and why it stopped.
# A sweep keeps such a run as failed instead of continuing it (a retry repeats the failure).
STOPPED_FILE = "stopped.json"


class ConfigError(ValueError):
    """A configuration key, value or task id is invalid."""


class NonFiniteLossError(FloatingPointError):
    """A training loss or statistic became NaN or infinite; training stops before the bad step is applied."""

    # Set by refpo_warp.training.train_run when it stops a run (unset before: read them with getattr):
    checkpoint: Path | None  # the run's latest checkpoint
    run_dir: Path
    learning_rate: float  # the rate the run had


class DataFileError(ValueError):
    """An input file (checkpoint, motion, saved config, progress log) is unreadable or invalid; names the file."""


class SystemRefusedError(RuntimeError):
    """The machine lacks what a command needs (e.g. an OpenGL platform for rendering); the message says what."""


class MotionDataError(DataFileError):
    """A motion file is malformed; the message names the file and the problem."""


class CheckpointError(DataFileError):
    """A checkpoint is missing, truncated, foreign, of another shape, or holds objects that are not plain data."""


def closest(name: str, choices: Iterable[str]) -> str | None:
    """Return the valid choice closest to ``name`` (or None when nothing is close)."""
    choices = list(choices)
    match = difflib.get_close_matches(name, choices, n=1, cutoff=0.4)
    if match:
        return match[0]
    # Fall back to a prefix/suffix match so short typos of long dotted keys still get a suggestion.
    leaf = name.rsplit(".", 1)[-1]
    for choice in choices:
        if choice.rsplit(".", 1)[-1] == leaf:
            return choice
    return None


def unknown(kind: str, name: str, choices: Iterable[str]) -> ConfigError:
    """Build the error for an unknown ``kind`` (task, key, ...) that names the closest valid choice."""
    choices = sorted(choices)
    suggestion = closest(name, choices)
    hint = f" Did you mean '{suggestion}'?" if suggestion else ""
    return ConfigError(f"Unknown {kind} '{name}'.{hint} Valid choices: {', '.join(choices)}")


@contextlib.contextmanager
def tag_run_dir(run_dir: str | Path) -> Iterator[None]:
    """Record on any exception leaving this block the run dir it happened in (the CLI writes its log there)."""
    try:
        yield
    except BaseException as err:
        if getattr(err, "run_dir", None) is None:
            with contextlib.suppress(AttributeError):  # a few built-in exception types take no attributes
                err.run_dir = Path(run_dir)  # type: ignore[attr-defined]  # any exception type, tagged at run time
        raise
