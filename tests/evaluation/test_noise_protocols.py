"""Zero- and random-noise evaluation side by side, the EMA policy in a run, and the run's health in eval.json."""

import json

import pytest
import torch

from refpo_warp.evaluation.evaluate_run import evaluate_run
from refpo_warp.runner.checkpoints import latest_checkpoint
from refpo_warp.training import train
from refpo_warp.utils.errors import ConfigError

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)


def test_both_protocols_leave_the_random_numbers_and_the_training_as_they_were(tmp_path, quick_run):
    quick_run = [a for a in quick_run if not a.startswith("eval.interval=")] + ["eval.interval=1"]
    one = train([*quick_run, f"run_dir={tmp_path / 'one'}"])
    both = train([*quick_run, f"run_dir={tmp_path / 'both'}", "eval.initial_noise=[random, zero]"])
    assert set(both["results"]) == {"N=1", "N=2", "N=1/zero", "N=2/zero"}
    for setting in ("N=1", "N=2"):
        assert both["results"][setting] == one["results"][setting]  # random first: same stream, same numbers
    rows = [json.loads(line) for line in (tmp_path / "both" / "progress.jsonl").read_text().splitlines()]
    first = [json.loads(line) for line in (tmp_path / "one" / "progress.jsonl").read_text().splitlines()]
    assert all("eval/return_N1_zero" in row and "eval/return_N10_zero" in row for row in rows)  # interval_flow_steps
    for a, b in zip(first, rows):  # training statistics bit for bit
        assert {k: v for k, v in a.items() if k.startswith(("Loss/", "reward"))} == {
            k: v for k, v in b.items() if k.startswith(("Loss/", "reward"))
        }
    assert both["protocol"]["initial_noise"] == ["random", "zero"]
    assert set(both["health"]["curves"]) == {"N=1", "N=10", "N=1/zero", "N=10/zero"}
    assert both["health"]["curves"]["N=1"]["final_iteration"] == 2
    assert both["health"]["cliff"]["status"] == "insufficient_data"  # 3 iterations of FPO++'s 150


def test_zero_noise_evaluation_repeats_exactly(tmp_run_dir, quick_run):
    train([*quick_run, f"run_dir={tmp_run_dir}", "eval.initial_noise=zero"])
    first = evaluate_run(tmp_run_dir, overrides={"eval.initial_noise": "zero"})["results"]
    torch.manual_seed(123)  # another random stream: zero noise does not read it
    assert evaluate_run(tmp_run_dir, overrides={"eval.initial_noise": "zero"})["results"] == first
    assert set(first) == {"N=1/zero", "N=2/zero"}


@pytest.mark.parametrize(
    "value, words",
    [
        ("[random, random]", "listed twice"),
        ("[]", "expected random, zero"),
        ("noisy", "expected one of 'random', 'zero'"),
    ],
)
def test_bad_protocols_are_refused_by_name(tmp_run_dir, quick_run, value, words):
    with pytest.raises(ConfigError, match=words) as err:
        train([*quick_run, f"run_dir={tmp_run_dir}", f"eval.initial_noise={value}"])
    assert "eval.initial_noise" in str(err.value) and not tmp_run_dir.exists()


def test_a_run_with_the_ema_checkpoints_both_and_evaluates_the_ema(tmp_run_dir, quick_run):
    quick_run = [a.replace("algo=refpo", "algo=fpo_pp") for a in quick_run]
    out = train([*quick_run, f"run_dir={tmp_run_dir}", "algorithm.ema_decay=0.5", "algorithm.ema_warmup=1"])
    saved = torch.load(latest_checkpoint(tmp_run_dir), weights_only=True)
    live, ema = saved["actor_state_dict"], saved["ema_actor_state_dict"]
    assert any(not torch.equal(live[k], ema[k]) for k in live)
    assert set(out["results"]) == {"N=1", "N=2", "N=1/zero", "N=2/zero"}  # fpo_pp.yaml: both protocols
    # evaluation loads the EMA; the same checkpoint with the EMA switched off gives the live weights
    assert set(evaluate_run(tmp_run_dir)["results"]) == set(out["results"])
    obs = {"policy": torch.randn(5, 2)}
    ema_actions, live_actions = (
        inference_policy(tmp_run_dir, overrides)(obs) for overrides in ({}, {"algorithm.ema_decay": None})
    )
    assert not torch.allclose(ema_actions, live_actions)


def inference_policy(run_dir, overrides):
    from tensordict import TensorDict

    from refpo_warp.config.saved import load_run
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    run = load_run(run_dir, overrides)
    cfg = run.cfg
    _, runner = build_runner(run, None)
    load_latest(runner, run_dir, cfg["task"], cfg["algo"])
    policy = runner.get_inference_policy()
    return lambda obs: policy(TensorDict(obs, batch_size=[5]))


def test_ema_options_are_validated_and_explained(tmp_run_dir, quick_run):
    for value in ("1.0", "0", "-0.5"):
        with pytest.raises(ConfigError, match=rf"algorithm.ema_decay={value}.*null or a number in \(0, 1\)"):
            train([*quick_run, f"run_dir={tmp_run_dir}", f"algorithm.ema_decay={value}"])
    from refpo_warp.config.explain import explain
    from refpo_warp.config.resolve import resolve

    text = explain(resolve(["task=gridworld", "algo=fpo_pp"], device_type="cpu"), ["algorithm.ema_decay"])
    assert "0.95" in text and "fpo_pp.py" in text
