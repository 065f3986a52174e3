"""ReFPO: ratio, clipped surrogate, Reflow term and diagnostics against hand-worked values and autograd."""

import copy
import math

import pytest
import torch
from rsl_rl.models import MLPModel
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from refpo_warp.algorithms import ReFPO
from refpo_warp.algorithms.refpo import flow_statistics
from refpo_warp.errors import NonFiniteLossError
from refpo_warp.models import FlowActor

N, T, OBS, ACT = 6, 3, 4, 2


def make_refpo(**kwargs):
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(N, OBS)}, batch_size=[N])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    actor = FlowActor(obs, groups, "actor", ACT, hidden_dims=[16, 16], num_flow_steps=5)
    critic = MLPModel(obs, groups, "critic", 1, hidden_dims=[16])
    storage = RolloutStorage("rl", N, T, obs, [ACT])
    defaults = dict(num_mc_samples=4, num_learning_epochs=1, num_mini_batches=1, max_grad_norm=1e9,
                    schedule="fixed", value_loss_coef=0.0, use_clipped_value_loss=False)  # fmt: skip
    return ReFPO(actor, critic, storage, **{**defaults, **kwargs}), obs


def fill_storage(alg, advantages: float | None = 0.0):
    with torch.inference_mode():
        for _ in range(T):
            obs = TensorDict({"policy": torch.randn(N, OBS)}, batch_size=[N])
            alg.act(obs)
            alg.process_env_step(obs, torch.randn(N), torch.zeros(N, dtype=torch.bool), {})
        alg.compute_returns(obs)
    if advantages is not None:
        alg.storage.advantages = torch.full_like(alg.storage.advantages, advantages)


def test_log_ratio_modes_hand_worked():
    alg, _ = make_refpo()
    old = torch.tensor([[1.0, 2.0, 3.0]])
    new = torch.tensor([[0.5, 2.0, 4.0]])
    assert alg.log_ratio(old, new).item() == pytest.approx(-1.0 / 6.0)  # mean of (0.5, 0, -1)
    alg.ratio_mode = "per_sample"
    torch.testing.assert_close(alg.log_ratio(old, new), torch.tensor([[0.5, 0.0, -1.0]]))
    alg.log_ratio_clip = 0.3
    torch.testing.assert_close(alg.log_ratio(old, new), torch.tensor([[0.3, 0.0, -0.3]]))
    alg.ratio_mode = "mean"
    assert alg.log_ratio(old, torch.tensor([[-9.0, 2.0, 3.0]])).item() == pytest.approx(0.1)  # (0.3+0+0)/3


def test_clipped_surrogate_hand_worked():
    alg, _ = make_refpo(clip_param=0.1)
    ratio = torch.tensor([1.2, 1.2, 0.8, 1.05])
    adv = torch.tensor([2.0, -1.0, 1.0, 3.0])
    # per sample: -min(r A, clip(r) A) = -2.2, 1.2, -0.8, -3.15  -> mean -1.2375
    assert alg.surrogate_loss(ratio, adv).item() == pytest.approx(-1.2375)
    # per-sample ratios (B, K) broadcast the advantage of their action
    assert alg.surrogate_loss(ratio.reshape(2, 2), torch.tensor([1.0, 1.0])).item() == pytest.approx(
        -(1.1 + 1.1 + 0.8 + 1.05) / 4
    )


def test_flow_statistics_hand_worked():
    old = torch.tensor([[0.0, 1.0], [2.0, 10.0]])
    new = torch.tensor([[0.5, 4.5], [2.0, 6.0]])
    log_rho = torch.log(torch.tensor([1.0, 1.3]))
    stats = flow_statistics(old, new, log_rho, torch.tensor([[0.1, 0.3]]), clip_param=0.2, explosion_threshold=3.0)
    assert stats["explosion_rate"].item() == pytest.approx(0.5)  # |3.5| and |4| exceed 3
    assert stats["clip_fraction"].item() == pytest.approx(0.5)
    assert stats["ratio_mean"].item() == pytest.approx(1.15)
    assert stats["straightness_error"].item() == pytest.approx(0.2)
    assert stats["approx_kl"].item() == pytest.approx((0.3 - math.log(1.3)) / 2, rel=1e-5)


def test_old_losses_use_rollout_parameters_before_any_step():
    alg, _ = make_refpo(num_mini_batches=1, num_learning_epochs=1)
    fill_storage(alg, advantages=1.0)
    stats = alg.update()
    # the only minibatch is evaluated before the single gradient step: the ratio is exactly 1
    assert stats["ratio_mean"] == pytest.approx(1.0, abs=1e-6)
    assert stats["clip_fraction"] == 0.0 and stats["explosion_rate"] == 0.0


@pytest.mark.parametrize("reflow_coef", [0.0, 0.5])
def test_reflow_term_gradient(reflow_coef):
    """Zero advantages and value weight: one SGD step moves the actor by -lr * reflow_coef * grad(mean CFM)."""
    lr = 0.1
    alg, _ = make_refpo(reflow_coef=reflow_coef, optimizer="sgd", learning_rate=lr)
    fill_storage(alg, advantages=0.0)
    st = alg.storage
    tau, eps, _ = (p.flatten(0, 1).clone() for p in st.distribution_params)
    obs, actions = st.observations.flatten(0, 1).clone(), st.actions.flatten(0, 1).clone()
    reference = copy.deepcopy(alg.actor)
    reference.cfm_loss(obs, actions, tau, eps).mean().backward()
    stats = alg.update()
    assert stats["reflow"] == pytest.approx(reference.cfm_loss(obs, actions, tau, eps).mean().item(), rel=1e-5)
    for p_new, p_ref in zip(alg.actor.parameters(), reference.parameters()):
        expected = p_ref - lr * reflow_coef * p_ref.grad
        torch.testing.assert_close(p_new.detach(), expected.detach(), atol=1e-6, rtol=1e-5)


def test_discrete_tau_grid_and_pair_shapes():
    alg, _ = make_refpo(tau_sampling="discrete")
    tau, eps = alg.sample_pairs(1000, "cpu")
    assert tau.shape == (1000, 4) and eps.shape == (1000, 4, ACT)
    assert set((tau * 5).round().unique().tolist()) == {0, 1, 2, 3, 4}  # the 5-step Euler grid k/5
    assert torch.allclose(tau * 5, (tau * 5).round())


def test_non_finite_loss_stops_before_the_step():
    alg, _ = make_refpo()
    fill_storage(alg, advantages=float("nan"))
    before = [p.clone() for p in alg.actor.parameters()]
    with pytest.raises(NonFiniteLossError, match="stopped before applying"):
        alg.update()
    for p, q in zip(alg.actor.parameters(), before):
        assert torch.equal(p, q)


def test_unsupported_extensions_are_refused():
    obs = TensorDict({"policy": torch.zeros(2, 3)}, batch_size=[2])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    actor = FlowActor(obs, groups, "actor", 1, hidden_dims=[4])
    critic = MLPModel(obs, groups, "critic", 1, hidden_dims=[4])
    storage = RolloutStorage("rl", 2, 2, obs, [1])
    with pytest.raises(ValueError, match="symmetry_cfg"):
        ReFPO(actor, critic, storage, symmetry_cfg={"use_data_augmentation": True})
    with pytest.raises(TypeError, match="FlowActor"):
        ReFPO(critic, critic, storage)


def test_clipped_value_loss_uses_its_own_clip_range():
    alg, _ = make_refpo(clip_param=0.01, value_clip_param=0.2, use_clipped_value_loss=True)
    old, ret = torch.tensor([0.0, 0.0]), torch.tensor([1.0, -1.0])
    values = torch.tensor([0.5, 0.1])
    # clipped values: 0.2 and 0.1 -> per-sample max of (0.25, 0.64) and (1.21, 1.21) -> mean 0.925
    assert alg.value_loss(values, old, ret).item() == pytest.approx(0.925)
    assert make_refpo(clip_param=0.3)[0].value_clip_param == 0.3  # default: rsl_rl's behaviour
