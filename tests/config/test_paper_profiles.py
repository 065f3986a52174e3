"""Configs of Flow-GRPO, ReinFlow and the advantage-weighted ReFPO: every task resolves for each, and the DMC CUDA
profiles hold the paper's tables (c) and (d) with Brax batch semantics."""

import pytest
from constructor_config import effective_config  # tests/ is on sys.path under pytest

from refpo_warp.config.resolve import resolve_config
from refpo_warp.envs.registry import list_tasks

ALGOS = ("flow_grpo", "reinflow", "refpo_aw")


@pytest.mark.parametrize("algo", ALGOS)
@pytest.mark.parametrize("device", ["cpu", "cuda"])
def test_every_task_resolves(algo, device):
    for task in list_tasks():
        cfg = resolve_config([f"task={task}", f"algo={algo}"], device_type=device)
        if algo == "flow_grpo":
            assert cfg["num_envs"] % cfg["env"]["reset_group_size"] == 0, task
            assert cfg["eval"]["env"]["reset_group_size"] == 1 and not cfg["runner"]["init_at_random_ep_len"], task
        if algo == "reinflow":
            assert cfg["eval"]["flow_steps"] == [4, 1], task


def test_dmc_cuda_profiles_follow_tables_c_and_d():
    grpo = effective_config(resolve_config(["task=dmc_cheetah_run", "algo=flow_grpo"], device_type="cuda"))
    alg = grpo["algorithm"]
    # 2048 envs x 480 steps = 983,040 transitions in 32 minibatches of 30,720, 8 passes, 200M env steps
    assert (grpo["num_envs"], grpo["runner"]["num_steps_per_env"], grpo["total_env_steps"]) == (2048, 480, 200_000_000)
    assert (alg["num_mini_batches"], alg["num_learning_epochs"], alg["clip_param"]) == (32, 8, 0.1)
    assert (alg["kl_coef"], alg["noise_level"], alg["feather_std"], alg["adv_clip"]) == (5e-3, 1.0, 0.05, 8.0)
    assert (alg["learning_rate"], alg["gamma"], alg["reward_scale"], alg["max_grad_norm"]) == (1e-4, 0.995, 10, 1)
    assert grpo["env"]["reset_group_size"] == 8
    assert grpo["actor"]["num_flow_steps"] == 10 and grpo["actor"]["output_scale"] == 0.5
    assert grpo["actor"]["hidden_dims"] == [32, 32, 32, 32]
    rf = effective_config(resolve_config(["task=dmc_cheetah_run", "algo=reinflow"], device_type="cuda"))
    alg, actor = rf["algorithm"], rf["actor"]
    # 2048 envs x 120 chunks of 4 = 983,040 env steps per iteration; 204 iterations ~ 200M env steps
    assert (rf["num_envs"], rf["runner"]["num_steps_per_env"], rf["env"]["action_chunk"]) == (2048, 120, 4)
    assert rf["max_iterations"] * 2048 * 120 * 4 >= 200_000_000 > (rf["max_iterations"] - 1) * 2048 * 120 * 4
    assert (alg["num_mini_batches"], alg["num_learning_epochs"], alg["clip_param"]) == (32, 8, 0.1)
    assert (alg["gamma"], alg["lam"], alg["reward_scale"], alg["learning_rate"]) == (0.99, 0.95, 3.0, 3e-5)
    assert (alg["value_loss_coef"], alg["entropy_coef"]) == (0.3, 0.05)  # ReinFlow's 0.5 MSE x 0.6
    assert (actor["num_flow_steps"], actor["ft_denoising_steps"], actor["time_embed_dim"]) == (4, 2, 16)
    assert (actor["sigma_min"], actor["sigma_max"], actor["min_sampling_std"]) == (0.08, 0.16, 0.1)
    aw = effective_config(resolve_config(["task=dmc_cheetah_run", "algo=refpo_aw"], device_type="cuda"))
    refpo = effective_config(resolve_config(["task=dmc_cheetah_run", "algo=refpo"], device_type="cuda"))
    differs = {k for k in aw["algorithm"] if aw["algorithm"][k] != refpo["algorithm"].get(k)}
    assert differs == {"class_name", "reflow_weighting"} and aw["actor"] == refpo["actor"]
