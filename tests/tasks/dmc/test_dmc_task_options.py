"""Per-task env options of the DMC family: a task's own cfg (``tasks/dmc/<task>_cfg.py``, a ``DmcCfg`` subclass) is
the only one that accepts its options; another task refuses them (exit 2), naming itself, its options and the task
that has them."""

import subprocess
import sys
from dataclasses import fields

import pytest

from refpo_warp.config.resolve import resolve_config
from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.envs.registry import check_env_options, get_task, list_tasks, make_env_cfg
from refpo_warp.tasks.dmc import suite
from refpo_warp.tasks.dmc.cfg import DmcCfg, stray_cfg_modules, task_cfg_class
from refpo_warp.tasks.dmc.cheetah_run_cfg import CheetahRunCfg
from refpo_warp.tasks.dmc.point_mass_wall_cfg import PointMassWallCfg
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT

FAMILY = {
    "task",
    "solver_iterations",
    "solver_ls_iterations",
}  # DmcCfg's own (action_transform: a new default); read by tasks/dmc/env.py


def names(cls) -> set[str]:
    return {f.name for f in fields(cls)}


def test_each_task_takes_its_own_cfg_or_the_familys():
    own = {name: task_cfg_class(name) for name in suite.task_names() if task_cfg_class(name) is not DmcCfg}
    assert own == {"cheetah_run": CheetahRunCfg, "point_mass_wall": PointMassWallCfg}
    for name in suite.task_names():
        assert get_task(f"dmc_{name}").cfg_class is task_cfg_class(name)
    assert names(DmcCfg) - names(EnvCfg) == FAMILY  # nothing only some tasks read
    assert names(CheetahRunCfg) - names(DmcCfg) == {"reset_bank_size"}
    assert names(PointMassWallCfg) - names(DmcCfg) == {"wall_half_length", "wall_half_thickness", "start_spread"}
    assert stray_cfg_modules() == []


def test_a_cfg_file_that_names_no_task_is_found(tmp_path):
    for file in ("cheetah_run_cfg.py", "cheeta_run_cfg.py", "cfg.py", "bench.py"):
        (tmp_path / file).write_text("")
    assert stray_cfg_modules(tmp_path) == ["cheeta_run_cfg.py"]


def test_the_reset_bank_is_cheetahs_option():
    cfg = make_env_cfg("dmc_cheetah_run", reset_bank_size=8)
    assert cfg.reset_bank(4) == 8 and make_env_cfg("dmc_cheetah_run").reset_bank(4) == 256
    assert make_env_cfg("dmc_cheetah_run").reset_bank(300) == 300  # max(num_envs, 256)
    with pytest.raises(ConfigError, match=r"'reset_bank_size': an env option of dmc_cheetah_run only"):
        make_env_cfg("dmc_cartpole_balance", reset_bank_size=8)


def test_another_tasks_option_is_refused_naming_the_task_its_options_and_the_owner():
    with pytest.raises(ConfigError) as err:
        check_env_options(get_task("dmc_cheetah_run"), {"wall_half_length": 0.1}, "env.")
    message = str(err.value)
    assert message.startswith(
        "Unknown env option for task 'dmc_cheetah_run' 'env.wall_half_length': an env option of dmc_point_mass_wall"
        " only. Valid choices: env.action_chunk, env.action_transform, env.graph_capture,"
    )
    valid = message.split("Valid choices: ")[1].split(", ")
    assert sorted(k.removeprefix("env.") for k in valid) == sorted(names(CheetahRunCfg))
    with pytest.raises(ConfigError, match=r"'env.wall_lenght'. Did you mean 'env.wall_half_length'"):
        check_env_options(get_task("dmc_point_mass_wall"), {"wall_lenght": 0.1}, "env.")
    check_env_options(get_task("dmc_point_mass_wall"), {"wall_half_length": 0.1, "max_episode_length": 5}, "env.")


@pytest.mark.parametrize(
    ("task", "key", "owner"),
    [
        ("dmc_point_mass", "env.wall_half_length=0.1", "dmc_point_mass_wall"),
        ("dmc_cartpole_balance", "env.reset_bank_size=8", "dmc_cheetah_run"),  # accepted and ignored before
        ("dmc_walker_walk", "eval.env.start_spread=0.01", "dmc_point_mass_wall"),
        ("gridworld", "env.reset_bank_size=8", "dmc_cheetah_run"),
    ],
)
def test_a_config_with_another_tasks_option_is_refused(task, key, owner):
    with pytest.raises(ConfigError, match=f"for task '{task}' '{key.split('=')[0]}': an env option of {owner} only"):
        resolve_config([f"task={task}", "algo=ppo", "device=cpu", key], device_type="cpu")


def test_every_task_resolves_with_only_the_options_it_has():
    """Every task's own options resolve for it; the family's for every DMC task."""
    for task in (t for t in list_tasks() if t.startswith("dmc_")):
        own = names(get_task(task).cfg_class) - names(DmcCfg)
        overrides = {"reset_bank_size": 8, "wall_half_length": 0.1, "solver_iterations": 3}
        given = {k: v for k, v in overrides.items() if k in own or k in FAMILY}
        cfg = resolve_config({"task": task, "algo": "ppo", "device": "cpu", "env": given}, device_type="cpu")
        assert cfg["env"] == given


def test_the_cli_exits_2_naming_the_task_and_its_options(tmp_path):
    run_dir = tmp_path / "run"
    argv = ["task=dmc_cheetah_run", "env.wall_half_length=0.1", f"run_dir={run_dir}", "max_iterations=1"]
    proc = subprocess.run(
        [sys.executable, "tools/train.py", *argv, "num_envs=2"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 2, proc.stderr
    assert (
        "Unknown env option for task 'dmc_cheetah_run' 'env.wall_half_length': an env option of dmc_point_mass_wall "
        "only. Valid choices: " in proc.stderr
    )
    assert "env.reset_bank_size" in proc.stderr and "Traceback" not in proc.stderr and not run_dir.exists()


def test_the_env_refuses_a_cfg_other_than_its_tasks():
    """A spec registered by hand with the family's cfg for a task with its own: refused before the model is built."""
    from refpo_warp.tasks.dmc.env import DmcEnv

    with pytest.raises(ConfigError, match="DMC task cheetah_run takes a CheetahRunCfg, got a DmcCfg"):
        DmcEnv(DmcCfg(task="cheetah_run"), num_envs=2, device="cpu")
