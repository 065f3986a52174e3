"""Task discovery: the families declare their tasks, the registry finds them, and task ids and config files agree."""

import dataclasses

import pytest

from refpo_warp.config.config_set import config_set
from refpo_warp.config.resolve import resolve_config
from refpo_warp.envs.registry import _TASKS, get_task, list_tasks, register_task, task_families
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.tasks.dmc import suite
from refpo_warp.tasks.gridworld.cfg import GridWorldCfg
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import PACKAGED_CONFIG_DIR


def test_every_registered_task_has_a_config_file():
    configs = config_set()
    missing = [t for t in list_tasks() if not configs.task_file(t).is_file()]
    assert not missing, f"registered tasks without a config file: {missing}"


def test_every_task_config_file_names_a_registered_task():
    files = sorted(p.stem for p in (PACKAGED_CONFIG_DIR / "task").glob("*.yaml") if not p.stem.startswith("_"))
    assert files, "no task config files found"
    unregistered = sorted(set(files) - set(list_tasks()))
    assert not unregistered, f"configs/task/*.yaml without a registered task id: {unregistered}"


def test_families_are_found_not_listed():
    assert task_families() == ["dmc", "gridworld", "humanoid"]
    # Every module of the DMC suite is one task id, and nothing else is.
    assert sorted(t for t in list_tasks() if t.startswith("dmc_")) == [f"dmc_{n}" for n in suite.task_names()]
    assert get_task("dmc_cheetah_run").cfg_overrides == {"task": "cheetah_run"}


def test_a_registered_task_without_a_config_file_is_an_error(tmp_path):
    spec = TaskSpec(
        "test_no_config",
        "refpo_warp.tasks.gridworld.env:GridWorldEnv",
        GridWorldCfg,
        config_file=tmp_path / "missing.yaml",
    )
    register_task(spec)
    try:
        with pytest.raises(ConfigError, match=r"test_no_config.*missing.yaml.*does not exist"):
            resolve_config({"task": "test_no_config", "device": "cpu"})
    finally:
        del _TASKS["test_no_config"]


def test_a_spec_names_only_fields_of_its_cfg_and_ids_are_unique():
    with pytest.raises(ConfigError, match=r"grid_size.*size"):
        TaskSpec("bad", "refpo_warp.tasks.gridworld.env:GridWorldEnv", GridWorldCfg, {"grid_size": 5})
    clash = dataclasses.replace(get_task("gridworld"), entry_point="refpo_warp.tasks.dmc.env:DmcEnv")
    with pytest.raises(ValueError, match="already registered"):
        register_task(clash)
