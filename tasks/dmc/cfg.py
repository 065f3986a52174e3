"""The DMC family's env options (Warp-free), those every DMC task reads: the suite task, the solver iteration caps,
Playground's tanh on actions. An option that only one task reads is in that task's cfg, a subclass of ``DmcCfg`` in
``tasks/dmc/<task>_cfg.py`` (``tasks/dmc/__init__.py`` finds it by that name)."""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.tasks.dmc.suite import task_names
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Int, OneOf
from refpo_warp.utils.options import option

TASK_CFG_SUFFIX = "_cfg"  # tasks/dmc/<task>_cfg.py: a task's own options


@dataclass
class DmcCfg(EnvCfg):
    action_transform: str = option(
        "tanh", doc="MuJoCo Playground sends tanh(action) to the DM Control envs (clip: the actions clipped to [-1, 1])"
    )
    task: str = option(
        "cartpole_balance",
        OneOf(task_names(), fixed=True),
        "suite task name (set by the registered task id, e.g. dmc_cheetah_run -> cheetah_run)",
    )
    solver_iterations: int = option(
        0, Int(0, 10_000), "MuJoCo solver iterations; 0 keeps the model file's (Playground's deliberately low) value"
    )
    solver_ls_iterations: int = option(
        0, Int(0, 10_000), "MuJoCo line-search iterations; 0 keeps the model file's value"
    )


def task_cfg_class(name: str) -> type[DmcCfg]:
    """The env cfg class of suite task ``name``: the one ``DmcCfg`` subclass that ``tasks/dmc/<name>_cfg.py`` defines,
    or ``DmcCfg`` where the task has no options of its own."""
    if not (Path(__file__).parent / f"{name}{TASK_CFG_SUFFIX}.py").is_file():
        return DmcCfg
    module = importlib.import_module(f"{__package__}.{name}{TASK_CFG_SUFFIX}")
    found = [
        c
        for c in vars(module).values()
        if isinstance(c, type) and issubclass(c, DmcCfg) and c.__module__ == module.__name__
    ]
    if len(found) != 1:
        raise ConfigError(
            f"{module.__file__} must define exactly one DmcCfg subclass (task {name}'s), found {len(found)}"
        )
    return found[0]


def stray_cfg_modules(folder: Path = Path(__file__).parent) -> list[str]:
    """``*_cfg.py`` files of ``folder`` (``tasks/dmc/``) that name no suite task (a misspelt task name would leave its
    options unused)."""
    names = set(task_names())
    return sorted(
        p.name
        for p in folder.glob(f"*{TASK_CFG_SUFFIX}.py")
        if p.name.removesuffix(f"{TASK_CFG_SUFFIX}.py") not in names
    )
