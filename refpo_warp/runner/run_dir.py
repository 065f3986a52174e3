"""The run directory: the files a run writes into it, the checks made before it writes, and the lock that keeps two
processes from training into one directory. Its saved config: ``refpo_warp/config/saved.py``."""

from __future__ import annotations

import contextlib
import fnmatch
import os
from collections.abc import Iterator
from pathlib import Path

from refpo_warp.config.saved import IDENTITY_KEYS, RUN_CONFIG
from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.utils.errors import STOPPED_FILE, ConfigError, DataFileError

# Files a run writes into its directory (glob patterns): only their interrupted temp files are ever removed.
RUN_FILES = (
    "model_*.pt",
    RUN_CONFIG,
    "progress.jsonl",
    "eval.json",
    "eval.prev.json",
    STOPPED_FILE,
    "error.log",
    "*.png",
)


def check_writable(run_dir: Path) -> None:
    """Refuse a run dir that is a file, or that cannot be created or written (before anything is built)."""
    if run_dir.exists() and not run_dir.is_dir():
        raise ConfigError(f"run_dir={run_dir} is a file, not a directory")
    existing = run_dir
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise ConfigError(f"run_dir={run_dir} cannot be created: {existing} is a file")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ConfigError(f"run_dir={run_dir} cannot be written: no write permission on {existing}")


def check_new_run_dir(run_dir: Path) -> None:
    """A new run may start in a directory without files of the names a run writes (other files, e.g. a sweep's
    logs, stay untouched), or over a refpo_warp run that never wrote a checkpoint; never where it would replace
    someone else's config.yaml, progress.jsonl, eval.json or figures."""
    if not run_dir.is_dir():
        return
    clashes = sorted(p.name for p in run_dir.iterdir() if any(fnmatch.fnmatch(p.name, pat) for pat in RUN_FILES))
    if not clashes:
        return
    try:
        saved = load_yaml(run_dir / RUN_CONFIG, error=DataFileError)
        if all(isinstance(saved.get(k), str) for k in IDENTITY_KEYS):
            return  # a refpo_warp run without checkpoints: starting it again is what the user asks for
    except DataFileError:
        pass
    raise ConfigError(
        f"run_dir={run_dir} is not a refpo_warp run directory (no usable {RUN_CONFIG}) but holds "
        f"{', '.join(clashes[:5])}, which a run would replace; choose a new or empty directory"
    )


@contextlib.contextmanager
def run_lock(run_dir: Path) -> Iterator[None]:
    """Hold an exclusive lock on the run directory (released when the process exits, even on kill -9)."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield
        return
    fd = os.open(run_dir, os.O_RDONLY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError(
                f"run_dir={run_dir} is in use by another training process; wait for it to finish "
                f"or choose another run_dir"
            ) from None
        yield
    finally:
        os.close(fd)
