"""One name per concept across the refpo commands: the output folder is out=DIR, a sweep dir is the subject of both
report and plot, and the spellings a command once took are refused with the name they have now (exit 2, no
traceback)."""

import json

import pytest
import yaml

from refpo_warp.cli.main import main
from refpo_warp.studies.grid.spec import fingerprint


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["report", "runs/x", "--out", "o"], "'--out' is spelled 'out='"),
        (["report", "runs/x", "--curve-methods=ppo"], "'--curve-methods' is spelled 'curve_methods='"),
        (["report", "runs/x", "seed=3"], "'seed=' is spelled 'ratio_seed='"),
        (["plot", "sweep=runs/x"], "'sweep=' is spelled 'refpo plot <sweep dir>'"),
        (["plot", "run_dir=a", "run_dir=b"], "'run_dir=' is spelled 'run_dirs=[A,B]'"),
        (["report", "runs/x", "outt=o"], "Did you mean 'out'"),
        (["plot", "run_dirs=[a]", "ou=b"], "Did you mean 'out'"),
        (["train", "--tasks"], "'--tasks' is spelled '--list-tasks'"),
        (["make-clips", "--seed", "3", "out=x"], "'--seed' is spelled 'seed='"),
        (["make-clips", "x"], "the output folder is out=DIR now"),
        (["convert-amass", "a", "b.motionlib.npz"], "the output file is out=PATH now"),
        (["collect", "episodes=1", "out=x", "sample=mean"], "'sample=' is spelled 'initial_noise="),
        (["sweep", "cpu_dmc", "seed=3"], "'seed=' is spelled 'seeds='"),
        (["sweep", "cpu_dmc", "algo=ppo"], "'algo=' is spelled 'methods='"),
        # the benchmarks read the same grammar: key=value options, one name for the env count, env.<option>=
        (["bench", "gridworld", "--envs", "4"], "'--envs' is spelled 'num_envs='"),
        (["bench", "gridworld", "--num-envs", "4"], "'--num-envs' is spelled 'num_envs='"),
        (["bench", "algorithms", "--minibatches=8"], "'--minibatches' is spelled 'num_mini_batches='"),
        (["bench", "algorithms", "--steps", "8"], "'--steps' is spelled 'num_steps_per_env='"),
        (["bench", "humanoid", "--env", "njmax=3"], "'--env' is spelled 'env.<option>='"),
        (["bench", "humanoid", "--json"], "'--json' is spelled 'out=PATH"),
        (["bench", "humanoid", "--steps", "3"], "'--steps' is spelled 'timed_steps='"),
        (["bench", "dmc", "--tasks", "cheetah_run"], "'--tasks' is spelled 'tasks='"),
        (["bench", "dmc", "--seconds", "1"], "'--seconds' is spelled 'timed_seconds='"),
        (["bench", "render", "--seconds", "1"], "'--seconds' is spelled 'video_seconds='"),
        (["bench", "latency", "--json", "x.json"], "'--json' is spelled 'out='"),
        (["bench", "latency", "--flow-steps", "10,1"], "'--flow-steps' is spelled 'flow_steps='"),
        (["bench", "dmc", "num_env=4"], "Did you mean 'num_envs'"),
        (["bench", "dmc", "--num-env", "4"], "Unknown flag of refpo bench dmc '--num-env'"),
        (["bench", "algorithms", "algos=refpoo"], "Did you mean 'refpo'"),
        (["bench", "dmc", "tasks=[dmc_cheetah_runn]"], "unknown DMC task ids"),
        # one list syntax, YAML's, in every command: a bare a,b is refused with the list spelling
        (["bench", "latency", "algos=ppo,fpo"], "algos='ppo,fpo' is invalid: a list is written algos=[ppo,fpo]"),
        (["report", "runs/x", "curve_methods=a,b"], "a list is written curve_methods=[a,b]"),
        (["sweep", "cpu_dmc", "methods=ppo,refpo"], "a list is written methods=[ppo,refpo]"),
        (["tune", "cpu_dmc", "methods=ppo,refpo"], "a list is written methods=[ppo,refpo]"),
        (["train", "task=gridworld", "eval.flow_steps=1,10"], "a list is written eval.flow_steps=[1,10]"),
        (["bench", "dmc", "num_envs=4", "num_envs=5"], "'num_envs' is given twice"),
        (["bench", "dmc", "num_envs=0"], "num_envs=0 is invalid"),
        (["bench", "dmc", "device=gpu"], "device='gpu' is invalid; expected auto, cpu, cuda or cuda:N"),
    ],
)
def test_old_spellings_typos_and_bad_values_are_refused_with_the_name_now(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err, err


def test_an_unknown_key_names_every_valid_one(capsys):
    assert main(["bench", "render", "frames=3"]) == 2
    err = capsys.readouterr().err
    assert "Valid choices: height, timed_frames, video_seconds, width" in err, err


def test_a_list_option_takes_yaml_lists_and_one_item_alone():
    from refpo_warp.benchmarks.latency import Options
    from refpo_warp.config.command_options import parse_options

    options, rest = parse_options("bench latency", Options, ["algos=[ppo, refpo]", "tasks=gridworld", "flow_steps=1"])
    assert options.algos == ["ppo", "refpo"] and options.tasks == ["gridworld"] and options.flow_steps == [1]
    assert options.batch_sizes == [1, "num_envs"] and options.repeats == 50 and rest == {}


def test_every_renamed_spelling_is_refused_by_its_command():
    """The table's every entry is refused by its command, naming the spelling it has now."""
    from refpo_warp.utils.renamed_spellings import RENAMED, renamed_error

    for command, table in RENAMED.items():
        for old, new in table.items():
            error = renamed_error(command, old)
            assert error is not None and f"'{old}' is spelled '{new}' now" in str(error)
    assert renamed_error("bench dmc", "num_envs=") is None


@pytest.mark.parametrize(
    ("argv", "shown"),
    [
        (
            ["bench", "dmc", "--help"],
            ["refpo bench dmc [key=value ...]", "num_envs=null", "tasks=null", "mujoco_c=true"],
        ),
        (["bench", "humanoid", "--help"], ["env.<option>=VALUE", "timed_steps=null", "out=null"]),
        (["bench", "gridworld", "--help"], ["num_envs=4096", "gym_steps=20"]),
        (["bench", "latency", "--help"], ["tasks=[dmc_cheetah_run]", "flow_steps=[10, 1]", "batch_sizes="]),
        (["bench", "algorithms", "--help"], ["num_mini_batches=8", "num_learning_epochs=2", "num_steps_per_env=60"]),
        (["bench", "render", "--help"], ["timed_frames=60", "video_seconds=10.0"]),
        (["bench", "train", "--help"], ["algo=[ppo, refpo]", "iterations=3", "[run option=VALUE ...]", "num_envs="]),
        (["report", "--help"], ["curve_methods=null", "ratio_seed=null", "--explain"]),
        (["plot", "--help"], ["run_dirs=null", "out=null"]),
        (["play", "--help"], ["agent=null", "device=auto", "out=runs/videos"]),
        (["collect", "--help"], ["initial_noise=random", "device=auto", "--explain"]),
        (["sweep", "--help"], ["seeds=null", "methods=null", "--explain"]),
        (["tune", "--help"], ["trials=null", "methods=null", "config_dir=null"]),
    ],
)
def test_each_commands_help_lists_its_options_from_the_fields(argv, shown, capsys):
    assert main(argv) == 0
    out = capsys.readouterr().out
    for text in shown:
        assert text in out, (text, out)


def test_explain_says_where_each_option_comes_from(capsys):
    assert main(["bench", "latency", "--explain", "algos,repeats", "algos=[ppo]"]) == 0
    out = capsys.readouterr().out
    assert "algos = [ppo]\n  set by  the command line" in out
    assert "repeats = 50\n  set by  the default (its field in refpo_warp.benchmarks.latency)" in out
    assert main(["report", "runs/x", "--explain", "ratio_seed", "ratio_seed=3"]) == 0
    assert "ratio_seed = 3\n  set by  the command line" in capsys.readouterr().out
    assert main(["bench", "train", "--explain", "warmup", "task=gridworld", "warmup=0", "algorithm.lam=0.9"]) == 0
    out = capsys.readouterr().out
    assert "warmup = 0\n  set by  the command line" in out and "passed on: task=gridworld algorithm.lam=0.9" in out
    assert main(["collect", "--explain", "device", "episodes=1", "out=x"]) == 0
    assert "device = auto" in capsys.readouterr().out
    assert main(["sweep", "cpu_dmc", "--explain", "seeds", "seeds=[21,22]", "methods=ppo"]) == 0
    assert "seeds = [21, 22]" in capsys.readouterr().out


@pytest.fixture
def sweep_dir(tmp_path):
    """A sweep dir of two finished runs (what refpo sweep leaves: sweep.yaml, config.yaml, eval.json, progress)."""
    root, runs = tmp_path / "sweep", []
    for seed in (1, 2):
        run_dir = root / "dmc_a" / "ppo" / f"seed{seed}"
        run_dir.mkdir(parents=True)
        config = {"task": "dmc_a", "algo": "ppo", "seed": seed, "device": "cpu"}
        (run_dir / "config.yaml").write_text(yaml.safe_dump(config))
        (run_dir / "eval.json").write_text(
            json.dumps(
                {
                    "task": "dmc_a",
                    "algo": "ppo",
                    "seed": seed,
                    "results": {"mean_action": {"return_mean": 100.0 + seed}},
                }
            )
        )
        rows = [
            {"iteration": i, "env_steps": 1000 * (i + 1), "reward_mean": 10.0 * i, "eval/return": 50.0 * i}
            for i in range(2)
        ]
        (run_dir / "progress.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
        runs.append(
            {
                "task": "dmc_a",
                "label": "ppo",
                "algo": "ppo",
                "seed": seed,
                "run_dir": str(run_dir.relative_to(root)),
                "fingerprint": fingerprint(config),
            }
        )
    spec = {
        "name": "tiny",
        "device": "cpu",
        "tasks": ["dmc_a"],
        "seeds": [1, 2],
        "runs": runs,
        "methods": [{"label": "ppo", "name": "PPO", "algo": "ppo"}],
    }
    (root / "sweep.yaml").write_text(yaml.safe_dump(spec))
    return root


def test_report_and_plot_take_the_sweep_dir_and_out(sweep_dir, tmp_path):
    assert main(["report", str(sweep_dir), f"out={tmp_path / 'report'}", "curve_methods=[ppo]", "ratio_seed=2"]) == 0
    assert (tmp_path / "report" / "report.md").exists() and (tmp_path / "report" / "main.csv").exists()
    assert main(["plot", str(sweep_dir), f"out={tmp_path / 'curves'}"]) == 0
    assert list((tmp_path / "curves").glob("*_curves.png"))
