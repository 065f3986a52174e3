"""Task registry: task ids map to a ``TaskSpec`` (env cfg dataclass, lazily imported env class, config file).

Task families are the subpackages of the task root package (``tasks``); each declares its tasks as a ``TASKS`` list
of ``refpo_warp.envs.task_spec.TaskSpec`` next to its code. The registry finds the families (nothing lists them by
hand), imports each once and reads its list; the families never import the registry. Listing tasks and resolving configs
never import a simulator: the env module is imported only when ``make_env`` builds that task. Code outside the task
root adds tasks with ``register_task``; a task that a config folder adds (``refpo_warp.config.config_set``) is never
registered: ``make_env``, ``make_env_cfg`` and ``family_module`` take its ``TaskSpec`` in place of an id.
"""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil
from collections.abc import Iterable
from typing import Any

from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.utils.errors import ConfigError, unknown

__all__ = [
    "check_env_options",
    "family_module",
    "get_task",
    "list_tasks",
    "make_env",
    "make_env_cfg",
    "register_task",
    "task_families",
]

TASK_ROOT = "refpo_warp.tasks"  # the package whose subpackages are the task families (the repository's tasks/)

_TASKS: dict[str, TaskSpec] = {}
_FAMILIES: list[str] = []


def register_task(spec: TaskSpec, replace: bool = False) -> None:
    """Add a task (a family's ``TASKS`` entries are added this way when the family is discovered); ``replace``: a
    different spec of the same id gives way."""
    if not isinstance(spec, TaskSpec):
        raise TypeError(f"register_task takes a TaskSpec, got {type(spec).__name__}")
    if spec.task_id in _TASKS and _TASKS[spec.task_id] != spec and not replace:
        raise ValueError(f"Task id '{spec.task_id}' is already registered by {_TASKS[spec.task_id].entry_point}")
    _TASKS[spec.task_id] = spec


def task_families() -> list[str]:
    """The task families (subpackages of the task root), each imported once and its ``TASKS`` registered."""
    if not _FAMILIES:
        root = importlib.import_module(TASK_ROOT)
        names = sorted(m.name for m in pkgutil.iter_modules(root.__path__) if m.ispkg and not m.name.startswith("_"))
        for name in names:
            family = importlib.import_module(f"{TASK_ROOT}.{name}")
            if not isinstance(getattr(family, "TASKS", None), (list, tuple)):
                raise ConfigError(f"{family.__file__}: a task family must declare its tasks as TASKS = [TaskSpec(...)]")
            for spec in family.TASKS:
                register_task(spec)
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


def _spec(task: str | TaskSpec) -> TaskSpec:
    return task if isinstance(task, TaskSpec) else get_task(task)


def family_module(task: str | TaskSpec, name: str):
    """The optional module ``name`` of the task's family (``refpo_warp.tasks.<family>.<name>``, e.g. ``evaluation`` or
    ``render``), or None where the family has none."""
    family = _spec(task).entry_point.split(":")[0].rsplit(".", 1)[0]
    try:
        return importlib.import_module(f"{family}.{name}")
    except ModuleNotFoundError as err:
        if err.name != f"{family}.{name}":
            raise
        return None


def _option_names(spec: TaskSpec) -> list[str]:
    return [f.name for f in dataclasses.fields(spec.cfg_class)]


def check_env_options(spec: TaskSpec, keys: Iterable[str], prefix: str = "") -> None:
    """Refuse a key that is no env option of the task's cfg class, naming the task, its options and, for an option
    of other tasks (one task's own, e.g. dmc_point_mass_wall's ``wall_half_length``), the tasks that have it."""
    valid = _option_names(spec)
    for key in keys:
        if key not in valid:
            what, choices = f"env option for task '{spec.task_id}'", [f"{prefix}{k}" for k in valid]
            owners = [t for t in list_tasks() if key in _option_names(get_task(t))]
            if not owners:
                raise unknown(what, f"{prefix}{key}", choices)
            raise ConfigError(
                f"Unknown {what} '{prefix}{key}': an env option of {', '.join(owners)} only. "
                f"Valid choices: {', '.join(sorted(choices))}"
            )


def make_env_cfg(task: str | TaskSpec, /, **overrides: Any):
    """The env cfg dataclass of ``task`` with ``overrides`` applied (unknown fields raise with a suggestion)."""
    spec = _spec(task)
    check_env_options(spec, overrides)
    return spec.cfg_class(**{**spec.cfg_overrides, **overrides})


def make_env(task: str | TaskSpec, /, num_envs: int = 64, device: str = "auto", seed: int = 0, **env_cfg: Any):
    """Build the rsl_rl ``VecEnv`` of a registered task.

    Args:
        task: A registered id such as ``"gridworld"``, ``"dmc_cartpole_balance"`` or ``"humanoid_root"``, or the
            ``TaskSpec`` of a task a config folder adds (``Resolution.task`` of a resolved config).
        num_envs: Number of parallel environments (one Warp thread / Newton world each).
        device: ``"auto"`` (CUDA when available, else CPU), ``"cpu"`` or ``"cuda:N"``.
        seed: Seed of the per-env random streams.
        **env_cfg: Fields of the task's env cfg dataclass to override.

    With ``action_chunk`` above 1 the env comes wrapped in an ``ActionChunkWrapper`` (H env steps per action).
    """
    spec = _spec(task)
    cfg = make_env_cfg(spec, **env_cfg)
    env = spec.env_class()(cfg, num_envs=num_envs, device=device, seed=seed)
    if cfg.action_chunk > 1:
        from refpo_warp.envs.action_chunk import ActionChunkWrapper

        env = ActionChunkWrapper(env, cfg.action_chunk)
    return env
