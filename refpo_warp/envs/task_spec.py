"""``TaskSpec``: what a task family declares about one task id (no imports of its own, so families depend on it and
not on the registry that discovers them).

A family package ``tasks/<family>/__init__.py`` lists its tasks as ``TASKS = [TaskSpec(...), ...]``; the registry
(``refpo_warp.envs.registry``) finds the families and reads these lists. Code outside ``tasks/`` registers a spec with
``refpo_warp.envs.registry.register_task``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from refpo_warp.envs.env_cfg import EnvCfg


@dataclass(frozen=True)
class TaskSpec:
    """One task: its env (built lazily), its Warp-free env cfg class, the cfg fields its id fixes, and its training
    config file."""

    task_id: str
    entry_point: str
    """``"module.path:ClassName"`` of a ``WarpVecEnv`` subclass, imported only when an env is built."""
    cfg_class: type[EnvCfg]
    """Its env cfg dataclass (an ``EnvCfg`` subclass from a module that does not import Warp)."""
    cfg_overrides: dict[str, Any] = field(default_factory=dict)
    """Env cfg fields this id fixes (e.g. the DMC suite task)."""
    description: str = ""
    config_file: str | Path | None = None
    """Its training config (a YAML layer over the run options' defaults); None: ``configs/task/<task_id>.yaml``."""

    def __post_init__(self) -> None:
        what = f"env option of {self.cfg_class.__name__} (task '{self.task_id}')"
        self.cfg_class.check_keys(self.cfg_overrides, what)

    def env_class(self) -> type:
        module_path, name = self.entry_point.split(":")
        return getattr(importlib.import_module(module_path), name)
