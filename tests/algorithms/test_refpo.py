"""ReFPO: ratio, clipped surrogate, Reflow term, diagnostics and options against hand-worked values and autograd."""

import copy
import math

import pytest
import torch
from rollouts import small_flow_algorithm  # tests/algorithms/rollouts.py
from rsl_rl.models import MLPModel
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from refpo_warp.algorithms import ReFPO
from refpo_warp.algorithms.on_policy import soft_bound_loss, value_regression_loss
from refpo_warp.algorithms.refpo import TauSampling, sample_tau
from refpo_warp.models import FlowActor
from refpo_warp.utils.errors import ConfigError, NonFiniteLossError

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

N, T, OBS, ACT = 6, 3, 4, 2


def make_refpo(actor_kwargs=None, **kwargs):
    defaults = {
        "num_mc_samples": 4,
        "num_learning_epochs": 1,
        "num_mini_batches": 1,
        "max_grad_norm": 1e9,
        "value_loss_coef": 0.0,
    }
    return small_flow_algorithm(ReFPO, N, T, OBS, ACT, actor_kwargs, **{**defaults, **kwargs})


def fill_storage(alg, advantages: float | None = 0.0):
    with torch.inference_mode():
        for _ in range(T):
            obs = TensorDict({"policy": torch.randn(N, OBS)}, batch_size=[N])
            alg.act(obs)
            alg.process_env_step(obs, torch.randn(N), torch.zeros(N, dtype=torch.bool), {})
        alg.compute_returns(obs)
    if advantages is not None:
        alg.storage.advantages = torch.full_like(alg.storage.advantages, advantages)


def test_defaults_are_the_projects_tuned_values():
    alg, _ = make_refpo()
    assert (alg.schedule, alg.clip_param, alg.learning_rate, alg.reflow_coef) == ("fixed", 0.05, 3e-4, 0.04)
    assert (alg.entropy_coef, alg.use_clipped_value_loss) == (0.0, False)
    with pytest.warns(UserWarning, match="adaptive"):
        make_refpo(schedule="adaptive")


def test_the_constructor_sets_every_option_and_checks_the_given_ones():
    alg, _ = make_refpo(reflow_coef=0.3, reward_scale=10, tau_sampling=TauSampling.DISCRETE)
    assert (alg.reflow_coef, alg.reward_scale, alg.tau_sampling) == (0.3, 10.0, "discrete")
    assert type(alg.reward_scale) is float and type(alg.tau_sampling) is str  # the rules normalise
    assert (alg.explosion_threshold, alg.value_clip_param, alg.one_step_states) == (3.0, 0.05, 256)  # defaults
    with pytest.raises(ConfigError, match=r"ReFPO.reflow_coef=-1 is invalid"):
        make_refpo(reflow_coef=-1)


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
    """Explosion per action (the paper's number) vs per pair, on hand-made old/new losses."""
    alg, _ = make_refpo(clip_param=0.2)
    old = torch.tensor([[0.0, 1.0], [2.0, 10.0], [0.0, 0.0]])
    new = torch.tensor([[0.5, 4.5], [2.0, 6.0], [3.5, 3.5]])
    # pair changes old - new: (-0.5, -3.5), (0, 4), (-3.5, -3.5); per-action means: -2, 2, -3.5
    log_rho = (old - new).mean(dim=-1)
    stats = alg.flow_statistics(old, new, log_rho, torch.tensor([[0.1, 0.3]]))
    assert stats["Flow/explosion_rate_pair"].item() == pytest.approx(4 / 6)  # |3.5|, |4|, |3.5|, |3.5| exceed 3
    assert stats["Flow/explosion_rate"].item() == pytest.approx(1 / 3)  # only the third action's |-3.5|
    ratio = torch.exp(torch.tensor([-2.0, 2.0, -3.5]))
    assert stats["Flow/clip_fraction"].item() == 1.0
    assert stats["Flow/ratio_mean"].item() == pytest.approx(ratio.mean().item())
    assert stats["Flow/ratio_max"].item() == pytest.approx(math.exp(2.0))
    assert stats["Flow/straightness_error"].item() == pytest.approx(0.2)
    assert stats["Flow/approx_kl"].item() == pytest.approx(((ratio - 1) - torch.log(ratio)).mean().item(), rel=1e-5)


def test_old_losses_use_rollout_parameters_before_any_step():
    alg, _ = make_refpo(num_mini_batches=1, num_learning_epochs=1)
    fill_storage(alg, advantages=1.0)
    stats = alg.update()
    # the only minibatch is evaluated before the single gradient step: the ratio is exactly 1
    assert stats["Flow/ratio_mean"] == pytest.approx(1.0, abs=1e-6)
    assert stats["Flow/clip_fraction"] == 0.0 and stats["Flow/explosion_rate"] == 0.0


@pytest.mark.parametrize(
    "reflow_coef, actor_kwargs",
    [
        (0.0, {}),
        (0.5, {}),
        (
            0.5,
            {
                "parameterization": "data",
                "output_mode": "data",
                "loss_scale": 200.0,
                "time_conditioning": "adaln",
                "time_embed_dim": 16,
            },
        ),
    ],
    ids=["fpo", "refpo", "refpo-data-adaln-scaled"],
)
def test_reflow_term_gradient(reflow_coef, actor_kwargs):
    """Zero advantages and value weight: one SGD step moves the actor by -lr * reflow_coef * grad(mean CFM), the
    CFM loss being the actor's (output mode and scale), the same one the ratio uses."""
    lr = 0.1 if not actor_kwargs else 1e-4
    alg, _ = make_refpo(actor_kwargs, reflow_coef=reflow_coef, optimizer="sgd", learning_rate=lr)
    fill_storage(alg, advantages=0.0)
    tau, eps = alg.store.flat("tau").clone(), alg.store.flat("eps").clone()
    obs, actions = alg.storage.observations.flatten(0, 1).clone(), alg.storage.actions.flatten(0, 1).clone()
    reference = copy.deepcopy(alg.actor)
    reference.cfm_loss(obs, actions, tau, eps).mean().backward()
    stats = alg.update()
    assert stats["reflow"] == pytest.approx(reference.cfm_loss(obs, actions, tau, eps).mean().item(), rel=1e-5)
    for p_new, p_ref in zip(alg.actor.parameters(), reference.parameters()):
        expected = p_ref if p_ref.grad is None else p_ref - lr * reflow_coef * p_ref.grad
        torch.testing.assert_close(p_new.detach(), expected.detach(), atol=1e-6, rtol=1e-5)


def test_tau_sampling_modes():
    tau = sample_tau((200_000,), "logit_normal", 10, -1.2, 1.2, "cpu")
    # tau = 1 / (1 + exp(1.2 n - 1.2)): median at n = 0 -> 1 / (1 + e^-1.2) = 0.7685
    assert tau.median().item() == pytest.approx(1 / (1 + math.exp(-1.2)), abs=0.005)
    assert tau.min().item() >= 1e-4 and tau.max().item() <= 1.0
    grid = sample_tau((1000,), "discrete", 5, 0, 1, "cpu")
    assert set((grid * 5).round().unique().tolist()) == {0, 1, 2, 3, 4}  # the 5-step Euler grid k/5
    alg, _ = make_refpo(tau_sampling="discrete")  # the actor's 5 flow steps: tau on k/5, eps ~ N(0, I)
    tau, eps = alg.sample_pairs(1000, "cpu")
    assert tau.shape == (1000, 4) and eps.shape == (1000, 4, ACT)
    torch.testing.assert_close(tau * 5, (tau * 5).round())
    assert set((tau * 5).round().unique().tolist()) == {0, 1, 2, 3, 4}
    assert eps.mean().item() == pytest.approx(0.0, abs=0.05) and eps.std().item() == pytest.approx(1.0, abs=0.05)


def test_bound_loss_hand_worked_and_applied_to_the_predicted_action():
    assert soft_bound_loss(torch.tensor([0.5, 1.0, -1.3, 0.9]), 0.9).item() == pytest.approx((0.01 + 0.16) / 4)
    alg, _ = make_refpo(bound_coef=10.0, bound=0.0)  # bound 0: every predicted action is penalised
    fill_storage(alg, advantages=0.0)
    tau, eps = alg.store.flat("tau").clone(), alg.store.flat("eps").clone()
    obs, actions = alg.storage.observations.flatten(0, 1).clone(), alg.storage.actions.flatten(0, 1).clone()
    with torch.no_grad():
        clean = alg.actor.cfm_terms(obs, actions, tau, eps).clean_action
    assert alg.update()["bound"] == pytest.approx(clean.square().mean().item(), rel=1e-5)


def test_learning_rate_decays_exponentially_to_its_floor():
    alg, _ = make_refpo(learning_rate=1e-3, lr_decay_rate=0.5, lr_decay_floor=0.3)
    rates = []
    for _ in range(4):
        fill_storage(alg, advantages=0.0)
        alg.update()
        rates.append(alg.optimizer.param_groups[0]["lr"])
    expected = [1e-3 * max(math.exp(-0.5 * k), 0.3) for k in (1, 2, 3, 4)]  # exp(-1.5) = 0.22 < 0.3: floor
    assert rates == pytest.approx(expected)
    assert alg.save()["num_updates"] == 4


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
    old, ret = torch.tensor([0.0, 0.0]), torch.tensor([1.0, -1.0])
    values = torch.tensor([0.5, 0.1])
    # clipped values: 0.2 and 0.1 -> per-sample max of (0.25, 0.64) and (1.21, 1.21) -> mean 0.925
    assert value_regression_loss(values, old, ret, 0.2).item() == pytest.approx(0.925)
    assert value_regression_loss(values, old, ret, None).item() == pytest.approx((0.25 + 1.21) / 2)
    assert make_refpo(clip_param=0.01, value_clip_param=0.2)[0].value_clip_param == 0.2
    assert make_refpo(clip_param=0.3)[0].value_clip_param == 0.3  # default: rsl_rl's behaviour
