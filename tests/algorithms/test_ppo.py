"""Gaussian PPO on the shared update loop: with default options an update is rsl_rl's PPO update, number for number."""

import copy
import math

import pytest
import torch
from rsl_rl.algorithms import PPO as RslPPO
from rsl_rl.models import MLPModel
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from refpo_warp.algorithms import PPO

N, T, OBS, ACT = 8, 6, 5, 3
GAUSSIAN = {"class_name": "GaussianDistribution", "init_std": 0.7, "std_type": "scalar"}


def build(cls, **kwargs):
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(N, OBS)}, batch_size=[N])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    actor = MLPModel(
        obs, groups, "actor", ACT, hidden_dims=[16, 16], obs_normalization=True, distribution_cfg=dict(GAUSSIAN)
    )
    critic = MLPModel(obs, groups, "critic", 1, hidden_dims=[16], obs_normalization=True)
    return cls(actor, critic, RolloutStorage("rl", N, T, obs, [ACT]), **kwargs)


def rollout(alg, seed=1, time_outs=True):
    gen = torch.Generator().manual_seed(seed)
    with torch.inference_mode():
        for _ in range(T):
            obs = TensorDict({"policy": torch.randn(N, OBS, generator=gen)}, batch_size=[N])
            alg.act(obs)
            dones = torch.rand(N, generator=gen) < 0.2
            truncated = dones & (torch.rand(N, generator=gen) < 0.5) & time_outs
            alg.process_env_step(obs, torch.randn(N, generator=gen), dones, {"time_outs": truncated})
        alg.compute_returns(obs)


@pytest.mark.parametrize(
    "options",
    [
        {"schedule": "adaptive", "desired_kl": 0.001, "use_clipped_value_loss": True},
        {"schedule": "fixed", "normalize_advantage_per_mini_batch": True},
    ],
    ids=["adaptive-clipped", "fixed-per-minibatch"],
)
def test_update_matches_rsl_rl_ppo(options):
    kwargs = dict(num_learning_epochs=3, num_mini_batches=4, learning_rate=3e-3, entropy_coef=0.01, **options)
    ours, theirs = build(PPO, **kwargs), build(RslPPO, **kwargs)
    for alg in (ours, theirs):
        torch.manual_seed(5)
        rollout(alg)
    torch.testing.assert_close(ours.storage.advantages, theirs.storage.advantages)
    torch.manual_seed(7)
    ours_stats = ours.update()
    torch.manual_seed(7)
    theirs_stats = theirs.update()
    for name in ("actor", "critic"):
        for p, q in zip(getattr(ours, name).parameters(), getattr(theirs, name).parameters()):
            torch.testing.assert_close(p, q, rtol=1e-5, atol=1e-6)
    assert ours.learning_rate == pytest.approx(theirs.learning_rate)
    for key in ("surrogate", "value", "entropy"):
        assert ours_stats[key] == pytest.approx(theirs_stats[key], rel=1e-4, abs=1e-6)


def test_reward_scale_bound_loss_and_joint_clip_change_the_update():
    base = build(PPO, num_mini_batches=2)
    scaled = build(PPO, num_mini_batches=2, reward_scale=10.0)
    for alg in (base, scaled):
        torch.manual_seed(5)
        rollout(alg, time_outs=False)
    # rewards are scaled before GAE: the stored rewards differ by exactly 10x
    torch.testing.assert_close(scaled.storage.rewards, 10 * base.storage.rewards)
    assert "bound" not in base.update()


def sgd_step(**kwargs):
    """One SGD step on one minibatch of the same rollout: (algorithm, actor and critic before the step, stats)."""
    alg = build(PPO, num_mini_batches=1, num_learning_epochs=1, optimizer="sgd", learning_rate=0.1, **kwargs)
    torch.manual_seed(5)
    rollout(alg, time_outs=False)
    before = copy.deepcopy(alg.actor), copy.deepcopy(alg.critic)
    obs = alg.storage.observations.flatten(0, 1).clone()
    torch.manual_seed(7)
    return alg, before, obs, alg.update()


def test_bound_loss_is_the_mean_squared_mean_action_and_adds_its_own_gradient():
    """bound 0: every mean action is penalised, mean(a_mean^2); with SGD and no gradient clipping the bounded step
    differs from the plain one by exactly -lr * bound_coef * grad(bound loss)."""
    plain, _, _, _ = sgd_step(max_grad_norm=1e9)
    bounded, (reference, _), obs, stats = sgd_step(max_grad_norm=1e9, bound_coef=10.0, bound=0.0)
    reference(obs, stochastic_output=True)  # refreshes the distribution: the mean actions the only minibatch sees
    bound = reference.output_mean.square().mean()
    assert stats["bound"] == pytest.approx(bound.item(), rel=1e-5)
    bound.backward()
    for p_bounded, p_plain, p_ref in zip(bounded.actor.parameters(), plain.actor.parameters(), reference.parameters()):
        grad = torch.zeros_like(p_ref) if p_ref.grad is None else p_ref.grad
        torch.testing.assert_close(p_bounded - p_plain, -0.1 * 10.0 * grad, atol=1e-6, rtol=1e-4)


def test_joint_clip_bounds_the_norm_of_actor_and_critic_together():
    """A gradient norm far above max_grad_norm (1e-3): one SGD step moves each network by exactly lr * 1e-3 when
    they are clipped separately (rsl_rl), and both together by lr * 1e-3 when clipped jointly (Puffer-PHC)."""

    def step_norms(joint):
        alg, (actor, critic), _, _ = sgd_step(max_grad_norm=1e-3, joint_grad_clip=joint)
        return [
            torch.cat([(p - q).flatten() for p, q in zip(new.parameters(), old.parameters())]).norm().item()
            for new, old in ((alg.actor, actor), (alg.critic, critic))
        ]

    separate, joint = step_norms(False), step_norms(True)
    assert separate == pytest.approx([1e-4, 1e-4], rel=1e-4)
    assert math.hypot(*joint) == pytest.approx(1e-4, rel=1e-4)
    assert joint[0] < 0.99e-4 and joint[1] < 0.99e-4
