"""ReinFlow: the chain log-probability and entropy of a 2-step chain against hand-worked values, the noise bounds and
schedule, the sampler's clamps and truncation, the ratio at the first minibatch, and the noise-bound decay."""

import math

import pytest
import torch
from rollouts import random_rollout  # tests/algorithms/rollouts.py
from rsl_rl.models import MLPModel
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from refpo_warp.algorithms import ReinFlow
from refpo_warp.algorithms.reinflow import decayed_sigma_max
from refpo_warp.models import ReinFlowActor
from refpo_warp.models.reinflow_actor import fixed_sigma

N, T, OBS, ACT = 8, 3, 3, 2


def make_actor(obs_dim=OBS, act_dim=ACT, **kwargs):
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(N, obs_dim)}, batch_size=[N])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    return ReinFlowActor(obs, groups, "actor", act_dim, hidden_dims=[16, 16], **kwargs), obs, groups


def constant_velocity(actor, value: float) -> None:
    """Make v(x, t; o) = value everywhere (zero head weights, constant bias) and the noise network output 0."""
    with torch.no_grad():
        actor.velocity.head.weight.zero_()
        actor.velocity.head.bias.fill_(value)
        for p in actor.noise_net[-1].parameters():
            p.zero_()


def test_chain_log_prob_and_entropy_of_a_two_step_chain_hand_worked():
    """K = 2, D = 1, v = 0.6 (v / K = 0.3), learned noise on the last step only; chain x = (0.5, 0.9, 1.0).
    step 0 (fixed, lin): sigma = clamp(0.1 * 0, 0.08, 0.16) = 0.08 -> std max(0.08, 0.10) = 0.10; mu_0 = 0.8
    step 1 (learned, network output 0): log sigma^2 halfway -> sigma = sqrt(0.08 * 0.16) = 0.113137 = std;
            mu_1 = clamp(0.9 + 0.3, -1, 1) = 1.0
    log N(0.5; 0, 1)        = -0.125 - 0.918939             = -1.043939
    log N(0.9; 0.8, 0.1)    = -0.5 + 2.302585 - 0.918939    =  0.883646
    log N(1.0; 1.0, 0.1131) = 0 + 2.179155 - 0.918939       =  1.260216
    log pi = (sum) / ((K + 1) D) = 1.099923 / 3              =  0.366641
    entropy = (1.418939 + (1.418939 - 2.302585) + (1.418939 - 2.179155)) / 3 = -0.074974"""
    actor, _, _ = make_actor(obs_dim=1, act_dim=1, num_flow_steps=2, ft_denoising_steps=1, obs_normalization=False)
    constant_velocity(actor, 0.6)
    obs = TensorDict({"policy": torch.tensor([[0.3]])}, batch_size=[1])
    chain = torch.tensor([[[0.5], [0.9], [1.0]]])
    log_prob, entropy, std = actor.chain_log_prob(obs, chain, with_entropy=True)
    assert log_prob.item() == pytest.approx(0.366641, abs=2e-6)
    assert entropy.item() == pytest.approx(-0.074974, abs=2e-6)
    assert std.item() == pytest.approx((0.1 + math.sqrt(0.08 * 0.16)) / 2, abs=1e-6)
    assert actor.chain_log_prob(obs, chain).item() == pytest.approx(0.366641, abs=2e-6)


def test_noise_schedule_and_bounds():
    # table (d) K = 4, two learned steps: the fixed steps t = 0 and 0.25 get clamp(0.1 t) = 0.08, sampled at 0.10
    assert fixed_sigma(0.0, "lin", 0.08, 0.16) == 0.08 and fixed_sigma(0.25, "lin", 0.08, 0.16) == 0.08
    assert fixed_sigma(0.5, "vp", 0.08, 0.16) == pytest.approx(min(math.sqrt(0.05), 0.16))
    actor, obs, _ = make_actor()
    norm = actor.encode(obs)
    assert torch.equal(actor.step_std(norm, 0, 4), torch.full((N, ACT), 0.1))
    with torch.no_grad():
        actor.noise_net[-1].bias.fill_(50.0)
        assert torch.allclose(actor.step_std(norm, 3, 4), torch.tensor(0.16))
        actor.noise_net[-1].bias.fill_(-50.0)
        assert torch.allclose(actor.step_std(norm, 3, 4), torch.tensor(0.10))  # sigma_min 0.08, floored at 0.10
        actor.sigma_max.fill_(0.12)
        actor.noise_net[-1].bias.fill_(50.0)
        assert torch.allclose(actor.step_std(norm, 2, 4), torch.tensor(0.12))


def test_sampled_chain_clamps_truncates_and_matches_its_log_prob():
    actor, obs, _ = make_actor(output_scale=5.0)
    torch.manual_seed(3)
    with torch.no_grad():
        chain, log_prob = actor.sample_chain(obs)
        torch.testing.assert_close(actor.chain_log_prob(obs, chain), log_prob)
        norm = actor.encode(obs)
        feat = actor.velocity.project_obs(norm)
        for k in range(4):
            mean = actor.step_mean(feat, chain[:, k], k, 4)
            assert mean.abs().max() <= 1.0
            step = (chain[:, k + 1] - mean).abs()
            if k < 3:  # the last state is clamped to [-1, 1] after the noise
                assert (step <= 3.0 * actor.step_std(norm, k, 4) + 1e-6).all()
    assert chain.shape == (N, 5, ACT) and chain[:, -1].abs().max() <= 1.0


def test_deterministic_sampling_runs_the_noiseless_chain():
    actor, obs, _ = make_actor()
    x0 = torch.randn(N, ACT)
    with torch.no_grad():
        one = actor.sample(obs, 1, noise=x0)
        feat = actor.velocity.project_obs(actor.encode(obs))
        expected = (x0 + actor.velocity(feat, x0, torch.zeros(N))).clamp(-1, 1)
        torch.testing.assert_close(one, expected)
        torch.testing.assert_close(actor.sample(obs, 4, noise=x0), actor.sample(obs, 4, noise=x0))
        assert not torch.equal(actor.sample(obs, 4, noise=x0, perturbation=True), actor.sample(obs, 4, noise=x0))


def make_reinflow(**kwargs):
    actor, obs, groups = make_actor()
    critic = MLPModel(obs, groups, "critic", 1, hidden_dims=[16])
    return ReinFlow(
        actor,
        critic,
        RolloutStorage("rl", N, T, obs, [ACT]),
        **{"num_learning_epochs": 1, "num_mini_batches": 1, **kwargs},
    )


def fill_storage(alg, seed=1):
    random_rollout(alg, T, N, OBS, seed)


def test_ratio_is_one_at_the_first_minibatch():
    alg = make_reinflow(logprob_clip=None)
    fill_storage(alg)
    assert alg.store.flat("chain").shape == (N * T, 5, ACT)
    torch.testing.assert_close(alg.store.flat("chain")[:, -1], alg.storage.actions.flatten(0, 1))
    stats = alg.update()
    assert stats["Flow/ratio_mean"] == pytest.approx(1.0, abs=1e-6)
    assert stats["Flow/ratio_max"] == pytest.approx(1.0, abs=1e-6)
    assert stats["Flow/clip_fraction"] == 0.0 and "value" in stats and "entropy" in stats


def test_entropy_bonus_trains_the_noise_network_of_the_learned_steps():
    """Zero advantages and value weight: the only gradient is -entropy_coef * dH, which reaches the noise network."""
    alg = make_reinflow(entropy_coef=1.0, value_loss_coef=0.0, optimizer="sgd", learning_rate=0.1)
    fill_storage(alg)
    alg.storage.advantages = torch.zeros_like(alg.storage.advantages)
    alg.normalize_advantage_per_mini_batch = False
    noise_before = [p.clone() for p in alg.actor.noise_net.parameters()]
    velocity_before = [p.clone() for p in alg.actor.velocity.parameters()]
    alg.update()
    assert any(not torch.equal(a, b) for a, b in zip(noise_before, alg.actor.noise_net.parameters()))
    assert all(torch.equal(a, b) for a, b in zip(velocity_before, alg.actor.velocity.parameters()))


def test_log_probabilities_are_clamped_before_the_ratio():
    alg = make_reinflow(logprob_clip=[-1.0, 1.0])
    assert alg.clamp_log_prob(torch.tensor([-3.0, 0.5, 2.0])).tolist() == [-1.0, 0.5, 1.0]


def test_noise_bound_decay_hand_worked():
    # sigma range [0.08, 0.16], hold 35% of 100 updates, then cosine to 0.08 + 0.7 * 0.08 = 0.136
    assert decayed_sigma_max(0, 100, 0.08, 0.16, 0.35, 0.7) == 0.16
    assert decayed_sigma_max(35, 100, 0.08, 0.16, 0.35, 0.7) == 0.16
    assert decayed_sigma_max(67.5, 100, 0.08, 0.16, 0.35, 0.7) == pytest.approx(0.148)
    assert decayed_sigma_max(100, 100, 0.08, 0.16, 0.35, 0.7) == pytest.approx(0.136)
    alg = make_reinflow(noise_decay_updates=2, noise_hold_ratio=0.0)
    fill_storage(alg)
    assert alg.update()["Flow/sigma_max"] == pytest.approx(0.148)
    assert float(alg.actor.sigma_max) == pytest.approx(0.148)


def test_plain_rsl_rl_runner_trains_it_by_class_name_on_chunked_actions():
    from rsl_rl.runners import OnPolicyRunner

    from refpo_warp import make_env

    env = make_env("gridworld", num_envs=8, device="cpu", seed=1, action_chunk=2)
    cfg = {
        "num_steps_per_env": 8,
        "save_interval": 100,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {"class_name": "refpo_warp.models:ReinFlowActor", "hidden_dims": [16]},
        "critic": {"class_name": "MLPModel", "hidden_dims": [16]},
        "algorithm": {"class_name": "refpo_warp.algorithms:ReinFlow", "num_learning_epochs": 1, "num_mini_batches": 2},
    }
    runner = OnPolicyRunner(env, cfg, log_dir=None, device="cpu")
    assert runner.alg.actor.action_dim == 4  # a chunk of two 2-D moves
    before = [p.detach().clone() for p in runner.alg.actor.parameters()]
    runner.learn(2)
    assert runner.alg.num_updates == 2
    after = list(runner.alg.actor.parameters())
    assert any(not torch.equal(a, b) for a, b in zip(before, after)), "two updates changed no actor parameter"
    assert all(torch.isfinite(p).all() for p in after)
