"""Every algorithm logs each network's gradient norm before the clip (Loss/grad_norm_actor, Loss/grad_norm_critic: the
mean over the update's minibatches), the norms torch.nn.utils.clip_grad_norm_ computes, and logging them changes no
parameter update."""

import math

import pytest
import torch
from rollouts import random_rollout, small_flow_algorithm  # tests/algorithms/rollouts.py
from test_flow_grpo import make_flow_grpo
from test_ppo import build, rollout
from torch import nn

from refpo_warp.algorithms import PPO, FPOPlusPlus, ReFPO
from refpo_warp.algorithms.on_policy import OnPolicyAlgorithm

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

N, T, OBS, ACT = 6, 4, 4, 2


def recording_clip(monkeypatch):
    """Every clip_grad_norm_ call: (float64 copies of the gradients it was given, by parameter id, the norm it
    returned)."""
    calls, original = [], torch.nn.utils.clip_grad_norm_

    def clip(parameters, max_norm, *args, **kwargs):
        parameters = list(parameters)
        grads = {id(p): p.grad.detach().double().clone() for p in parameters if p.grad is not None}
        norm = original(parameters, max_norm, *args, **kwargs)
        calls.append((grads, float(norm)))
        return norm

    monkeypatch.setattr(torch.nn.utils, "clip_grad_norm_", clip)
    return calls


def norm_of(grads: dict, module: nn.Module) -> float:
    ids = {id(p) for p in module.parameters()}
    return math.sqrt(sum(float(g.square().sum()) for key, g in grads.items() if key in ids))


def ppo(**kwargs):
    alg = build(PPO, num_mini_batches=2, num_learning_epochs=2, max_grad_norm=0.05, **kwargs)
    torch.manual_seed(5)
    rollout(alg)
    return alg


def fpo_pp(**kwargs):
    options = {"num_mc_samples": 4, "num_mini_batches": 2, "num_learning_epochs": 2, "max_grad_norm": 0.05}
    alg, _ = small_flow_algorithm(FPOPlusPlus, N, T, OBS, ACT, **{**options, **kwargs})
    random_rollout(alg, T, N, OBS)
    return alg


@pytest.mark.parametrize("make", [ppo, fpo_pp], ids=["ppo", "fpo_pp"])
def test_separate_clip_logs_the_norms_clip_grad_norm_returns(make, monkeypatch):
    alg = make(joint_grad_clip=False)
    calls = recording_clip(monkeypatch)
    stats = alg.update()
    assert len(calls) == 8  # 4 minibatches x (actor, critic)
    actor, critic = calls[0::2], calls[1::2]
    for grads, norm in actor:
        assert norm == pytest.approx(norm_of(grads, alg.actor), rel=1e-5) and norm > 0.05  # the clip acted
    for grads, norm in critic:
        assert norm == pytest.approx(norm_of(grads, alg.critic), rel=1e-5)
    assert stats["grad_norm_actor"] == pytest.approx(sum(n for _, n in actor) / 4, rel=1e-6)
    assert stats["grad_norm_critic"] == pytest.approx(sum(n for _, n in critic) / 4, rel=1e-6)


@pytest.mark.parametrize("make", [ppo, fpo_pp], ids=["ppo", "fpo_pp"])
def test_joint_clip_logs_each_network_norm_before_the_one_clip(make, monkeypatch):
    alg = make(joint_grad_clip=True)
    calls = recording_clip(monkeypatch)
    stats = alg.update()
    assert len(calls) == 4  # one clip over actor and critic per minibatch
    actor = [norm_of(grads, alg.actor) for grads, _ in calls]
    critic = [norm_of(grads, alg.critic) for grads, _ in calls]
    for a, c, (_, joint) in zip(actor, critic, calls):
        assert math.hypot(a, c) == pytest.approx(joint, rel=1e-5)  # the two parts of the norm it clipped from
    assert stats["grad_norm_actor"] == pytest.approx(sum(actor) / 4, rel=1e-5)
    assert stats["grad_norm_critic"] == pytest.approx(sum(critic) / 4, rel=1e-5)


def test_an_algorithm_without_a_critic_logs_the_actor_norm_only(monkeypatch):
    alg = make_flow_grpo(num_mini_batches=2, max_grad_norm=1e-4)
    random_rollout(alg, 3, 8, 4)
    calls = recording_clip(monkeypatch)
    stats = alg.update()
    assert "grad_norm_critic" not in stats and len(calls) == 2
    assert stats["grad_norm_actor"] == pytest.approx(sum(n for _, n in calls) / 2, rel=1e-6)


def clip_before_the_norms_were_logged(self):
    """The update loop's clip as it was before it returned the norms."""
    if self.joint_grad_clip:
        nn.utils.clip_grad_norm_(list(self.actor.parameters()) + list(self.critic.parameters()), self.max_grad_norm)
    else:
        nn.utils.clip_grad_norm_(self.actor.parameters(), self.max_grad_norm)
        if self.uses_critic:
            nn.utils.clip_grad_norm_(self.critic.parameters(), self.max_grad_norm)
    return {}


@pytest.mark.parametrize(
    "make,joint",
    [(ppo, False), (ppo, True), (fpo_pp, True), (fpo_pp, False)],
    ids=["ppo", "ppo-joint", "fpo_pp", "fpo_pp-separate"],
)
def test_logging_the_norms_changes_no_parameter(make, joint, monkeypatch):
    logged = make(joint_grad_clip=joint)
    torch.manual_seed(7)
    logged.update()
    monkeypatch.setattr(OnPolicyAlgorithm, "clip_gradients", clip_before_the_norms_were_logged)
    plain = make(joint_grad_clip=joint)
    torch.manual_seed(7)
    plain.update()
    for a, b in zip(logged.optimizer.param_groups[0]["params"], plain.optimizer.param_groups[0]["params"]):
        assert torch.equal(a, b)


def test_refpo_logs_both_norms():
    alg, _ = small_flow_algorithm(ReFPO, N, T, OBS, ACT, num_mc_samples=4, num_mini_batches=1, num_learning_epochs=1)
    random_rollout(alg, T, N, OBS)
    stats = alg.update()
    assert stats["grad_norm_actor"] > 0 and stats["grad_norm_critic"] > 0
    assert "learning_rate" not in stats  # a fixed rate is not logged
