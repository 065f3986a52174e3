"""Task registry: task ids map to lazily imported environment classes.

Task families (``tasks/<family>/__init__.py``) register their ids with entry-point strings so that listing tasks
never imports a physics engine; the environment module is imported only when ``make_env`` builds that task.
"""

from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass, field
from typing import Any

from refpo_warp.errors import unknown


@dataclass(frozen=True)
class TaskSpec:
    """What ``make_env`` needs to build a task: the env class and the cfg fields that define this task id."""

    task_id: str
    entry_point: str  # "module.path:ClassName" of a WarpVecEnv subclass
    cfg_overrides: dict[str, Any] = field(default_factory=dict)
    description: str = ""

    def env_class(self) -> type:
        module_path, name = self.entry_point.split(":")
        return getattr(importlib.import_module(module_path), name)


_TASKS: dict[str, TaskSpec] = {}
_FAMILIES_LOADED = False


def register_task(task_id: str, entry_point: str, description: str = "", **cfg_overrides: Any) -> None:
    """Register ``task_id``; ``cfg_overrides`` are env-cfg fields fixed by this id (e.g. the DMC domain)."""
    if task_id in _TASKS and _TASKS[task_id].entry_point != entry_point:
        raise ValueError(f"Task id '{task_id}' is already registered by {_TASKS[task_id].entry_point}")
    _TASKS[task_id] = TaskSpec(task_id, entry_point, dict(cfg_overrides), description)


def _load_families() -> None:
    global _FAMILIES_LOADED
    if not _FAMILIES_LOADED:
        importlib.import_module("tasks")  # each family's __init__ registers its ids
        _FAMILIES_LOADED = True


def list_tasks() -> list[str]:
    """All registered task ids, sorted."""
    _load_families()
    return sorted(_TASKS)


def get_task(task_id: str) -> TaskSpec:
    """The spec of ``task_id``; an unknown id raises an error naming the closest registered id."""
    _load_families()
    if task_id not in _TASKS:
        raise unknown("task", task_id, _TASKS)
    return _TASKS[task_id]


def make_env_cfg(task_id: str, **overrides: Any):
    """The env cfg dataclass of ``task_id`` with ``overrides`` applied (unknown fields raise with a suggestion)."""
    spec = get_task(task_id)
    cfg_class = spec.env_class().cfg_class
    valid = {f.name for f in dataclasses.fields(cfg_class)}
    for key in overrides:
        if key not in valid:
            raise unknown(f"env option for task '{task_id}'", key, valid)
    return cfg_class(**{**spec.cfg_overrides, **overrides})


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
