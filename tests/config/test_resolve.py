"""Config layering, validation and 'did you mean' errors; the CLI exits non-zero naming the closest choice."""

import subprocess
import sys

import pytest

from refpo_warp.config.dotted import merge, parse_overrides
from refpo_warp.config.resolve import resolve_config
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT

ROOT = REPO_ROOT


def test_layers_task_over_algo_over_default():
    cfg = resolve_config(["task=gridworld", "algo=refpo"], device_type="cpu")
    assert cfg["num_envs"] == 16 and cfg["total_env_steps"] == 260000  # task file
    assert cfg["algorithm"]["reflow_coef"] == 0.1  # task by_algo.refpo over algo/refpo.yaml's 0.04
    assert cfg["algorithm"]["num_mc_samples"] == 50
    assert cfg["actor"]["class_name"] == "refpo_warp.models:FlowActor"  # algo file
    assert cfg["eval"]["at_end"] is True  # its field's default (refpo_warp/config/run_options.py)
    fpo = resolve_config(["task=gridworld", "algo=fpo"], device_type="cpu")
    assert fpo["algorithm"]["reflow_coef"] == 0.0
    assert {k: v for k, v in fpo["algorithm"].items() if k != "reflow_coef"} == {
        k: v for k, v in cfg["algorithm"].items() if k != "reflow_coef"
    }


def test_overrides_are_typed_like_their_defaults():
    cfg = resolve_config(
        [
            "task=gridworld",
            "algorithm.learning_rate=3e-4",
            "seed=7",
            "eval.flow_steps=[1, 5]",
            "env.size=9",
            "runner.log_full=true",
        ],
        device_type="cpu",
    )
    assert cfg["algorithm"]["learning_rate"] == 3e-4 and isinstance(cfg["algorithm"]["learning_rate"], float)
    assert cfg["seed"] == 7 and cfg["eval"]["flow_steps"] == [1, 5]
    assert cfg["env"]["size"] == 9 and cfg["runner"]["log_full"] is True


@pytest.mark.parametrize(
    "override, suggestion",
    [
        ("task=gridwrld", "gridworld"),
        ("algo=refop", "refpo"),
        ("num_env=8", "num_envs"),
        ("algorithm.reflow_cof=0.1", "algorithm.reflow_coef"),
        ("actor.hiden_dims=[8]", "actor.hidden_dims"),
        ("env.max_episode_lenght=10", "env.max_episode_length"),
        ("eval.flow_step=[1]", "eval.flow_steps"),
    ],
)
def test_unknown_names_suggest_the_closest_valid_one(override, suggestion):
    with pytest.raises(ConfigError, match=f"Did you mean '{suggestion}'"):
        resolve_config(["task=gridworld", override] if not override.startswith("task") else [override])


def test_bad_values_are_reported():
    with pytest.raises(ConfigError, match=r"num_envs=.many. is invalid; expected an integer"):
        resolve_config(["task=gridworld", "num_envs=many"])
    with pytest.raises(ConfigError, match="key=value"):
        parse_overrides(["gridworld"])


def test_merge_is_deep_and_does_not_mutate():
    base = {"a": {"b": 1, "c": 2}, "d": [1]}
    out = merge(base, {"a": {"b": 5}, "d": [2]})
    assert out == {"a": {"b": 5, "c": 2}, "d": [2]} and base["a"]["b"] == 1


def test_cli_unknown_task_exits_nonzero_with_suggestion():
    proc = subprocess.run(
        [sys.executable, "tools/train.py", "task=gridwrld"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 2
    assert "Did you mean 'gridworld'" in proc.stderr


def test_cli_lists_tasks():
    proc = subprocess.run(
        [sys.executable, "tools/train.py", "--list-tasks"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0 and "gridworld" in proc.stdout


def test_env_options_need_no_prefix():
    cfg = resolve_config(["task=gridworld", "size=11", "max_episode_length=50"], device_type="cpu")
    assert cfg["env"] == {"size": 11, "max_episode_length": 50}
    cfg = resolve_config(["task=humanoid_root", "motion_file=clips/"], device_type="cpu")
    assert cfg["env"]["motion_file"] == "clips/"


def test_a_notice_states_the_runs_own_sizes_and_refuses_unknown_fields():
    from refpo_warp.config.run_options import notice_text

    cfg = resolve_config(["task=humanoid_root", "algo=ppo", "num_envs=8", "actor.hidden_dims=[64]"], device_type="cpu")
    text = notice_text(cfg["notice"], cfg, 4096)
    assert "(8 envs, hidden layers 64 / 256 x 256 (actor / critic), 4,096 env steps)" in text
    assert "algo=ppo device=cuda:0" in text
    with pytest.raises(ConfigError, match=r"notice=.*KeyError.*\{num_envs\}"):
        resolve_config(["task=gridworld", "algo=ppo", "notice=at {envs} envs"], device_type="cpu")
