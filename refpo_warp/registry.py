"""Task registry: task ids map to an env cfg dataclass and a lazily imported environment class.

Task families are the subpackages of the task root package (``tasks``); the registry imports each one the first time
a task is looked up, and the family's ``__init__`` registers its ids with ``register_task``. Nothing lists the
families by hand. A registration names the env cfg class (from a Warp-free module) and the env class as an
entry-point string, so listing tasks and resolving configs never import a simulator; the env module is imported
only when ``make_env`` builds that task.
"""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from refpo_warp.errors import unknown

TASK_ROOT = "tasks"  # the package whose subpackages are the task families


@dataclass(frozen=True)
class TaskSpec:
    """A registered task: what builds its env and which config file holds its training defaults."""

    task_id: str
    entry_point: str  # "module.path:ClassName" of a WarpVecEnv subclass
    cfg_class: type  # its env cfg dataclass (an EnvCfg subclass, importable without Warp)
    cfg_overrides: dict[str, Any] = field(default_factory=dict)
    description: str = ""
    config_file: Path | None = None  # None: configs/task/<task_id>.yaml

    def env_class(self) -> type:
        module_path, name = self.entry_point.split(":")
        return getattr(importlib.import_module(module_path), name)

    @property
    def package(self) -> str:
        """The package of the env module: the family (``tasks.<family>``), home of its optional ``report.py``."""
        return self.entry_point.split(":")[0].rsplit(".", 1)[0]


_TASKS: dict[str, TaskSpec] = {}
_FAMILIES: list[str] = []


def register_task(task_id: str, entry_point: str, cfg_class: type, description: str = "",
                  config_file: str | Path | None = None, **cfg_overrides: Any) -> None:  # fmt: skip
    """Register ``task_id``: its env (``"module:Class"``), env cfg class, and the cfg fields this id fixes (e.g. the
    DMC suite task). ``config_file`` is its training config (default ``configs/task/<task_id>.yaml``)."""
    valid = {f.name for f in dataclasses.fields(cfg_class)}
    for key in cfg_overrides:
        if key not in valid:
            raise unknown(f"env option of {cfg_class.__name__} (registering '{task_id}')", key, valid)
    spec = TaskSpec(task_id, entry_point, cfg_class, dict(cfg_overrides), description,
                    Path(config_file) if config_file is not None else None)  # fmt: skip
    if task_id in _TASKS and _TASKS[task_id] != spec:
        raise ValueError(f"Task id '{task_id}' is already registered by {_TASKS[task_id].entry_point}")
    _TASKS[task_id] = spec


def task_families() -> list[str]:
    """The task families (subpackages of the task root), each imported once so that it registered its ids."""
    if not _FAMILIES:
        root = importlib.import_module(TASK_ROOT)
        names = sorted(m.name for m in pkgutil.iter_modules(root.__path__) if m.ispkg)
        for name in names:
            importlib.import_module(f"{TASK_ROOT}.{name}")
        _FAMILIES.extend(names)
    return list(_FAMILIES)


def list_tasks() -> list[str]:
    """All registered task ids, sorted."""
    task_families()
    return sorted(_TASKS)


def get_task(task_id: str) -> TaskSpec:
    """The spec of ``task_id``; an unknown id raises an error naming the closest registered id."""
    task_families()
    if task_id not in _TASKS:
        raise unknown("task", task_id, _TASKS)
    return _TASKS[task_id]


def make_env_cfg(task_id: str, **overrides: Any):
    """The env cfg dataclass of ``task_id`` with ``overrides`` applied (unknown fields raise with a suggestion)."""
    spec = get_task(task_id)
    valid = {f.name for f in dataclasses.fields(spec.cfg_class)}
    for key in overrides:
        if key not in valid:
            raise unknown(f"env option for task '{task_id}'", key, valid)
    return spec.cfg_class(**{**spec.cfg_overrides, **overrides})


def make_env(task_id: str, num_envs: int = 64, device: str = "auto", seed: int = 0, **env_cfg: Any):
    """Build the rsl_rl ``VecEnv`` of a registered task.

    Args:
        task_id: A registered id such as ``"gridworld"``, ``"dmc_cartpole_balance"`` or ``"humanoid_root"``.
        num_envs: Number of parallel environments (one Warp thread / Newton world each).
        device: ``"auto"`` (CUDA when available, else CPU), ``"cpu"`` or ``"cuda:N"``.
        seed: Seed of the per-env random streams.
        **env_cfg: Fields of the task's env cfg dataclass to override.

    With ``action_chunk`` above 1 the env comes wrapped in an ``ActionChunkWrapper`` (H env steps per action).
    """
    spec = get_task(task_id)
    cfg = make_env_cfg(task_id, **env_cfg)
    env = spec.env_class()(cfg, num_envs=num_envs, device=device, seed=seed)
    if cfg.action_chunk > 1:
        from refpo_warp.envs.action_chunk import ActionChunkWrapper

        env = ActionChunkWrapper(env, cfg.action_chunk)
    return env
