"""FPO++: the trust regions, the per-pair ratio with its caps and straight-through cap, the sqrt(D) CFM reduction, the
advantage clamp and the Reflow term of ReFPO on FPO++, against hand-worked values and autograd."""

import math

import pytest
import torch
from rollouts import small_flow_algorithm  # tests/algorithms/rollouts.py

from refpo_warp.algorithms import FPOPlusPlus, ReFPO
from refpo_warp.algorithms.fpo_pp import straight_through_max
from refpo_warp.algorithms.on_policy import Minibatch
from refpo_warp.algorithms.refpo import sample_tau
from refpo_warp.algorithms.trust_region import surrogate
from refpo_warp.utils.errors import ConfigError

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

N, T, OBS, ACT = 6, 3, 4, 2


def make(cls=FPOPlusPlus, **kwargs):
    defaults = {"num_mc_samples": 4, "num_learning_epochs": 1, "num_mini_batches": 1, "max_grad_norm": 1e9}
    return small_flow_algorithm(cls, N, T, OBS, ACT, **{**defaults, **kwargs})


# ---------------------------------------------------------------------------------------------------- trust regions
RATIO, ADV = torch.tensor([1.1, 0.9]), torch.tensor([1.0, -1.0])


def test_ppo_clip_hand_worked():
    # A = 1: -min(1.1, 1.05) = -1.05; A = -1: -min(-0.9, -0.95) = 0.95
    assert surrogate(RATIO, ADV, 0.05, "ppo").item() == pytest.approx((-1.05 + 0.95) / 2)


def test_spo_penalty_hand_worked():
    # -(rho A - |A| / (2 e) (rho - 1)^2), e = 0.05: A = 1: -(1.1 - 10 * 0.01) = -1.0; A = -1: -(-0.9 - 0.1) = 1.0
    assert surrogate(RATIO, ADV, 0.05, "spo").item() == pytest.approx(0.0, abs=1e-6)


def test_aspo_takes_ppo_for_positive_and_spo_for_other_advantages():
    assert surrogate(RATIO, ADV, 0.05, "aspo").item() == pytest.approx((-1.05 + 1.0) / 2)
    # A = 0 counts as non-positive (SPO): both terms vanish
    assert surrogate(torch.tensor([2.0]), torch.tensor([0.0]), 0.05, "aspo").item() == 0.0


def test_spo_gradient_pulls_the_ratio_back_where_ppo_gives_none():
    ratio = torch.tensor([1.2], requires_grad=True)
    surrogate(ratio, torch.tensor([1.0]), 0.05, "ppo").backward()
    assert ratio.grad.item() == 0.0  # clipped: no gradient
    ratio.grad = None
    surrogate(ratio, torch.tensor([1.0]), 0.05, "spo").backward()
    # d/drho of -(rho - 10 (rho - 1)^2) = -1 + 20 (rho - 1) = 3 > 0: descent lowers rho towards 1.05
    assert ratio.grad.item() == pytest.approx(3.0)


def test_per_sample_ratio_broadcasts_the_advantage_over_pairs():
    ratio = torch.tensor([[1.1, 0.9], [1.0, 1.0]])
    adv = torch.tensor([1.0, -2.0])
    # row 0 (PPO): -min(1.1, 1.05) = -1.05 and -0.9; row 1 (SPO at rho = 1): 2, 2
    assert surrogate(ratio, adv, 0.05, "aspo").item() == pytest.approx((-1.05 - 0.9 + 2.0 + 2.0) / 4)


# ---------------------------------------------------------------------------------------------------- the ratio
def test_caps_and_straight_through_cap_hand_worked():
    alg, _ = make()
    old = torch.tensor([[25.0, 3.0, 15.0], [25.0, 3.0, 15.0]])
    new = torch.tensor([[30.0, 1.0, 2.0], [30.0, 1.0, 2.0]], requires_grad=True)
    adv = torch.tensor([1.0, -1.0])
    # caps at 20: old (20, 3, 15), new (20, 1, 2); differences (0, 2, 13); the 13 is capped at 10 in the forward pass
    log_rho = alg.log_ratio(old, new, adv)
    torch.testing.assert_close(log_rho, torch.tensor([[0.0, 2.0, 10.0], [0.0, 2.0, 10.0]]))
    log_rho.sum().backward()
    # d(delta)/d(L_new) = -1 through the straight-through cap; 0 where L_new was capped (30 > 20)
    torch.testing.assert_close(new.grad, torch.tensor([[0.0, -1.0, -1.0], [0.0, -1.0, -1.0]]))


def test_negative_advantage_cap_acts_where_the_advantage_is_negative_only():
    alg, _ = make(loss_cap=None, negative_advantage_loss_cap=5.0, log_ratio_cap=None)
    old, new = torch.tensor([[8.0], [8.0]]), torch.tensor([[7.0], [7.0]])
    torch.testing.assert_close(alg.log_ratio(old, new, torch.tensor([1.0, -1.0])), torch.tensor([[1.0], [3.0]]))


def test_straight_through_max():
    x = torch.tensor([1.0, 12.0], requires_grad=True)
    y = straight_through_max(x, 10.0)
    y.sum().backward()
    torch.testing.assert_close(y, torch.tensor([1.0, 10.0]))
    torch.testing.assert_close(x.grad, torch.ones(2))


def test_sqrt_dim_reduction_is_the_sum_over_actions_over_sqrt_d():
    alg, obs = make()
    actions, tau, eps = torch.randn(N, ACT), torch.rand(N, 4), torch.randn(N, 4, ACT)
    loss, terms = alg.cfm_losses(obs, actions, tau, eps)
    # sum_d e^2 / sqrt(D) = D * mean_d e^2 / sqrt(D)
    torch.testing.assert_close(loss, terms.velocity_error * ACT / math.sqrt(ACT))
    alg.cfm_reduction = "mean"
    torch.testing.assert_close(alg.cfm_losses(obs, actions, tau, eps)[0], terms.velocity_error)


def batch_of(alg, obs, advantages):
    actions, tau, eps = torch.randn(N, ACT), torch.rand(N, 4), torch.randn(N, 4, ACT)
    alg.store.write_all(tau=tau.repeat(T, 1), eps=eps.repeat(T, 1, 1), old_loss=torch.ones(N * T, 4))
    zeros = torch.zeros(N, 1)
    return Minibatch(obs, actions, zeros, zeros, advantages, torch.arange(N), alg.store)


def test_advantages_are_clamped_before_the_surrogate():
    alg, obs = make(advantage_clip=100.0)
    big = batch_of(alg, obs, torch.tensor([1000.0, -1000.0, 5.0, -5.0, 100.0, 0.0]))
    clamped = Minibatch(**{**big.__dict__, "advantages": torch.tensor([100.0, -100.0, 5.0, -5.0, 100.0, 0.0])})
    assert alg.policy_loss(big)[0].item() == pytest.approx(alg.policy_loss(clamped)[0].item())


def test_reflow_term_is_the_uncapped_mean_cfm_loss_of_the_same_pairs():
    alg, obs = make(reflow_coef=0.5)
    batch = batch_of(alg, obs, torch.zeros(N))
    new_loss = alg.cfm_losses(obs, batch.actions, batch.field("tau"), batch.field("eps"))[0]
    loss, stats = alg.policy_loss(batch)
    assert stats["reflow"].item() == pytest.approx(new_loss.mean().item())
    assert loss.item() == pytest.approx(stats["surrogate"].item() + 0.5 * new_loss.mean().item(), rel=1e-5)


def test_defaults_are_fpo_plus_plus_and_refpo_accepts_the_trust_region():
    alg, _ = make()
    assert (alg.reflow_coef, alg.ratio_mode, alg.trust_region, alg.tau_sampling, alg.output_mode) == (
        0.0,
        "per_sample",
        "aspo",
        "uniform_inset",
        "u",
    )
    assert (
        alg.cfm_reduction,
        alg.loss_cap,
        alg.negative_advantage_loss_cap,
        alg.log_ratio_cap,
        alg.advantage_clip,
        alg.ema.decay,
        alg.ema.warmup,
    ) == ("sqrt_dim", 20.0, 20.0, 10.0, 100.0, 0.95, 500)
    assert make(ReFPO)[0].trust_region == "ppo"
    for trust_region in ("ppo", "spo", "aspo"):
        assert make(ReFPO, trust_region=trust_region)[0].trust_region == trust_region
    with pytest.raises(ConfigError, match="trust_region='clip' is invalid; expected one of 'ppo', 'spo', 'aspo'"):
        make(ReFPO, trust_region="clip")


def test_inset_flow_times_stay_inside_the_margins():
    tau = sample_tau((20000,), "uniform_inset", 10, 0.0, 1.0, "cpu")
    assert 0.005 <= tau.min().item() < 0.006 and 0.994 < tau.max().item() <= 0.995
    assert tau.mean().item() == pytest.approx(0.5, abs=0.01)
