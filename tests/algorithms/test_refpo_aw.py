"""Advantage-weighted ReFPO: the weighted Reflow term against hand-worked values, equal to ReFPO's when every
advantage is positive, blind to negative-advantage samples, and the trajectory variant's segment returns."""

import pytest
import torch
import torch.nn.functional as F
from rollouts import random_rollout  # tests/algorithms/rollouts.py
from rsl_rl.models import MLPModel
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from refpo_warp.algorithms import AdvantageWeightedReFPO, ReFPO
from refpo_warp.algorithms.refpo_aw import segment_returns, weighted_reflow
from refpo_warp.models import FlowActor

N, T, OBS, ACT = 6, 3, 4, 2


def test_weighted_reflow_hand_worked():
    losses = torch.tensor([1.0, 2.0, 3.0, 4.0])
    adv = torch.tensor([1.0, -1.0, 2.0, -3.0])
    assert weighted_reflow(losses, adv, "positive").item() == pytest.approx((1 + 3) / 2)
    assert weighted_reflow(losses, adv, "relu").item() == pytest.approx((1 * 1 + 2 * 3) / 3)
    w = F.softplus(adv)
    assert weighted_reflow(losses, adv, "softplus").item() == pytest.approx((w * losses).sum().item() / w.sum().item())
    assert weighted_reflow(losses, -adv.abs(), "positive").item() == 0.0  # no positive advantage: no term
    assert weighted_reflow(losses, -adv.abs(), "relu").item() == 0.0
    with pytest.raises(ValueError, match="reflow_weighting"):
        weighted_reflow(losses, adv, "negative")


def test_positive_weighting_equals_the_plain_term_when_every_advantage_is_positive():
    losses = torch.rand(16)
    assert weighted_reflow(losses, torch.rand(16) + 0.1, "positive").item() == pytest.approx(losses.mean().item())


def test_negative_advantage_samples_get_no_reflow_gradient():
    losses = torch.rand(8, requires_grad=True)
    adv = torch.tensor([1.0, -1.0] * 4)
    weighted_reflow(losses, adv, "positive").backward()
    assert torch.equal(losses.grad[1::2], torch.zeros(4))
    torch.testing.assert_close(losses.grad[0::2], torch.full((4,), 0.25))
    changed = losses.detach().clone()
    changed[1::2] += 100.0
    before = weighted_reflow(losses, adv, "positive").item()
    assert weighted_reflow(changed, adv, "positive").item() == pytest.approx(before)


def test_segment_returns_hand_worked():
    # one env, rewards 1..5, the episode ends after step 1: segments (1, 2) -> 3 and (3, 4, 5) -> 12
    rewards = torch.tensor([1.0, 2.0, 3.0, 4.0, 5.0]).unsqueeze(-1)
    dones = torch.tensor([False, True, False, False, False]).unsqueeze(-1)
    torch.testing.assert_close(segment_returns(rewards, dones).squeeze(-1), torch.tensor([3.0, 3.0, 12.0, 12.0, 12.0]))


def build(cls, **kwargs):
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(N, OBS)}, batch_size=[N])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    actor = FlowActor(obs, groups, "actor", ACT, hidden_dims=[16, 16], num_flow_steps=5)
    critic = MLPModel(obs, groups, "critic", 1, hidden_dims=[16])
    return cls(
        actor,
        critic,
        RolloutStorage("rl", N, T, obs, [ACT]),
        num_mc_samples=4,
        num_learning_epochs=2,
        num_mini_batches=2,
        reflow_coef=0.5,
        **kwargs,
    )


def rollout(alg, advantages):
    torch.manual_seed(3)
    random_rollout(alg, T, N, OBS)
    alg.storage.advantages = advantages.reshape(T, N, 1).clone()


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["all-positive", "all-negative"])
def test_update_matches_refpo_with_all_positive_and_without_reflow_with_all_negative_advantages(sign):
    advantages = sign * (torch.rand(T * N, generator=torch.Generator().manual_seed(2)) + 0.5)
    ours, plain = build(AdvantageWeightedReFPO), build(ReFPO)
    if sign < 0:
        plain.reflow_coef = 0.0  # no positive advantage: the weighted term vanishes
    stats = []
    for alg in (ours, plain):
        rollout(alg, advantages)
        torch.manual_seed(7)
        stats.append(alg.update())
    for p, q in zip(ours.actor.parameters(), plain.actor.parameters()):
        torch.testing.assert_close(p, q, rtol=1e-5, atol=1e-6)
    assert (stats[0]["reflow"] > 0) == (sign > 0)


def test_trajectory_weighting_uses_segment_returns_relative_to_the_batch():
    alg = build(AdvantageWeightedReFPO, reflow_weighting="trajectory")
    rollout(alg, torch.ones(T * N))
    alg.before_update()
    st = alg.storage
    totals = segment_returns(st.rewards.squeeze(-1), st.dones.squeeze(-1))
    torch.testing.assert_close(alg.store.flat("trajectory_advantage"), (totals - totals.mean()).flatten())


def test_plain_rsl_rl_runner_trains_it_by_class_name():
    from rsl_rl.runners import OnPolicyRunner

    from refpo_warp import make_env

    cfg = {
        "num_steps_per_env": 8,
        "save_interval": 100,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {"class_name": "refpo_warp.models:FlowActor", "hidden_dims": [16], "num_flow_steps": 4},
        "critic": {"class_name": "MLPModel", "hidden_dims": [16]},
        "algorithm": {
            "class_name": "refpo_warp.algorithms:AdvantageWeightedReFPO",
            "reflow_weighting": "softplus",
            "num_learning_epochs": 1,
            "num_mini_batches": 2,
        },
    }
    runner = OnPolicyRunner(make_env("gridworld", num_envs=8, device="cpu", seed=1), cfg, log_dir=None, device="cpu")
    before = [p.detach().clone() for p in runner.alg.actor.parameters()]
    runner.learn(2)
    assert isinstance(runner.alg, AdvantageWeightedReFPO) and runner.alg.reflow_weighting == "softplus"
    assert runner.alg.num_updates == 2
    after = list(runner.alg.actor.parameters())
    assert any(not torch.equal(a, b) for a, b in zip(before, after)), "two updates changed no actor parameter"
    assert all(torch.isfinite(p).all() for p in after)
