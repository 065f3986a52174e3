"""Tasks that a user's config folder adds: a file ``task/<name>.yaml`` there whose name is no registered task id is a
new task id, a variant of the registered task its ``base`` chain names (its env, env cfg and the env options that id
fixes), trained with the file's settings over that task's::

    # my_configs/task/gridworld_small.yaml: `refpo train task=gridworld_small config_dir=my_configs`
    base: gridworld
    num_envs: 8
    env: {max_episode_length: 100}

A file whose name is a registered id is that task's config (a task registered by code without a config file).
"""

from __future__ import annotations

from pathlib import Path

from refpo_warp.config.config_path import ConfigPath
from refpo_warp.config.layers import file_chain
from refpo_warp.envs.registry import get_task, list_tasks, register_task
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import shown

_VARIANTS: set[str] = set()  # the ids registered here (a later config path may register them from another file)


def register_config_tasks(path: ConfigPath) -> list[str]:
    """Register the task variants of the user's config folders; their ids."""
    added = []
    for name, file in path.user_files("task").items():
        if name.startswith("_") or (name in list_tasks() and name not in _VARIANTS):
            continue
        base = variant_base(name, file, path)
        spec = get_task(base)
        register_task(
            TaskSpec(
                name,
                spec.entry_point,
                spec.cfg_class,
                dict(spec.cfg_overrides),
                description=f"{spec.description} (from {shown(file)})",
                config_file=file,
            ),
            replace=name in _VARIANTS,
        )
        _VARIANTS.add(name)
        added.append(name)
    return added


def variant_base(name: str, file: Path, path: ConfigPath) -> str:
    """The registered task a variant's ``base`` chain names (exactly one)."""
    registered = [t for t in list_tasks() if t not in _VARIANTS]
    named = {found.stem for found, _ in file_chain(file, "task", path, (name,))[:-1]} & set(registered)
    if len(named) != 1:
        what = "names none" if not named else f"names several ({', '.join(sorted(named))})"
        raise ConfigError(
            f"{shown(file)}: a task file of your own either configures a registered task (its name is "
            f"the task id) or derives from exactly one with base: <task id>; its base chain {what}. "
            f"Registered tasks: {', '.join(registered)}"
        )
    return named.pop()
