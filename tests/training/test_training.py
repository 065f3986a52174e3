"""Training front door: rsl_rl's own runner with class_name strings, checkpoints, resume, NaN stop, eval.json."""

import json

import pytest
import torch
from rsl_rl.runners import OnPolicyRunner

from refpo_warp import make_env
from refpo_warp.evaluation.episodes import run_episodes
from refpo_warp.runner.checkpoints import latest_checkpoint
from refpo_warp.training import train
from refpo_warp.utils.errors import ConfigError, NonFiniteLossError

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

QUICK = [
    "task=gridworld",
    "algo=refpo",
    "num_envs=8",
    "runner.num_steps_per_env=32",
    "max_iterations=3",
    "algorithm.num_mc_samples=4",
    "algorithm.num_learning_epochs=2",
    "runner.save_interval=1",
    "eval.num_envs=16",
    "eval.flow_steps=[1, 2]",
    "device=cpu",
]


def test_rsl_rl_runner_trains_flow_policy_from_plain_dict():
    """An existing rsl_rl config switches to ReFPO by changing only class_name strings (and flow options).

    The algorithm dict carries every key Isaac Lab's RslRlPpoAlgorithmCfg sends, plus the flow options.
    """
    torch.manual_seed(0)
    env = make_env("gridworld", num_envs=16, device="cpu", seed=1)
    cfg = {
        "num_steps_per_env": 64,
        "save_interval": 100,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {
            "class_name": "refpo_warp.models:FlowActor",
            "hidden_dims": [64, 64],
            "activation": "relu",
            "obs_normalization": False,
            "distribution_cfg": None,
            "num_flow_steps": 10,
        },
        "critic": {"class_name": "MLPModel", "hidden_dims": [64, 64], "activation": "relu", "obs_normalization": False},
        "algorithm": {
            "class_name": "refpo_warp.algorithms:ReFPO",
            "reflow_coef": 0.1,
            "num_mc_samples": 8,
            "num_learning_epochs": 5,
            "num_mini_batches": 4,
            "clip_param": 0.2,
            "gamma": 0.99,
            "lam": 0.98,
            "learning_rate": 1e-3,
            "entropy_coef": 0.0,
            "desired_kl": 0.01,
            "schedule": "fixed",
            "max_grad_norm": 0.5,
            "value_loss_coef": 1.0,
            "use_clipped_value_loss": False,
            "normalize_advantage_per_mini_batch": False,
            "optimizer": "adam",
            "use_mixed_precision": False,
            "share_cnn_encoders": False,
            "rnd_cfg": None,
            "symmetry_cfg": None,
        },
    }
    runner = OnPolicyRunner(env, cfg, log_dir=None, device="cpu")
    eval_env = make_env("gridworld", num_envs=64, device="cpu", seed=2)

    def mean_length():
        policy = runner.get_inference_policy()
        return run_episodes(lambda o: policy(o, stochastic_output=True), eval_env)["length"].mean().item()

    before = mean_length()
    runner.alg.train_mode()
    runner.learn(12)
    after = mean_length()
    assert after < 0.5 * before, f"mean episode length {before:.1f} -> {after:.1f}: the policy did not learn"
    policy = runner.alg.get_policy()  # rsl_rl logs output_std as the action std: the spread of the last batch drawn
    actions = policy(eval_env.get_observations(), stochastic_output=True)
    torch.testing.assert_close(policy.output_std, actions.std(dim=0))
    assert policy.output_std.shape == (2,) and (policy.output_std > 0).all()


def test_train_writes_checkpoints_config_progress_and_eval(tmp_run_dir):
    results = train(QUICK + [f"run_dir={tmp_run_dir}"])
    assert sorted(p.name for p in tmp_run_dir.glob("model_*.pt")) == ["model_0.pt", "model_1.pt", "model_2.pt"]
    assert not list(tmp_run_dir.glob("*.tmp")), "atomic writes leave no temp files"
    assert torch.load(tmp_run_dir / "model_2.pt", weights_only=False)["iter"] == 2
    assert (tmp_run_dir / "config.yaml").exists() and list(tmp_run_dir.glob("events.out.tfevents*"))
    rows = [json.loads(line) for line in (tmp_run_dir / "progress.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [0, 1, 2]
    assert {"Flow/ratio_max", "Flow/explosion_rate", "Flow/straightness_error", "Flow/clip_fraction"} <= set(rows[0])
    saved = json.loads((tmp_run_dir / "eval.json").read_text())
    assert saved == json.loads(json.dumps(results))
    assert set(saved["results"]) == {"N=1", "N=2"}
    for summary in saved["results"].values():  # GridWorld pays 20 for a goal and nothing else
        assert summary["return_mean"] == pytest.approx(20.0 * summary["success_rate"]) and summary["episodes"] == 16
    assert {"straightness_error", "explosion_rate"} <= set(saved["diagnostics"])
    assert all((tmp_run_dir / f).exists() for f in ("gridworld_field_N1.png", "gridworld_trajectories_N10.png"))


def test_gaussian_ppo_run_is_evaluated_with_its_figures(tmp_run_dir):
    ppo = [a for a in QUICK if not a.startswith(("algo=", "algorithm.num_mc"))] + ["algo=ppo"]
    results = train(ppo + [f"run_dir={tmp_run_dir}"])
    summary = results["results"]["mean_action"]
    assert summary["return_mean"] == pytest.approx(20.0 * summary["success_rate"]) and summary["episodes"] == 16
    assert all((tmp_run_dir / f).exists() for f in ("gridworld_field.png", "gridworld_trajectories.png"))


def test_resume_continues_from_last_checkpoint(tmp_run_dir):
    train(QUICK + [f"run_dir={tmp_run_dir}", "eval.at_end=false"])
    with pytest.raises(ConfigError, match="resume=true"):
        train(QUICK + [f"run_dir={tmp_run_dir}"])
    train([f"run_dir={tmp_run_dir}", "resume=true", "max_iterations=5", "eval.at_end=false"])
    rows = [json.loads(line) for line in (tmp_run_dir / "progress.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [0, 1, 2, 3, 4]
    assert latest_checkpoint(tmp_run_dir).name == "model_4.pt"


def test_nan_loss_stops_training_and_keeps_last_good_checkpoint(tmp_run_dir, monkeypatch):
    from refpo_warp.algorithms import ReFPO

    original = ReFPO.update
    calls = {"n": 0}

    def update_with_nan_on_third_call(self):
        out = original(self)
        calls["n"] += 1
        if calls["n"] == 3:
            out["surrogate"] = float("nan")
        return out

    monkeypatch.setattr(ReFPO, "update", update_with_nan_on_third_call)
    with pytest.raises(NonFiniteLossError, match="iteration 2"):
        train(
            [a for a in QUICK if not a.startswith("max_iterations=")] + [f"run_dir={tmp_run_dir}", "max_iterations=6"]
        )
    assert latest_checkpoint(tmp_run_dir).name == "model_1.pt"
    good = torch.load(tmp_run_dir / "model_1.pt", weights_only=False)
    assert all(torch.isfinite(v).all() for v in good["actor_state_dict"].values())


def test_dmc_learner_stores_the_pre_tanh_action_the_env_squashes():
    """With the DMC default action transform, rollout storage keeps the sampled (unbounded) flow action and the
    physics receives tanh of it."""
    from refpo_warp.config.resolve import resolve
    from refpo_warp.runner.build import build_runner
    from refpo_warp.utils.warp_setup import wp

    run = resolve(
        ["task=dmc_cartpole_balance", "algo=refpo", "device=cpu", "num_envs=64", "runner.num_steps_per_env=4"]
    )
    env, runner = build_runner(run, None)
    alg = runner.alg
    obs = env.get_observations()
    with torch.inference_mode():
        actions = alg.act(obs)
        env.step(actions)
        stored = alg.transition.actions.clone()
        alg.process_env_step(obs, torch.zeros(64), torch.zeros(64, dtype=torch.bool), {})
    torch.testing.assert_close(alg.storage.actions[0], stored)
    assert stored.abs().max() > 1.0  # an untrained flow samples beyond the env's range; nothing clipped it
    torch.testing.assert_close(wp.to_torch(env.sim.views.ctrl), torch.tanh(stored))


def test_torch_threads_sets_the_runs_cpu_threads_and_null_keeps_the_rule():
    from refpo_warp.config.resolve import resolve
    from refpo_warp.runner.build import build_runner

    before = torch.get_num_threads()
    try:
        base = ["task=gridworld", "algo=ppo", "device=cpu", "num_envs=4", "runner.num_steps_per_env=4"]
        torch.set_num_threads(1)
        build_runner(resolve([*base, "torch_threads=2"]), None)
        assert torch.get_num_threads() == 2
        build_runner(resolve(base), None)  # null: the count the command set stays
        assert torch.get_num_threads() == 2
    finally:
        torch.set_num_threads(before)
