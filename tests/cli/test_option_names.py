"""One name per concept across the refpo commands: the output folder is out=DIR, a sweep dir is the subject of both
report and plot, and the spellings a command once took are refused with the name they have now (exit 2, no
traceback)."""

import json

import pytest
import yaml

from refpo_warp.cli.main import main
from refpo_warp.sweeps.spec import fingerprint


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["report", "runs/x", "--out", "o"], "'--out' is spelled 'out='"),
        (["report", "runs/x", "--curve-methods=ppo"], "'--curve-methods' is spelled 'curve_methods='"),
        (["plot", "sweep=runs/x"], "'sweep=' is spelled 'refpo plot <sweep dir>'"),
        (["report", "runs/x", "outt=o"], "Did you mean 'out'"),
        (["plot", "run_dir=a", "ou=b"], "Did you mean 'out'"),
        # the benchmarks read the same convention: one name for the env count, env options as env.<option>=
        (["bench", "gridworld", "--envs", "4"], "'--envs' is spelled '--num-envs'"),
        (["bench", "algorithms", "--envs=8"], "'--envs' is spelled '--num-envs'"),
        (["bench", "humanoid", "--env", "njmax=3"], "'--env' is spelled 'env.<option>='"),
        (["bench", "dmc", "--num-env", "4"], "Did you mean '--num-envs'"),
        (["bench", "algorithms", "--algos", "refpoo"], "Did you mean 'refpo'"),
    ],
)
def test_old_spellings_and_typos_are_refused_with_the_name_now(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err, err


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
    assert main(["report", str(sweep_dir), f"out={tmp_path / 'report'}", "curve_methods=ppo"]) == 0
    assert (tmp_path / "report" / "report.md").exists() and (tmp_path / "report" / "main.csv").exists()
    assert main(["plot", str(sweep_dir), f"out={tmp_path / 'curves'}"]) == 0
    assert list((tmp_path / "curves").glob("*_curves.png"))


def test_a_benchmarks_help_lists_its_flags(capsys):
    assert main(["bench", "dmc", "--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("refpo bench dmc [flags]") and "--num-envs NUM_ENVS" in out and "--no-mujoco-c" in out
