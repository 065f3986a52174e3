"""Evaluation never changes training: a run with periodic evaluation (returns, Jacobian statistics, a video) trains
to the same bits as the same run without it, its normalisers included, and the evaluation at the end of training
gives the numbers ``refpo eval`` gives for the same checkpoint."""

import json

import pytest
import torch

from refpo_warp.evaluation.evaluate_run import evaluate_run
from refpo_warp.runner.checkpoints import latest_checkpoint
from refpo_warp.training import train

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

RUN = [
    "task=gridworld",
    "num_envs=8",
    "runner.num_steps_per_env=16",
    "max_iterations=6",
    "runner.save_interval=100",
    "algorithm.num_learning_epochs=1",
    "eval.num_envs=8",
    "eval.interval_num_envs=8",
    "eval.flow_steps=[1, 2]",
    "eval.at_end=false",
    "device=cpu",
    "seed=3",
    "actor.obs_normalization=true",
    "critic.obs_normalization=true",
]  # GridWorld normalises nothing by default


def tensors(tree, prefix=""):
    """Every tensor of a checkpoint by its path (``actor_state_dict.obs_normalizer._mean``, ...)."""
    for key, value in tree.items():
        if isinstance(value, dict):
            yield from tensors(value, f"{prefix}{key}.")
        elif torch.is_tensor(value):
            yield f"{prefix}{key}", value


def training_rows(run_dir):
    rows = [json.loads(line) for line in (run_dir / "progress.jsonl").read_text().splitlines()]
    return [
        {k: v for k, v in row.items() if not k.startswith(("eval/", "Flow/jacobian", "time_s", "steps_per_s"))}
        for row in rows
    ]


@pytest.mark.parametrize("algo", ["refpo", "ppo", "reinflow", "fpo_pp"])
def test_periodic_evaluation_leaves_training_bit_identical(tmp_path, algo):
    extra = ["algorithm.num_mc_samples=4"] if algo != "ppo" and algo != "reinflow" else []
    extra += ["algorithm.ema_warmup=2", "actor.num_flow_steps=4"] if algo == "fpo_pp" else []  # the EMA evaluated
    plain, evaluated = tmp_path / "plain", tmp_path / "evaluated"
    train([*RUN, *extra, f"algo={algo}", f"run_dir={plain}", "eval.interval=0"])
    train([*RUN, *extra, f"algo={algo}", f"run_dir={evaluated}", "eval.interval=2"])
    rows = [json.loads(line) for line in (evaluated / "progress.jsonl").read_text().splitlines()]
    assert sum(any(k.startswith("eval/return") for k in row) for row in rows) == 3  # evaluations did happen
    assert training_rows(plain) == training_rows(evaluated)
    saved = [dict(tensors(torch.load(latest_checkpoint(d), weights_only=True))) for d in (plain, evaluated)]
    evaluation_envs = [k for k in saved[1] if k.startswith("run_state.eval_envs.")]  # the evaluated run's own
    assert evaluation_envs and not any(k.startswith("run_state.eval_envs.") for k in saved[0])
    saved[1] = {k: v for k, v in saved[1].items() if k not in evaluation_envs}
    assert saved[0].keys() == saved[1].keys()
    assert any("obs_normalizer" in name for name in saved[0])  # the normalisers' statistics are compared too
    different = [name for name in saved[0] if not torch.equal(saved[0][name], saved[1][name])]
    assert not different, different


def test_the_final_evaluation_is_what_refpo_eval_gives_for_its_checkpoint(tmp_path):
    run_dir = tmp_path / "run"
    run = [a for a in RUN if a != "eval.at_end=false"]
    at_end = train([*run, "algo=refpo", "algorithm.num_mc_samples=4", "eval.interval=0", f"run_dir={run_dir}"])
    at_end = at_end["results"]
    torch.manual_seed(12345)  # whatever the process's streams hold, the evaluation draws from its own
    assert evaluate_run(run_dir)["results"] == at_end
