"""Humanoid configs (the reference Puffer-PHC set-up on CUDA, a small CPU run), the flow actor's first actions, and
the train -> evaluate path writing eval.json."""

import json
from pathlib import Path

import pytest
import torch
from constructor_config import effective_config  # tests/ is on sys.path under pytest

from refpo_warp.config.resolve import resolve, resolve_config
from refpo_warp.envs.registry import make_env
from refpo_warp.runner.build import build_runner, rsl_rl_config
from refpo_warp.training import train


@pytest.mark.parametrize("algo, reflow", [("refpo", 0.1), ("fpo", 0.0)])
def test_cuda_profile_carries_the_reference_hyperparameters(algo, reflow):
    cfg = effective_config(resolve_config(["task=humanoid_root_hands", f"algo={algo}"], device_type="cuda"))
    alg, actor = cfg["algorithm"], cfg["actor"]
    assert cfg["num_envs"] * cfg["runner"]["num_steps_per_env"] == 131072  # batch size
    assert cfg["num_envs"] * cfg["runner"]["num_steps_per_env"] // alg["num_mini_batches"] == 32768  # minibatch
    assert (alg["num_learning_epochs"], alg["learning_rate"], alg["gamma"], alg["lam"]) == (4, 1e-4, 0.98, 0.2)
    assert (alg["clip_param"], alg["value_loss_coef"], alg["value_clip_param"]) == (0.01, 1.2, 0.2)
    assert (alg["max_grad_norm"], alg["joint_grad_clip"], alg["bound_coef"], alg["bound"]) == (10.0, True, 10.0, 0.9)
    assert (alg["lr_decay_rate"], alg["lr_decay_floor"]) == (1.5e-4, 0.2)
    assert (alg["tau_sampling"], alg["tau_logit_mean"], alg["tau_logit_std"]) == ("logit_normal", -1.2, 1.2)
    assert alg["reflow_coef"] == reflow and alg["num_mc_samples"] == 1
    assert (actor["parameterization"], actor["output_mode"], actor["loss_scale"]) == ("data", "data", 200.0)
    assert (actor["time_conditioning"], actor["head_init_gain"], actor["obs_clip"]) == ("adaln", 0.01, 10.0)
    assert actor["num_flow_steps"] == 10 and actor["action_noise_std"] == 0.05
    assert cfg["total_env_steps"] == 100_000_000
    assert cfg["runner"]["obs_groups"] == {"actor": ["policy"], "critic": ["critic"]}
    assert (
        resolve_config(["task=humanoid_all", f"algo={algo}"], device_type="cuda")["algorithm"]["max_grad_norm"] == 1.0
    )


def test_gaussian_baseline_is_the_references():
    cfg = resolve_config(["task=humanoid_root", "algo=ppo"], device_type="cuda")
    dist = cfg["actor"]["distribution_cfg"]
    assert dist["init_std"] == pytest.approx(torch.exp(torch.tensor(-2.9)).item()) and dist["learn_std"] is False
    assert cfg["algorithm"]["clip_param"] == 0.01 and cfg["algorithm"]["bound_coef"] == 10.0
    assert cfg["runner"]["obs_groups"] == {"actor": ["policy"], "critic": ["policy"]}


@pytest.mark.parametrize("algo", ["refpo", "ppo"])
def test_first_actions_are_small_like_the_references(algo):
    """Built from the paper-sized configs and fed real observations, the untrained policy's rollout actions have a
    spread of about the 0.05 perturbation (flow) or fixed std (Gaussian), and none reaches the +-1 action bound."""
    torch.manual_seed(0)
    run = resolve(["task=humanoid_root", f"algo={algo}", "device=cpu"], device_type="cuda")
    cfg = run.cfg
    cfg["num_envs"] = 32
    env = make_env("humanoid_root", num_envs=32, device="cpu", seed=3)
    _, runner = build_runner(run, None, env=env)
    obs = env.get_observations()
    runner.alg.actor.update_normalization(obs)
    with torch.inference_mode():
        actions = torch.cat([runner.alg.actor(obs, stochastic_output=True) for _ in range(8)])
    assert actions.std().item() <= 0.06, actions.std().item()
    assert actions.abs().max().item() < 1.0
    assert rsl_rl_config(cfg)["actor"]["class_name"].endswith("FlowActor" if algo == "refpo" else "PhcMLPModel")


def test_cpu_profile_is_small_and_evaluates_every_clip_with_the_reference_protocol():
    cfg = resolve_config(["task=humanoid_root"], device_type="cpu")
    assert cfg["num_envs"] <= 32 and cfg["total_env_steps"] <= 50_000
    assert cfg["eval"]["num_envs"] is None and cfg["eval"]["env"] == {"eval_mode": True}
    assert cfg["eval"]["initial_noise"] == ["random"] and cfg["eval"]["perturbation"] is False
    assert cfg["eval"]["flow_steps"] == [10, 1]
    assert "toy scale" in cfg["notice"] and "device=cuda:0" in cfg["notice"]


@pytest.mark.slow
def test_train_and_evaluate_humanoid_root(tmp_run_dir, capsys):
    results = train(
        [
            "task=humanoid_root",
            "device=cpu",
            "num_envs=4",
            "runner.num_steps_per_env=8",
            "max_iterations=2",
            f"run_dir={tmp_run_dir}",
        ]
    )
    saved = json.loads((tmp_run_dir / "eval.json").read_text())
    assert saved["eval_envs"] == 12 and saved["protocol"] == {"initial_noise": ["random"], "perturbation": False}
    for n in ("N=10", "N=1"):
        summary = saved["results"][n]
        assert summary["episodes"] == 12 and summary["unfinished"] == 0
        # one name per metric, the paper's: no success_mean, mpjpe_mm_mean, alive_steps_mean or length_mean
        assert set(summary) == {
            "episodes",
            "unfinished",
            "return_mean",
            "return_std",
            "success_rate_pct",
            "alive_duration",
            "mpjpe_mm",
        }
        assert 0.0 <= summary["success_rate_pct"] <= 100.0
        assert 1.0 <= summary["alive_duration"] <= 151.0
        assert summary["mpjpe_mm"] > 0.0
    assert results["results"]["N=1"]["mpjpe_mm"] == saved["results"]["N=1"]["mpjpe_mm"]
    # the run dir holds its figures: curves (return, episode length, success: the env logs Episode/success) and the
    # flow diagnostics
    assert [Path(f).name for f in saved["figures"]] == ["curves.png", "curves_diagnostics.png"]
    assert all(Path(f).parent == tmp_run_dir and Path(f).is_file() for f in saved["figures"])
    rows = [json.loads(line) for line in (tmp_run_dir / "progress.jsonl").read_text().splitlines()]
    assert any("Episode/success" in r for r in rows)
    out = capsys.readouterr().out
    assert out.count("toy scale") == 2  # the notice at the start and at the end
