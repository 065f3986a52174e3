"""The EMA actor (``algorithm.ema_decay``, FPO++'s): its start after the warm-up and its update by hand; the live
weights as the policy of evaluation, checkpoints and export before the warm-up, the average after it; checkpoints that
hold both, a resume training on from the live ones."""

import copy

import pytest
import torch
from rollouts import random_rollout  # tests/algorithms/rollouts.py
from rsl_rl.models import MLPModel
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict
from torch import nn

from refpo_warp.algorithms import FPOPlusPlus, ReFPO
from refpo_warp.models import FlowActor
from refpo_warp.models.ema import ActorEMA

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

N, T, OBS, ACT = 8, 4, 3, 2


class Scalar(nn.Module):
    def __init__(self, value: float) -> None:
        super().__init__()
        self.w = nn.Parameter(torch.tensor([value]))
        self.register_buffer("count", torch.tensor([0.0]))


def test_ema_starts_after_its_warmup_from_the_live_weights_hand_worked():
    live = Scalar(0.0)
    ema = ActorEMA(live, decay=0.5, warmup=3)
    expected = [(1.0, 0.0), (2.0, 0.0), (3.0, 3.0), (5.0, 4.0), (9.0, 6.5)]  # (live, average) after each update
    for update, (value, average) in enumerate(expected, start=1):
        with torch.no_grad():
            live.w.fill_(value)
            live.count.fill_(10.0 * update)
        ema.update(live, update)  # nothing before update 3; then the live weights; then 0.5 * ema + 0.5 * live
        assert ema.model.w.item() == pytest.approx(average), update
        assert ema.started(update) == (update >= 3)
        if update >= 3:
            assert ema.model.count.item() == 10.0 * update  # buffers (the normaliser) follow the live actor
    assert not ema.model.w.requires_grad and not ema.started(2) and ActorEMA(live, 0.5, 0).started(0)


def build(cls=ReFPO, **kwargs):
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(N, OBS)}, batch_size=[N])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    actor = FlowActor(obs, groups, "actor", ACT, hidden_dims=[16], num_flow_steps=4, obs_normalization=True)
    critic = MLPModel(obs, groups, "critic", 1, hidden_dims=[16])
    storage = RolloutStorage("rl", N, T, obs, [ACT])
    return cls(
        actor,
        critic,
        storage,
        num_mc_samples=2,
        num_learning_epochs=2,
        num_mini_batches=2,
        learning_rate=1e-2,
        **kwargs,
    ), obs


def train(alg, updates: int) -> None:
    for seed in range(updates):
        random_rollout(alg, T, N, OBS, seed=seed)
        alg.update()


def test_rollouts_use_the_live_actor_and_the_policy_is_the_ema_after_its_warmup():
    alg, obs = build(ema_decay=0.9, ema_warmup=1)
    train(alg, 3)
    policy = alg.get_policy()
    assert policy is alg.ema.model and policy is not alg.actor
    live, ema = alg.actor.sample(obs, initial_noise="zero"), policy.sample(obs, initial_noise="zero")
    assert not torch.allclose(live, ema)  # started after update 1, two updates behind

    def from_one_stream(sample):
        torch.manual_seed(3)
        with torch.inference_mode():
            return sample()

    step = from_one_stream(lambda: alg.act(obs))  # the action a rollout step stores and sends to the env
    torch.testing.assert_close(step, from_one_stream(lambda: alg.actor(obs, stochastic_output=True)))
    assert not torch.allclose(step, from_one_stream(lambda: policy(obs, stochastic_output=True)))
    plain, _ = build()  # off by default for ReFPO
    assert plain.ema is None and plain.get_policy() is plain.actor


def test_before_the_warmup_evaluation_checkpoints_and_export_use_the_live_weights():
    alg, obs = build(FPOPlusPlus, ema_warmup=3)
    train(alg, 2)
    assert alg.get_policy() is alg.actor and "ema_actor_state_dict" not in alg.save()
    exported = torch.jit.script(alg.get_policy().as_jit())
    torch.testing.assert_close(exported(obs["policy"]), alg.actor.sample(obs, initial_noise="zero"))
    train(alg, 1)  # update 3: the average starts from the live weights
    assert alg.get_policy() is alg.ema.model
    for a, b in zip(alg.actor.state_dict().values(), alg.ema.state_dict().values()):
        torch.testing.assert_close(a, b, rtol=0, atol=0)
    train(alg, 1)
    saved = alg.save()
    assert not torch.equal(
        saved["ema_actor_state_dict"]["velocity.head.weight"], saved["actor_state_dict"]["velocity.head.weight"]
    )
    default, _ = build(FPOPlusPlus)  # FPO++'s 500 updates: a short run never uses its average
    train(default, 2)
    assert default.ema.warmup == 500 and default.get_policy() is default.actor


def test_zero_noise_sampling_is_deterministic():
    alg, obs = build()
    first, second = alg.actor.sample(obs, initial_noise="zero"), alg.actor.sample(obs, initial_noise="zero")
    torch.testing.assert_close(first, second, rtol=0, atol=0)
    assert not torch.equal(alg.actor.sample(obs), alg.actor.sample(obs))  # random x_0


def test_export_gives_the_ema_actors_zero_noise_actions():
    alg, obs = build(FPOPlusPlus, ema_warmup=1)
    train(alg, 2)
    exported = torch.jit.script(alg.get_policy().as_jit())
    expected = alg.ema.model.sample(obs, initial_noise="zero")
    torch.testing.assert_close(exported(obs["policy"]), expected)
    assert not torch.allclose(exported(obs["policy"]), alg.actor.sample(obs, initial_noise="zero"))


def test_checkpoint_holds_both_and_a_resume_trains_from_the_live_weights():
    alg, _ = build(ema_decay=0.9, ema_warmup=1)
    train(alg, 2)
    saved = alg.save()
    assert saved["num_updates"] == 2
    resumed, _ = build(ema_decay=0.9, ema_warmup=1)
    resumed.load(saved, None, strict=True)
    for name, value in alg.actor.state_dict().items():
        torch.testing.assert_close(resumed.actor.state_dict()[name], value)  # the weights training continues from
    for name, value in alg.ema.state_dict().items():
        torch.testing.assert_close(resumed.ema.state_dict()[name], value)
    assert not all(torch.equal(a, b) for a, b in zip(resumed.actor.parameters(), resumed.ema.model.parameters()))
    # a checkpoint past the warm-up without an EMA starts the average at its weights
    plain, _ = build()
    train(plain, 1)
    late, _ = build(ema_decay=0.9, ema_warmup=1)
    late.load(plain.save(), None, strict=True)
    for a, b in zip(late.actor.parameters(), late.ema.model.parameters()):
        torch.testing.assert_close(a, b)


def test_a_resume_before_the_warmup_trains_on_from_the_live_weights_and_starts_the_average_on_time():
    alg, _ = build(ema_decay=0.9, ema_warmup=3)
    train(alg, 2)
    resumed, _ = build(ema_decay=0.9, ema_warmup=3)
    resumed.load(copy.deepcopy(alg.save()), None, strict=True)  # as from a file: no tensor shared with alg
    assert resumed.get_policy() is resumed.actor
    for a, b in zip(alg.actor.state_dict().values(), resumed.actor.state_dict().values()):
        torch.testing.assert_close(a, b, rtol=0, atol=0)
    for one in (alg, resumed):  # the same third update from the same weights, rollout and random numbers
        torch.manual_seed(7)
        random_rollout(one, T, N, OBS, seed=2)
        one.update()
    for a, b in zip(alg.ema.state_dict().values(), resumed.ema.state_dict().values()):
        torch.testing.assert_close(a, b)
    for a, b in zip(resumed.actor.state_dict().values(), resumed.ema.state_dict().values()):
        torch.testing.assert_close(a, b, rtol=0, atol=0)  # started from the live weights at update 3
