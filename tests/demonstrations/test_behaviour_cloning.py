"""Behaviour-cloning losses against hand-worked values, the normaliser from the data, the validation split, and a
clone that fits a two-mode action distribution where a Gaussian cannot."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from tensordict import TensorDict

from refpo_warp.demonstrations.behaviour_cloning import (
    CloneOptions,
    as_obs,
    clone,
    flow_bc_loss,
    gaussian_nll,
    make_loss,
    set_normalizer,
    split_episodes,
)
from refpo_warp.models import FlowActor


def obs_of(rows: int, dim: int = 1) -> TensorDict:
    return TensorDict({"policy": torch.zeros(rows, dim)}, batch_size=[rows])


def constant_flow(value: float, **options) -> FlowActor:
    """A flow actor whose velocity is ``value`` everywhere (head weights 0, bias ``value``)."""
    actor = FlowActor(obs_of(2), {"actor": ["policy"]}, "actor", 1, hidden_dims=[4], **options)
    with torch.no_grad():
        actor.velocity.head.weight.zero_()
        actor.velocity.head.bias.fill_(value)
    return actor


@pytest.mark.parametrize("mode,expected", [("u", 0.45), ("eps", (0.3**2 * 0.09 + 0.8**2 * 0.81) / 2)])
def test_flow_loss_is_the_actors_cfm_loss_by_hand(mode, expected):
    # v = 0.5; a = 1; eps = 0.2, -0.4 -> targets a - eps = 0.8, 1.4; errors -0.3, -0.9; squares 0.09, 0.81
    # u: their mean 0.45; eps: weighted by tau^2 (tau = 0.3, 0.8)
    actor = constant_flow(0.5, output_mode=mode)
    tau, eps = torch.tensor([[0.3, 0.8]]), torch.tensor([[[0.2], [-0.4]]])
    loss = flow_bc_loss(actor, obs_of(1), torch.tensor([[1.0]]), tau, eps)
    assert float(loss.detach()) == pytest.approx(expected, rel=1e-6)


def test_gaussian_nll_by_hand():
    from rsl_rl.models import MLPModel

    obs = TensorDict({"policy": torch.zeros(1, 3)}, batch_size=[1])
    actor = MLPModel(
        obs, {"actor": ["policy"]}, "actor", 2, hidden_dims=[4], distribution_cfg={"class_name": "GaussianDistribution"}
    )
    with torch.no_grad():
        actor.mlp[-1].weight.zero_()
        actor.mlp[-1].bias.copy_(torch.tensor([0.2, -0.1]))
        actor.distribution.std_param.copy_(torch.tensor([0.5, 2.0]))
    # per dim 0.5 ((a - m) / s)^2 + log s + 0.5 log(2 pi): (0.5 / 0.5, 1.0 / 2) -> 0.5 + log 0.5, 0.125 + log 2
    expected = 0.5 + math.log(0.5) + 0.125 + math.log(2.0) + math.log(2 * math.pi)
    assert float(gaussian_nll(actor, obs, torch.tensor([[0.7, 0.9]])).detach()) == pytest.approx(expected, rel=1e-6)


def test_normaliser_is_set_to_the_datas_statistics():
    actor = FlowActor(obs_of(2, 2), {"actor": ["policy"]}, "actor", 1, hidden_dims=[4], obs_normalization=True)
    data = np.array([[1.0, 10.0], [3.0, 14.0], [5.0, 12.0]], np.float32)
    assert set_normalizer(actor, data)
    norm = actor.obs_normalizer
    np.testing.assert_allclose(norm.mean.numpy(), [3.0, 12.0])
    np.testing.assert_allclose(norm.std.numpy(), np.sqrt([8 / 3, 8 / 3]), rtol=1e-6)
    assert int(norm.count) == 3
    assert not set_normalizer(constant_flow(0.0), data[:, :1])  # nothing to set where the actor normalises nothing


def test_validation_split_holds_out_whole_episodes():
    train, val = split_episodes(20, 0.1, seed=3)
    assert len(val) == 2 and not set(train) & set(val) and sorted(train + val) == list(range(20))
    assert split_episodes(20, 0.1, seed=3) == (train, val)
    assert split_episodes(2, 0.9, seed=0)[0]  # at least one training episode


def test_as_obs_splits_the_flat_rows_by_group():
    obs = as_obs(torch.arange(10.0).reshape(2, 5), {"a": 2, "b": 3})
    assert obs["a"].tolist() == [[0, 1], [5, 6]] and obs["b"].tolist() == [[2, 3, 4], [7, 8, 9]]


def test_flow_clone_keeps_both_modes_and_stops_early():
    """Actions +1 (70 %) and -1 (30 %) at one observation: the clone samples both in about those shares; the
    validation loss stops training before the epoch limit once it no longer improves."""
    from refpo_warp.algorithms.refpo import sample_tau

    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    actions = np.where(rng.random(3000) < 0.7, 1.0, -1.0).astype(np.float32)[:, None]
    obs = np.zeros((3000, 1), np.float32)
    actor = FlowActor(obs_of(2), {"actor": ["policy"]}, "actor", 1, hidden_dims=[32, 32])

    def tau(shape):
        return sample_tau(shape, "uniform", 10, 0.0, 1.0, "cpu")

    rows = []
    summary = clone(
        actor,
        make_loss(actor, tau, 8),
        {"policy": 1},
        (obs[:2700], actions[:2700]),
        (obs[2700:], actions[2700:]),
        CloneOptions(400, 256, 3e-3, 5, 8, 0),
        rows.append,
    )
    assert summary["stopped_early"] and summary["epochs_run"] == len(rows) < 400
    assert summary["best_val_loss"] == min(r["val_loss"] for r in rows)
    with torch.no_grad():
        samples = actor.sample(obs_of(4000), 10, "random").squeeze(-1)
    up = float((samples > 0.5).float().mean())
    down = float((samples < -0.5).float().mean())
    assert 0.6 < up < 0.8 and 0.2 < down < 0.4, (up, down)
