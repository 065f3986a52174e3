"""A user's config folder (``config_dir=`` or ``REFPO_CONFIG_PATH``): its task, algo and sweep files load, are
validated and explained like the shipped ones, and its task files are listed; mistakes name the file or option."""

import pytest

from refpo_warp.cli.main import main
from refpo_warp.config.config_path import ENV_VAR, config_path
from refpo_warp.config.layers import RUN_DEFAULTS
from refpo_warp.config.resolve import resolve
from refpo_warp.studies.grid.spec import load_sweep
from refpo_warp.utils.errors import ConfigError

VARIANT = "base: gridworld\nnum_envs: 8\nenv: {max_episode_length: 50}\n"
ALGO = "base: refpo\nalgorithm: {reflow_coef: 0.3}\n"
SWEEP = "device: cpu\ntasks: [grid_small]\nseeds: [1]\nmethods:\n  - {label: mine, algo: my_refpo}\n"


@pytest.fixture
def user_configs(tmp_path):
    folder = tmp_path / "my_configs"
    for kind, name, text in (("task", "grid_small", VARIANT), ("algo", "my_refpo", ALGO), ("sweep", "mine", SWEEP)):
        (folder / kind).mkdir(parents=True, exist_ok=True)
        (folder / kind / f"{name}.yaml").write_text(text)
    return folder


def test_a_user_task_and_algo_resolve_over_the_shipped_layers(user_configs):
    res = resolve({"task": "grid_small", "algo": "my_refpo", "device": "cpu", "config_dir": str(user_configs)})
    cfg = res.cfg
    assert cfg["num_envs"] == 8 and cfg["env"]["max_episode_length"] == 50
    assert cfg["runner"]["num_steps_per_env"] == 128  # gridworld's, through base
    assert cfg["algorithm"]["reflow_coef"] == 0.3 and cfg["algorithm"]["num_mc_samples"] == 50  # its base's by_algo
    assert cfg["config_dir"] == str(user_configs)  # absolute: the run's evaluation finds it from anywhere
    sources = [layer.source for layer in res.layers]
    assert sources[:3] == [RUN_DEFAULTS, "configs/default.yaml", "configs/task/gridworld.yaml"]
    assert str(user_configs / "task" / "grid_small.yaml") in sources
    assert f"{user_configs / 'task' / 'grid_small.yaml'} by_algo.refpo" not in sources  # the variant sets none
    assert str(user_configs / "algo" / "my_refpo.yaml") in sources


def test_the_environment_variable_names_folders_too(user_configs, monkeypatch):
    monkeypatch.setenv(ENV_VAR, str(user_configs))
    assert config_path().user_dirs == (user_configs,)
    assert resolve({"task": "grid_small", "device": "cpu"}).cfg["num_envs"] == 8


def test_tasks_lists_the_users_task_and_explain_names_its_file(user_configs, capsys):
    assert main(["train", "--list-tasks", f"config_dir={user_configs}"]) == 0
    listed = capsys.readouterr().out
    assert "gridworld " in listed and "grid_small" in listed and "grid_small.yaml" in listed
    code = main(
        [
            "train",
            "task=grid_small",
            "algo=my_refpo",
            "device=cpu",
            f"config_dir={user_configs}",
            "--explain",
            "algorithm.reflow_coef",
        ]
    )
    assert code == 0
    explained = capsys.readouterr().out
    assert f"algorithm.reflow_coef = 0.3\n  set by  {user_configs / 'algo' / 'my_refpo.yaml'}" in explained


def test_list_names_the_users_sweep_beside_the_shipped_ones_with_their_descriptions(user_configs, capsys):
    (user_configs / "sweep" / "mine.yaml").write_text("description: my grid\n" + SWEEP)
    assert main(["sweep", "--list", f"config_dir={user_configs}"]) == 0
    listed = capsys.readouterr().out.splitlines()
    names = [line.split()[0] for line in listed]
    assert names == sorted(names) and {"cpu_dmc", "trend_8x", "mine"} <= set(names)
    assert [line.split(None, 1)[1] for line in listed if line.startswith("mine ")] == ["my grid"]
    assert main(["tune", "--list"]) == 0
    assert capsys.readouterr().out.split()[0] == "cpu_dmc"
    assert main(["sweep", "--list", "tasks=[x]"]) == 2  # only config_dir= applies
    assert "Valid choices: config_dir" in capsys.readouterr().err


def test_a_user_sweep_is_found_by_name(user_configs):
    sweep = load_sweep("mine", [f"config_dir={user_configs}"])
    assert [run.key for run in sweep.runs] == ["grid_small/mine/seed1"]
    assert f'config_dir="{user_configs}"' in sweep.runs[0].args  # every run gets the folder


@pytest.mark.parametrize(
    "case,match",
    [
        ("missing", r"config_dir=.*nowhere: no such directory"),
        ("no_layout", r"config_dir=.*has none of the folders task/, algo/, sweep/"),
        ("shadow", r"my_configs/algo/refpo.yaml has the name of configs/algo/refpo.yaml .*base: refpo\)"),
        ("no_env", r"orphan.yaml: a task file of your own .* names none. Registered tasks: dmc_acrobot"),
        ("defaults", r"holds a default.yaml, which is never read"),
        ("bad_base", r"Unknown base of .*my_refpo.yaml .* 'refpoo'. Did you mean 'refpo'"),
    ],
)
def test_mistakes_name_the_file_or_option(user_configs, tmp_path, case, match):
    folder = user_configs
    if case == "missing":
        folder = tmp_path / "nowhere"
    elif case == "no_layout":
        folder = tmp_path / "empty"
        folder.mkdir()
    elif case == "shadow":
        (user_configs / "algo" / "refpo.yaml").write_text(ALGO)
    elif case == "no_env":
        (user_configs / "task" / "orphan.yaml").write_text("num_envs: 4\n")
    elif case == "defaults":
        (user_configs / "default.yaml").write_text("seed: 3\n")
    elif case == "bad_base":
        (user_configs / "algo" / "my_refpo.yaml").write_text("base: refpoo\n")
    with pytest.raises(ConfigError, match=match):
        resolve({"task": "grid_small", "algo": "my_refpo", "device": "cpu", "config_dir": str(folder)})


def test_a_user_task_is_never_registered_and_trains_from_the_spec_its_folder_gives(user_configs, tmp_path):
    from refpo_warp.config.saved import load_run
    from refpo_warp.envs.registry import list_tasks
    from refpo_warp.training import train

    before = list_tasks()
    run_dir = tmp_path / "run"
    options = [f"config_dir={user_configs}", "device=cpu", "max_iterations=1", "eval.num_envs=4"]
    options += ["runner.num_steps_per_env=8", "eval.flow_steps=[1]", "algorithm.num_mc_samples=4"]
    results = train(["task=grid_small", "algo=my_refpo", f"run_dir={run_dir}", *options])
    assert set(results["results"]) == {"N=1"} and (run_dir / "model_0.pt").is_file()
    assert load_run(run_dir, {}).cfg["task"] == "grid_small"  # the saved config_dir finds the task again
    assert list_tasks() == before and "grid_small" not in before  # resolving and training registered nothing
