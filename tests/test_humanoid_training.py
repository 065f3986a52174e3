"""Humanoid configs (paper Appendix B.3 on CUDA, a small CPU run) and the train -> evaluate path writing eval.json."""

import json

import pytest

from refpo_warp.config import resolve_config
from refpo_warp.training import train


@pytest.mark.parametrize("algo, reflow", [("refpo", 0.1), ("fpo", 0.0)])
def test_cuda_profile_carries_the_paper_hyperparameters(algo, reflow):
    cfg = resolve_config(["task=humanoid_root_hands", f"algo={algo}"], device_type="cuda")
    alg = cfg["algorithm"]
    assert cfg["num_envs"] * cfg["runner"]["num_steps_per_env"] == 131072  # batch size
    assert cfg["num_envs"] * cfg["runner"]["num_steps_per_env"] // alg["num_mini_batches"] == 32768  # minibatch
    assert (alg["num_learning_epochs"], alg["learning_rate"], alg["gamma"], alg["lam"]) == (4, 1e-4, 0.98, 0.2)
    assert (alg["clip_param"], alg["value_loss_coef"], alg["max_grad_norm"]) == (0.01, 1.2, 10.0)
    assert alg["reflow_coef"] == reflow and cfg["actor"]["num_flow_steps"] == 10
    assert cfg["actor"]["action_noise_std"] == 0.05
    assert cfg["total_env_steps"] == 100_000_000
    assert cfg["runner"]["obs_groups"] == {"actor": ["policy"], "critic": ["critic"]}


def test_cpu_profile_is_small_and_evaluates_every_clip_deterministically():
    cfg = resolve_config(["task=humanoid_root"], device_type="cpu")
    assert cfg["num_envs"] <= 32 and cfg["total_env_steps"] <= 50_000
    assert cfg["eval"]["num_envs"] is None and cfg["eval"]["env"] == {"eval_mode": True}
    assert cfg["eval"]["stochastic"] is False and cfg["eval"]["flow_steps"] == [10, 1]


@pytest.mark.slow
def test_train_and_evaluate_humanoid_root(tmp_run_dir):
    results = train(["task=humanoid_root", "device=cpu", "num_envs=4", "runner.num_steps_per_env=8",
                     "max_iterations=2", f"run_dir={tmp_run_dir}"])  # fmt: skip
    saved = json.loads((tmp_run_dir / "eval.json").read_text())
    assert saved["eval_envs"] == 12 and saved["stochastic"] is False  # one env per shipped clip
    for n in ("N=10", "N=1"):
        summary = saved["results"][n]
        assert summary["episodes"] == 12 and summary["unfinished"] == 0
        assert 0.0 <= summary["success_rate_pct"] <= 100.0
        assert 1.0 <= summary["alive_duration"] <= 151.0
        assert summary["mpjpe_mm"] > 0.0
    assert results["results"]["N=1"]["mpjpe_mm"] == saved["results"]["N=1"]["mpjpe_mm"]
