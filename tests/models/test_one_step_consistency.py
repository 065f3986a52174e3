"""The one-step consistency diagnostic against fields whose Euler paths are known in closed form."""

import math

import pytest
import torch
from tensordict import TensorDict

from refpo_warp.models import FlowActor
from refpo_warp.models.flow_diagnostics import env_actions, one_step_consistency

OBS, ACT, ROWS = 3, 2, 64


def actor_with_field(field):
    """A FlowActor whose velocity is ``field(x, tau)`` (the network is bypassed)."""
    obs = TensorDict({"policy": torch.zeros(1, OBS)}, batch_size=[1])
    actor = FlowActor(obs, {"actor": ["policy"]}, "actor", ACT, hidden_dims=[8])
    actor.velocity.forward = lambda feat, x, tau: field(x, tau)
    return actor


def observations():
    return TensorDict({"policy": torch.randn(ROWS, OBS, generator=torch.Generator().manual_seed(0))}, batch_size=[ROWS])


def test_a_constant_field_is_one_step_consistent():
    actor = actor_with_field(lambda x, tau: torch.full_like(x, 0.3))
    out = one_step_consistency(actor, observations(), num_steps=10, generator=torch.Generator().manual_seed(1))
    assert out["one_step_error"] == pytest.approx(0.0, abs=1e-12)
    assert out["policy_spread"] == pytest.approx(1.0, rel=0.2)  # a = eps + 0.3: the noise's own variance


@pytest.mark.parametrize("k, n", [(1.0, 10), (-0.5, 4)])
def test_a_linear_field_matches_the_closed_form_of_its_euler_paths(k, n):
    # v = k x: one Euler step gives (1 + k) eps, n steps (1 + k/n)^n eps, so the squared gap per dimension is
    # ((1 + k) - (1 + k/n)^n)^2 eps^2, and the spread of the n-step action is (1 + k/n)^(2n) Var(eps).
    actor = actor_with_field(lambda x, tau: k * x)
    gen = torch.Generator().manual_seed(2)
    out = one_step_consistency(actor, observations(), num_steps=n, noises=4, generator=gen)
    eps = torch.randn(4 * ROWS, ACT, generator=torch.Generator().manual_seed(2))  # the same draws
    gap = (1 + k) - (1 + k / n) ** n
    assert out["one_step_error"] == pytest.approx(gap**2 * float(eps.square().mean()), rel=1e-5)
    spread = float(eps.reshape(4, ROWS, ACT).var(dim=0).mean()) * (1 + k / n) ** (2 * n)
    assert out["policy_spread"] == pytest.approx(spread, rel=1e-5)
    assert out["one_step_ratio"] == pytest.approx(out["one_step_error"] / out["policy_spread"])


def test_the_gap_is_measured_in_the_envs_action_space():
    # v = 2: a_1 = eps + 2 = a_n; in tanh space also equal. v = 4 x: far apart before tanh, close after (both saturate).
    actor = actor_with_field(lambda x, tau: 4.0 * x)
    raw = one_step_consistency(actor, observations(), 10, None, generator=torch.Generator().manual_seed(3))
    squashed = one_step_consistency(actor, observations(), 10, "tanh", generator=torch.Generator().manual_seed(3))
    assert squashed["one_step_error"] < 0.1 * raw["one_step_error"]
    torch.testing.assert_close(env_actions(torch.tensor([-2.0, 0.5, 3.0]), "clip"), torch.tensor([-1.0, 0.5, 1.0]))
    assert env_actions(torch.tensor([math.inf]), "tanh").item() == 1.0
    with pytest.raises(ValueError, match="action transform"):
        env_actions(torch.zeros(1), "scale")


def test_the_diagnostic_leaves_the_callers_random_stream_alone():
    actor = actor_with_field(lambda x, tau: x)
    torch.manual_seed(5)
    expected = torch.rand(3)
    torch.manual_seed(5)
    one_step_consistency(actor, observations(), 10, generator=torch.Generator().manual_seed(9))
    torch.testing.assert_close(torch.rand(3), expected)
