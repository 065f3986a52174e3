"""ReFPO's one-step options (ours, beyond the paper): the one-step consistency term on the rollout's own (eps_0, a) and
the Reflow term weighted towards small flow times, against hand-worked values and the actor's own sampler."""

import pytest
import torch
from rollouts import random_rollout, small_flow_algorithm  # tests/algorithms/rollouts.py

from refpo_warp.algorithms import ReFPO
from refpo_warp.algorithms.on_policy import Minibatch
from refpo_warp.utils.errors import ConfigError

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

N, T, OBS, ACT = 6, 3, 4, 2


def build(**kwargs) -> ReFPO:
    return small_flow_algorithm(
        ReFPO, N, T, OBS, ACT, num_mc_samples=3, num_learning_epochs=1, num_mini_batches=1, **kwargs
    )[0]


def test_the_one_step_term_is_the_one_step_samplers_error_against_the_rollout_action():
    alg = build(one_step_coef=0.5)
    random_rollout(alg, T, N, OBS)
    alg.before_update()
    batch = next(iter(alg.minibatches()))
    loss, stats = alg.policy_loss(batch)
    with torch.no_grad():
        one_step = alg.actor.sample(batch.observations, 1, noise=batch.field("eps0"))  # eps_0 + v(eps_0, 0)
        n_step = alg.actor.sample(batch.observations, noise=batch.field("eps0"))
    torch.testing.assert_close(n_step, batch.actions)  # the rollout's action is the N-step sample of its eps_0
    expected = (one_step - batch.actions).square().mean()
    torch.testing.assert_close(stats["one_step"], expected, rtol=1e-5, atol=1e-7)
    plain = stats["surrogate"] + alg.reflow_coef * stats["reflow"]
    torch.testing.assert_close(loss, plain + 0.5 * expected, rtol=1e-5, atol=1e-7)
    assert "one_step" not in build().policy_loss(batch)[1]  # off by default


def test_towards_zero_weights_the_reflow_pairs_by_one_minus_tau():
    alg = build(reflow_tau_weight="towards_zero")
    alg.store.write_all(tau=torch.tensor([[0.0, 0.5, 0.9]]).repeat(N * T, 1))
    batch = Minibatch(None, None, None, None, None, torch.arange(2), alg.store)
    losses = torch.tensor([[1.0, 2.0, 4.0], [3.0, 3.0, 3.0]])
    # weights 1, 0.5, 0.1 per row: (1 + 1 + 0.4 + 3 + 1.5 + 0.3) / (2 * 1.6)
    assert alg.reflow_loss(losses, batch).item() == pytest.approx(7.2 / 3.2)
    assert build().reflow_loss(losses, batch).item() == pytest.approx(16.0 / 6)


def test_options_are_validated():
    with pytest.raises(ConfigError, match="one_step_coef=-1"):
        build(one_step_coef=-1.0)
    with pytest.raises(ConfigError, match="'uniform', 'towards_zero'"):
        build(reflow_tau_weight="small")
