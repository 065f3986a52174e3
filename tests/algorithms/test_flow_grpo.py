"""Flow-GRPO: the SDE step against hand-worked values and an exact Gaussian flow, group advantages on hand-made
batches, the ratio at the first minibatch, the KL term, and construction without a critic."""

import copy
import math

import pytest
import torch
from rollouts import random_rollout  # tests/algorithms/rollouts.py
from rsl_rl.runners import OnPolicyRunner
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from refpo_warp import make_env
from refpo_warp.algorithms import FlowGRPO
from refpo_warp.algorithms.flow_grpo import discounted_reward_to_go, group_advantages
from refpo_warp.algorithms.flow_sde import gaussian_log_prob, sample_sde_chain, sde_grid, sde_mean, sde_means
from refpo_warp.models import FlowActor, NoCritic

N, T, OBS, ACT = 8, 3, 4, 2
LOG_SQRT_2PI = 0.9189385332


def test_sde_grid_hand_worked():
    # N = 2, a = 1: h = 0.5; s_0 = sqrt(1 / h) = sqrt(2) (the sigma = 1 rule), s_1 = sqrt(0.5 / 0.5) = 1;
    # transition stds s sqrt(h) = 1 and sqrt(0.5)
    grid = sde_grid(2, 1.0)
    torch.testing.assert_close(grid.tau, torch.tensor([0.0, 0.5]))
    torch.testing.assert_close(grid.scale, torch.tensor([math.sqrt(2.0), 1.0]))
    torch.testing.assert_close(grid.std, torch.tensor([1.0, math.sqrt(0.5)]))
    # N = 10, a = 1 (table (c)): first step std 1.0, last sqrt(0.1 / 0.9) sqrt(0.1) = 0.10541
    grid = sde_grid(10, 1.0)
    assert grid.std[0].item() == pytest.approx(1.0) and grid.std[-1].item() == pytest.approx(0.105409, abs=1e-6)
    assert sde_grid(10, 0.5).std[3].item() == pytest.approx(0.5 * grid.std[3].item())


def test_sde_step_mean_std_and_log_prob_on_a_1d_example():
    """N = 2, a = 1, x = 0.4, v = 1.2, next state 1.5 (hand-worked):
    step 0 (tau 0, s^2 = 2):     mu = x + 0.5 v - 0.5 * 2 / 2 * x = 0.5 x + 0.5 v = 0.8, std 1,
                                 log p = -(0.7)^2 / 2 - log 1 - log sqrt(2 pi) = -1.163939
    step 1 (tau 0.5, s^2 = 1):   mu = x + 0.5 v - 0.5 * 1 / 1 * (x - 0.5 v) = 0.5 x + 0.75 v = 1.1, std sqrt(0.5),
                                 log p = -(0.4)^2 / 1 - log sqrt(0.5) - log sqrt(2 pi) = -0.732369"""
    grid = sde_grid(2, 1.0)
    x, v, nxt = torch.tensor([[0.4]]), torch.tensor([[1.2]]), torch.tensor([[1.5]])
    expected = [(0.8, 1.0, -0.245 - LOG_SQRT_2PI), (1.1, math.sqrt(0.5), -0.16 + 0.5 * math.log(2.0) - LOG_SQRT_2PI)]
    for k, (mean, std, log_p) in enumerate(expected):
        mu = sde_mean(x, v, grid.tau[k : k + 1], grid.scale[k : k + 1], 0.5)
        assert mu.item() == pytest.approx(mean, abs=1e-6)
        assert grid.std[k].item() == pytest.approx(std, abs=1e-6)
        assert gaussian_log_prob(nxt, mu, grid.std[k : k + 1]).item() == pytest.approx(log_p, abs=1e-6)
    # the log-probability is averaged (not summed) over action dims: (-1.163939 + log N(0.8; 0.8, 1)) / 2
    two_d = gaussian_log_prob(torch.tensor([[1.5, 0.8]]), torch.tensor([[0.8, 0.8]]), torch.tensor([1.0]))
    assert two_d.item() == pytest.approx((-0.245 - 2 * LOG_SQRT_2PI) / 2, abs=1e-6)


def test_sde_keeps_the_marginals_of_an_exact_gaussian_flow():
    """For actions a ~ N(m, s^2) the exact velocity of x_tau = (1 - tau) eps + tau a is known in closed form; the
    SDE with that velocity must end (as the ODE does) at mean m and std s, whatever the noise level."""
    m, s = 0.7, 0.3

    def velocity(obs_feat, x, tau):
        tau = tau.unsqueeze(-1)
        variance = (1 - tau) ** 2 + tau**2 * s**2
        return m + (tau * s**2 - (1 - tau)) / variance * (x - tau * m)

    torch.manual_seed(0)
    grid = sde_grid(50, 1.0)
    action, chain, _, _ = sample_sde_chain(velocity, torch.zeros(200_000, 1), 1, grid)
    assert chain.shape == (200_000, 51, 1) and torch.equal(action, chain[:, -1])
    assert action.mean().item() == pytest.approx(m, abs=0.005)
    assert action.std().item() == pytest.approx(s, abs=0.01)
    assert chain[:, 1].std().item() > 0.5  # the path is noisy: after step 0 (std 1) far from the ODE's


def make_actor(**kwargs):
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(N, OBS)}, batch_size=[N])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    actor = FlowActor(
        obs, groups, "actor", ACT, hidden_dims=[16, 16], num_flow_steps=4, obs_normalization=True, **kwargs
    )
    return actor, obs, groups


def make_flow_grpo(**kwargs):
    actor, obs, groups = make_actor()
    alg = FlowGRPO(
        actor,
        NoCritic(obs, groups, "critic", 1),
        RolloutStorage("rl", N, T, obs, [ACT]),
        **{"num_learning_epochs": 1, "num_mini_batches": 1, **kwargs},
    )
    alg.set_group_size(4)
    return alg


def fill_storage(alg, seed=1):
    random_rollout(alg, T, N, OBS, seed)


def test_rollout_stores_the_chain_its_means_and_log_probs():
    alg = make_flow_grpo(feather_std=0.05)
    fill_storage(alg)
    chain, means, old = alg.store.flat("chain"), alg.store.flat("old_mean"), alg.store.flat("old_log_prob")
    assert chain.shape == (N * T, 5, ACT) and means.shape == (N * T, 4, ACT) and old.shape == (N * T, 4)
    torch.testing.assert_close(chain[:, -1], alg.storage.actions.flatten(0, 1))  # the feathered action is x_N
    obs = alg.storage.observations.flatten(0, 1)
    with torch.no_grad():
        teacher = alg.step_means(alg.actor, obs, chain)
    torch.testing.assert_close(teacher, means, atol=1e-5, rtol=1e-5)
    torch.testing.assert_close(gaussian_log_prob(chain[:, 1:], means, alg.grid.std.expand(N * T, -1)), old)


def test_ratio_is_one_at_the_first_minibatch_and_kl_to_the_rollout_policy_is_zero():
    alg = make_flow_grpo()
    fill_storage(alg)
    stats = alg.update()
    assert stats["Flow/ratio_mean"] == pytest.approx(1.0, abs=1e-6)
    assert stats["Flow/ratio_max"] == pytest.approx(1.0, abs=1e-6)
    assert stats["kl"] == pytest.approx(0.0, abs=1e-10) and stats["Flow/clip_fraction"] == 0.0
    assert "value" not in stats and sum(p.numel() for p in alg.critic.parameters()) == 0


def test_kl_term_to_a_frozen_initial_policy_hand_computed():
    alg = make_flow_grpo(kl_reference="initial", timestep_fraction=0.5)
    assert alg.num_trained_steps == 2
    fill_storage(alg)
    with torch.no_grad():
        for p in alg.actor.velocity.head.parameters():
            p.add_(0.3)  # the policy moves away from the frozen initial copy
    batch = next(alg.minibatches())
    _, stats = alg.policy_loss(batch)
    chain = batch.field("chain")
    with torch.no_grad():
        new = alg.step_means(alg.actor, batch.observations, chain)[:, :2]
        ref = alg.step_means(alg.reference_actor, batch.observations, chain)[:, :2]
    expected = ((new - ref).square().mean(dim=-1) / (2 * alg.grid.scale[:2].square())).mean()
    assert stats["kl"].item() == pytest.approx(expected.item(), rel=1e-5) and expected.item() > 1e-4


def test_discounted_reward_to_go_hand_worked():
    # gamma 0.5, rewards 1, 2, 4, the episode ends after step 1: G = (1 + 0.5 * 2, 2, 4)
    rewards = torch.tensor([[1.0], [2.0], [4.0]])
    dones = torch.tensor([[False], [True], [False]])
    torch.testing.assert_close(discounted_reward_to_go(rewards, dones, 0.5), torch.tensor([[2.0], [2.0], [4.0]]))


def test_group_advantages_hand_worked():
    returns = torch.tensor([[1.0, 3.0, 2.0, 6.0]])  # groups {1, 3} and {2, 6}: centred -1, 1, -2, 2
    # global std: population std of (1, 3, 2, 6) = sqrt(3.5) = 1.870829
    torch.testing.assert_close(
        group_advantages(returns, 2, "global", None), torch.tensor([[-1.0, 1.0, -2.0, 2.0]]) / (math.sqrt(3.5) + 1e-4)
    )
    # per-group std: 1 and 2
    torch.testing.assert_close(
        group_advantages(returns, 2, "group", None), torch.tensor([[-1 / 1.0001, 1 / 1.0001, -2 / 2.0001, 2 / 2.0001]])
    )
    torch.testing.assert_close(group_advantages(returns, 2, "group", 0.5), torch.tensor([[-0.5, 0.5, -0.5, 0.5]]))
    # time steps are normalised separately; a group of equal returns gets 0
    two_steps = torch.tensor([[1.0, 3.0, 2.0, 6.0], [5.0, 5.0, 0.0, 10.0]])
    out = group_advantages(two_steps, 2, "global", 8.0)
    assert out[1, 0] == 0 and out[1, 1] == 0 and out[1, 3].item() == pytest.approx(5 / (math.sqrt(12.5) + 1e-4))
    with pytest.raises(ValueError, match="groups of 3"):
        group_advantages(returns, 3)


def test_compute_returns_gives_group_relative_advantages():
    alg = make_flow_grpo(adv_clip=None)
    fill_storage(alg)
    st = alg.storage
    expected = group_advantages(
        discounted_reward_to_go(st.rewards.squeeze(-1) * 1.0, st.dones.squeeze(-1), alg.gamma), 4, "global", None
    )
    torch.testing.assert_close(st.advantages.squeeze(-1), expected)
    assert st.advantages.reshape(T, 2, 4).sum(dim=-1).abs().max() < 1e-5  # zero mean within each group


def test_runner_builds_it_without_a_critic_and_takes_the_group_size_from_the_env():
    env = make_env("gridworld", num_envs=16, device="cpu", seed=1, reset_group_size=8)
    cfg = {
        "num_steps_per_env": 8,
        "save_interval": 100,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {"class_name": "refpo_warp.models:FlowActor", "hidden_dims": [16], "num_flow_steps": 4},
        "critic": {"class_name": "MLPModel", "hidden_dims": [64, 64]},  # ignored: Flow-GRPO has no critic
        "algorithm": {"class_name": "refpo_warp.algorithms:FlowGRPO", "num_learning_epochs": 1, "num_mini_batches": 2},
    }
    runner = OnPolicyRunner(env, copy.deepcopy(cfg), log_dir=None, device="cpu")
    assert isinstance(runner.alg.critic, NoCritic) and runner.alg.group_size == 8
    before = [p.detach().clone() for p in runner.alg.actor.parameters()]
    runner.learn(1)
    after = list(runner.alg.actor.parameters())
    assert any(not torch.equal(a, b) for a, b in zip(before, after)), "the update changed no actor parameter"
    assert all(torch.isfinite(p).all() for p in after)
    with pytest.raises(ValueError, match="reset_group_size"):
        OnPolicyRunner(make_env("gridworld", num_envs=16, device="cpu", seed=1), copy.deepcopy(cfg), device="cpu")
    cfg["algorithm"]["group_size"] = 4
    with pytest.raises(ValueError, match="group_size=4"):
        OnPolicyRunner(env, cfg, device="cpu")


def test_teacher_forced_means_use_one_forward_pass_for_all_steps():
    actor, obs, _ = make_actor()
    grid = sde_grid(4, 0.7)
    with torch.no_grad():
        feat = actor.velocity.project_obs(actor.encode(obs))
        _, chain, means, _ = sample_sde_chain(actor.velocity, feat, ACT, grid)
        torch.testing.assert_close(sde_means(actor.velocity, feat, chain, grid), means, atol=1e-6, rtol=1e-5)
