"""The run directory: its saved config, the checks made before a run writes into it, resume compatibility and the
lock that keeps two processes from training into one directory.

Resume rule: a resumed run keeps its task, algorithm and model. An option that would change them (``task``,
``algo``, every ``class_name``, actor/critic options, and options whose rule says ``fixed=True``, such as
``runner.obs_groups`` or ``algorithm.optimizer``) is refused, naming each differing key; everything else (learning
rate, budget, evaluation, device, ...) may change.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fnmatch
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from refpo_warp.config.resolve import (
    CLASS_SECTIONS,
    LEAF_KEYS,
    class_parameters,
    load_yaml,
    resolve_class,
    resolve_config,
)
from refpo_warp.config.run_options import RUN_RULES
from refpo_warp.utils.errors import ConfigError, DataFileError
from refpo_warp.utils.option_rules import rules_for

RUN_CONFIG = "config.yaml"
IDENTITY_KEYS = ("task", "algo")
# Files a run writes into its directory (glob patterns): only their interrupted temp files are ever removed.
RUN_FILES = ("model_*.pt", RUN_CONFIG, "progress.jsonl", "eval.json", "eval.prev.json", "error.log", "*.png")


def flatten(cfg: dict, prefix: str = "") -> dict[str, Any]:
    """Dotted-key view of a nested config (``LEAF_KEYS`` mappings stay whole)."""
    out: dict[str, Any] = {}
    for key, value in cfg.items():
        if isinstance(value, dict) and value and key not in LEAF_KEYS:
            out.update(flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def read_run_config(run_dir: Path) -> dict:
    """The saved, resolved config of a run; ``ConfigError`` if ``run_dir`` is not a run, ``DataFileError`` if the
    file is damaged."""
    saved = Path(run_dir) / RUN_CONFIG
    if not Path(run_dir).is_dir():
        raise ConfigError(f"run_dir={run_dir}: no such run directory")
    if not saved.exists():
        raise ConfigError(f"{saved} not found: '{run_dir}' is not a refpo_warp run directory")
    data = load_yaml(saved, error=DataFileError)
    for key in IDENTITY_KEYS:
        if not isinstance(data.get(key), str):
            raise DataFileError(f"{saved}: no '{key}' in it; the file was edited or damaged")
    try:
        resolve_config(flatten(data))
    except ConfigError as err:
        raise DataFileError(f"{saved}: {err}") from None
    return data


def load_run_config(run_dir: Path, overrides: dict[str, Any]) -> dict:
    """The saved config of a run with ``overrides`` applied on top (used to resume and to evaluate); refuses
    overrides that would change the run's task, algorithm or model."""
    saved = read_run_config(run_dir)
    for key in IDENTITY_KEYS:
        if key in overrides and str(overrides[key]) != saved[key]:
            raise ConfigError(f"{key}={overrides[key]} differs from the run's {key}={saved[key]} ({run_dir}); a run "
                              f"keeps its {key}: choose another run_dir for a new run")  # fmt: skip
    cfg = resolve_config({**flatten(saved), **overrides})
    changed = fixed_changes(saved, cfg)
    if changed:
        raise ConfigError(f"the run in {run_dir} keeps its task, algorithm and model, but these options differ from "
                          f"its config.yaml: {'; '.join(changed)}. Choose another run_dir for a new run")  # fmt: skip
    return cfg


def fixed_changes(saved: dict, cfg: dict) -> list[str]:
    """``key: saved -> new`` for every option that may not change on resume and does. An option the saved config
    does not list (left at its default, or added to the code since) is compared with its default."""
    old, new = flatten(saved), flatten(cfg)
    changes = []
    for key, value in new.items():
        if not _is_fixed(cfg, key):
            continue
        before = old[key] if key in old else _default(cfg, key)
        if before is not _UNKNOWN and before != value:
            changes.append(f"{key}: {before!r} -> {value!r}")
    return changes


_UNKNOWN = object()


def _default(cfg: dict, key: str) -> Any:
    """The value an option has when a config does not set it (constructor or env cfg default)."""
    section, _, name = key.partition(".")
    if section in CLASS_SECTIONS and "." not in name:
        return class_parameters(cfg[section]["class_name"]).get(name, _UNKNOWN)
    if section == "env" and "." not in name:
        from refpo_warp.envs.registry import get_task

        fields = {f.name: f for f in dataclasses.fields(get_task(cfg["task"]).cfg_class)}
        return fields[name].default if name in fields else _UNKNOWN
    return _UNKNOWN


def _is_fixed(cfg: dict, key: str) -> bool:
    section, _, name = key.partition(".")
    if key in IDENTITY_KEYS:
        return True
    if section in CLASS_SECTIONS:
        if name == "class_name":
            return True
        rule = rules_for(resolve_class(cfg[section]["class_name"])).get(name.split(".")[0])
        default = section in ("actor", "critic")  # the networks
        return default if rule is None or rule.fixed is None else rule.fixed
    if section == "env":
        from refpo_warp.envs.registry import get_task

        rule = rules_for(get_task(cfg["task"]).cfg_class).get(name)
        return bool(rule is not None and rule.fixed)
    rule = RUN_RULES.get(key)
    return bool(rule is not None and rule.fixed)


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
    raise ConfigError(f"run_dir={run_dir} is not a refpo_warp run directory (no usable {RUN_CONFIG}) but holds "
                      f"{', '.join(clashes[:5])}, which a run would replace; choose a new or empty directory")


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
            raise ConfigError(f"run_dir={run_dir} is in use by another training process; wait for it to finish "
                              f"or choose another run_dir") from None  # fmt: skip
        yield
    finally:
        os.close(fd)
