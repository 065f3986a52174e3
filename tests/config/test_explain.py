"""Where a value comes from: the layers in order, each key's history, sections expanded to the constructor's options,
and the effective config (defaults filled in) that the classes receive."""

import subprocess
import sys

import pytest
from constructor_config import effective_config  # tests/ is on sys.path under pytest

from refpo_warp.config.explain import explain
from refpo_warp.config.layers import PROFILE_KEYS, RUN_DEFAULTS
from refpo_warp.config.resolve import resolve, resolve_config
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT


def test_layers_go_generic_to_specific_and_fpo_is_refpo_with_reflow_off():
    res = resolve(["task=gridworld", "algo=fpo", "seed=3"], device_type="cpu")
    assert [layer.source for layer in res.layers] == [
        RUN_DEFAULTS,
        "configs/default.yaml",
        "configs/task/gridworld.yaml",
        "configs/algo/refpo.yaml",
        "configs/task/gridworld.yaml by_algo.refpo",
        "configs/algo/fpo.yaml",
        "command line",
    ]
    assert res.sources["algorithm.reflow_coef"] == [
        ("configs/task/gridworld.yaml by_algo.refpo", 0.1),
        ("configs/algo/fpo.yaml", 0.0),
    ]
    assert res.sources["seed"] == [(RUN_DEFAULTS, 1), ("command line", 3)]
    refpo = resolve_config(["task=gridworld", "algo=refpo"], device_type="cpu")
    assert {k: v for k, v in res.cfg["algorithm"].items() if k != "reflow_coef"} == {
        k: v for k, v in refpo["algorithm"].items() if k != "reflow_coef"
    }


def test_explain_names_the_layer_that_set_a_key_and_the_constructor_default_below_it():
    text = explain(resolve(["task=gridworld", "algo=fpo"], device_type="cpu"), ["algorithm.reflow_coef"])
    assert (
        "algorithm.reflow_coef = 0.0\n  set by  configs/algo/fpo.yaml\n"
        "  over    0.1 from configs/task/gridworld.yaml by_algo.refpo\n"
        "  over    0.04 from the default of refpo_warp.algorithms.refpo.ReFPO (refpo_warp/algorithms/refpo.py)"
    ) in text


def test_explain_gives_the_comment_a_file_writes_beside_the_value_it_sets(tmp_path):
    text = explain(
        resolve(["task=dmc_point_mass", "algo=fpo_pp"], device_type="cpu"),
        ["algorithm.num_mc_samples", "actor.num_flow_steps", "actor.hidden_dims"],
    )
    assert (
        "algorithm.num_mc_samples = 16\n  set by  configs/algo/fpo_pp.yaml\n"
        '  why     FPO++ rl_cfg.py:234 n_samples_per_action = 16 ("gains plateau beyond 16")\n'
    ) in text
    assert "actor.num_flow_steps = 64\n  set by  configs/algo/fpo_pp.yaml\n  why     FPO++ rl_cfg.py:86" in text
    assert "actor.hidden_dims = [32, 32, 32, 32]\n  set by  configs/task/_dmc.yaml\n  over" in text  # no comment there
    # the comment of the layer that set the value; a later layer without one, or the command line, drops it
    res = resolve(["task=dmc_point_mass", "algo=fpo_pp", "algorithm.num_mc_samples=4"], device_type="cpu")
    assert "why" not in explain(res, ["algorithm.num_mc_samples"])
    from refpo_warp.config.yaml_files import key_comments

    path = tmp_path / "a.yaml"
    path.write_text(
        "a:\n  b: 1   # one '#' in quotes: \"#\"\n  c: {d: 2}  # shared by a flow mapping\n"
        "e: 'x # not a comment'\nf: [1, 2]  # a list\n"
    )
    assert key_comments(path) == {"a.b": "one '#' in quotes: \"#\"", "f": "a list"}


def test_a_section_lists_every_option_of_its_class_and_env_defaults_name_their_cfg():
    res = resolve(["task=dmc_point_mass", "algo=refpo"], device_type="cpu")
    text = explain(res, ["algorithm", "env.task", "env.max_episode_length"])
    assert "algorithm.num_mc_samples = 8\n  set by  the default of refpo_warp.algorithms.refpo.ReFPO" in text
    assert (
        "algorithm.gamma = 0.995\n  set by  configs/task/_dmc.yaml\n  over    0.99 from the default of rsl_rl" in text
    )
    assert "env.task = 'point_mass'\n  set by  the task id dmc_point_mass" in text
    assert "env.max_episode_length = 1000\n  set by  the default of refpo_warp.tasks.dmc.cfg.DmcCfg" in text
    with pytest.raises(ConfigError, match=r"Unknown config key to explain 'algorithm.reflow_cof'.*reflow_coef"):
        explain(res, ["algorithm.reflow_cof"])


def test_the_effective_config_holds_what_the_constructors_receive():
    cfg = effective_config(resolve_config(["task=dmc_cartpole_balance", "algo=refpo"], device_type="cuda"))
    alg, actor = cfg["algorithm"], cfg["actor"]
    assert (alg["reflow_coef"], alg["num_mc_samples"], alg["clip_param"], alg["lam"]) == (0.04, 8, 0.05, 0.95)
    assert (actor["num_flow_steps"], actor["time_embed_dim"], actor["output_scale"]) == (10, 8, 0.25)
    assert cfg["env"]["task"] == "cartpole_balance" and cfg["env"]["action_transform"] == "tanh"


def test_the_rsl_rl_defaults_the_algo_files_leave_to_rsl_rl():
    """configs/algo/ppo.yaml and the ReFPO family take these from rsl-rl-lib (the same in 5.0.1 and 5.5.1): a release
    that changed one would change the project's runs silently, so it fails here."""
    from refpo_warp.config.classes import class_parameters

    ppo = class_parameters("rsl_rl.algorithms:PPO")
    expected = {
        "num_learning_epochs": 5,
        "num_mini_batches": 4,
        "clip_param": 0.2,
        "gamma": 0.99,
        "lam": 0.95,
        "value_loss_coef": 1.0,
        "entropy_coef": 0.01,
        "learning_rate": 0.001,
        "max_grad_norm": 1.0,
        "use_clipped_value_loss": True,
        "schedule": "adaptive",
        "desired_kl": 0.01,
        "normalize_advantage_per_mini_batch": False,
    }
    assert {k: ppo[k] for k in expected} == expected
    mlp = class_parameters("rsl_rl.models:MLPModel")
    assert (tuple(mlp["hidden_dims"]), mlp["activation"]) == ((256, 256, 256), "elu")
    gaussian = class_parameters("rsl_rl.modules:GaussianDistribution")
    assert (gaussian["init_std"], gaussian["std_type"]) == (1.0, "scalar")


@pytest.mark.parametrize(
    "section, bad, message",
    [
        ("by_algo", {"refop": {}}, "Unknown algorithm under by_algo.*'refop'.*Did you mean 'refpo'"),
        ("by_device", {"gpu": {}}, "Unknown device type under by_device.*'gpu'"),
    ],
)
def test_a_task_file_names_only_real_algorithms_and_device_types(tmp_path, section, bad, message):
    import yaml

    from refpo_warp.envs.registry import _TASKS, get_task, register_task
    from refpo_warp.envs.task_spec import TaskSpec

    assert section in PROFILE_KEYS
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump({"base": "gridworld", section: bad}))
    spec = get_task("gridworld")
    register_task(TaskSpec("bad_profile", spec.entry_point, spec.cfg_class, config_file=tmp_path / "bad.yaml"))
    try:
        with pytest.raises(ConfigError, match=message):
            resolve_config({"task": "bad_profile"}, device_type="cpu")
    finally:
        del _TASKS["bad_profile"]


def test_the_cli_explains_without_writing_anything(tmp_path):
    run_dir = tmp_path / "never"
    proc = subprocess.run(
        [sys.executable, "tools/train.py", "task=gridworld", f"run_dir={run_dir}", "--explain", "num_envs"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert (
        "num_envs = 16\n  set by  configs/task/gridworld.yaml\n  over    64 from the run options' defaults "
        "(refpo_warp/config/run_options.py)\n  means   parallel envs"
    ) in proc.stdout
    assert not run_dir.exists()
