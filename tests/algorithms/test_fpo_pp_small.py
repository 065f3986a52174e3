"""FPO++'s small-task recipe (configs/algo/fpo_pp_small.yaml, its Isaac cartpole): the adaptive learning rate on the
change of the predicted noise end, the kNN entropy term, the clipped value loss, one minibatch permutation for every
pass and the config itself, each against a hand-worked value or an independent implementation of FPO++'s code
(amazon-far/fpo-control, isaaclab_experiments/isaaclab_fpo/isaaclab_fpo/)."""

import math
import warnings

import pytest
import torch
from rollouts import random_rollout, small_flow_algorithm  # tests/algorithms/rollouts.py

from refpo_warp.algorithms import FPOPlusPlus
from refpo_warp.algorithms import fpo_pp as fpo_pp_module
from refpo_warp.algorithms.fpo_pp import knn_entropy, noise_end_prediction
from refpo_warp.algorithms.on_policy import Minibatch, value_regression_loss
from refpo_warp.algorithms.transition_store import minibatch_indices

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

N, T, OBS, ACT, K = 6, 3, 4, 2, 5


def make(**kwargs):
    defaults = {"num_mc_samples": K, "num_learning_epochs": 1, "num_mini_batches": 1, "max_grad_norm": 1e9}
    return small_flow_algorithm(FPOPlusPlus, N, T, OBS, ACT, **{**defaults, **kwargs})


def whole_rollout(alg) -> Minibatch:
    st = alg.storage
    rows = st.actions.flatten(0, 1).shape[0]
    return Minibatch(
        st.observations.flatten(0, 1),
        st.actions.flatten(0, 1),
        st.values.flatten(0, 1),
        st.returns.flatten(0, 1),
        st.advantages.flatten(0, 1).squeeze(-1),
        torch.arange(rows),
        alg.store,
    )


def velocity(alg, obs, actions, tau, eps):
    """(x_tau, v) straight from the velocity field, independently of the CFM terms."""
    with torch.no_grad():
        feat = alg.actor.velocity.project_obs(alg.actor.encode(obs))
        x = (1.0 - tau).unsqueeze(-1) * eps + tau.unsqueeze(-1) * actions.unsqueeze(1)
        return x, alg.actor.velocity.predict(feat, x, tau)


# ------------------------------------------------------------------------------------------- the noise-end prediction
def test_noise_end_prediction_hand_worked_in_both_conventions():
    # ours: a = (1, 2), eps = (0.5, -1), tau = 0.4, v = (0, 1): x_tau = 0.6 eps + 0.4 a = (0.7, 0.2),
    # eps_hat = x_tau - tau v = (0.7, -0.2); from e_v = v - (a - eps) = (-0.5, -2): eps - tau e_v = (0.7, -0.2)
    a, eps, tau, v = torch.tensor([1.0, 2.0]), torch.tensor([0.5, -1.0]), torch.tensor(0.4), torch.tensor([0.0, 1.0])
    e_v = v - (a - eps)
    got = noise_end_prediction(tau.reshape(1, 1), eps.reshape(1, 1, 2), e_v.reshape(1, 1, 2))
    torch.testing.assert_close(got, torch.tensor([[[0.7, -0.2]]]))
    # FPO++ (modules/actor_critic.py:194-206): t = 1 - tau = 0.6, x_t = t eps + (1 - t) a, u = -v,
    # x0_pred = x_t - t u = (0.7, 0.8), x1_pred = x0_pred + u = (0.7, -0.2)
    t, u = 1.0 - tau, -v
    x_t = t * eps + (1.0 - t) * a
    x1_pred = (x_t - t * u) + u
    torch.testing.assert_close(got.reshape(2), x1_pred)


def test_noise_end_prediction_matches_fpo_plus_plus_x1_pred_on_random_pairs():
    gen = torch.Generator().manual_seed(3)
    a, eps = torch.randn(7, 1, 3, generator=gen), torch.randn(7, 4, 3, generator=gen)
    tau, v = torch.rand(7, 4, generator=gen), torch.randn(7, 4, 3, generator=gen)
    t, u = 1.0 - tau.unsqueeze(-1), -v
    x_t = t * eps + (1.0 - t) * a
    x1_pred = (x_t - t * u) + u
    torch.testing.assert_close(noise_end_prediction(tau, eps, v - (a - eps)), x1_pred, atol=1e-6, rtol=1e-5)


def test_the_rollout_stores_the_old_noise_end_and_the_kl_is_its_mean_squared_change():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # FPO++'s proxy: no warning about the ratio's KL
        alg, _ = make(schedule="adaptive", desired_kl=0.01, adaptive_kl="noise_prediction")
    random_rollout(alg, T, N, OBS)
    alg.before_update()
    batch = whole_rollout(alg)
    tau, eps = batch.field("tau"), batch.field("eps")
    x, v = velocity(alg, batch.observations, batch.actions, tau, eps)
    torch.testing.assert_close(alg.store.flat("old_noise_prediction"), x - tau.unsqueeze(-1) * v)
    _, stats = alg.policy_loss(batch)
    assert stats["Flow/noise_prediction_kl"].item() == 0.0  # the rollout's own parameters
    # shift the head's bias by 0.1: every velocity moves by 0.1 (output_scale 1), the noise end by -0.1 tau,
    # so the proxy is 0.01 mean(tau^2) over (B, K, D)
    with torch.no_grad():
        alg.actor.velocity.head.bias += 0.1
    _, stats = alg.policy_loss(batch)
    expected = 0.01 * tau.square().mean().item()
    assert stats["Flow/noise_prediction_kl"].item() == pytest.approx(expected, rel=1e-4)
    assert alg.kl_estimate(stats) is stats["Flow/noise_prediction_kl"]


def test_by_default_the_adaptive_schedule_still_reads_the_ratio_and_stores_nothing_more():
    with pytest.warns(UserWarning, match="adaptive"):
        alg, _ = make(schedule="adaptive", desired_kl=0.01)
    assert (alg.adaptive_kl, alg.knn_entropy_coef, alg.knn_entropy_k) == ("ratio", 0.0, 1)
    random_rollout(alg, T, N, OBS)
    alg.before_update()
    assert "old_noise_prediction" not in alg.store
    _, stats = alg.policy_loss(whole_rollout(alg))
    assert "Flow/noise_prediction_kl" not in stats and "entropy" not in stats
    assert alg.kl_estimate(stats) is stats["Flow/approx_kl"]


def fpo_plus_plus_rule(lr: float, kl: float, desired: float) -> float:
    """FPO++ algorithms/fpo.py:395-399 (rsl_rl's rule and bounds)."""
    if kl > desired * 2.0:
        return max(1e-5, lr / 1.5)
    if desired / 2.0 > kl > 0.0:
        return min(1e-2, lr * 1.5)
    return lr


@pytest.mark.parametrize(
    "lr,kl,expected",
    [
        (3e-4, 0.03, 2e-4),  # above 2 x 0.01: / 1.5
        (3e-4, 0.02, 3e-4),  # at 2 x 0.01: kept
        (3e-4, 0.004, 4.5e-4),  # below 0.01 / 2: x 1.5
        (3e-4, 0.005, 3e-4),  # at 0.01 / 2: kept
        (3e-4, 0.0, 3e-4),  # no change at all: kept
        (1.2e-5, 1.0, 1e-5),  # the lower bound
        (8e-3, 1e-4, 1e-2),  # the upper bound
    ],
)
def test_adaptive_rule_steps(lr, kl, expected):
    alg, _ = make(schedule="adaptive", desired_kl=0.01, adaptive_kl="noise_prediction", learning_rate=lr)
    alg._adapt_learning_rate(torch.tensor(kl))
    assert alg.learning_rate == pytest.approx(expected) == fpo_plus_plus_rule(lr, kl, 0.01)
    assert all(group["lr"] == alg.learning_rate for group in alg.optimizer.param_groups)


def test_the_rate_adapts_once_per_minibatch_on_that_minibatch_kl():
    alg, _ = make(
        schedule="adaptive",
        desired_kl=1e-7,
        adaptive_kl="noise_prediction",
        learning_rate=1e-3,
        num_mini_batches=2,
        num_learning_epochs=3,
    )
    random_rollout(alg, T, N, OBS)
    seen, adapt = [], alg._adapt_learning_rate

    def record(kl):
        seen.append((float(kl), alg.learning_rate))
        adapt(kl)

    alg._adapt_learning_rate = record
    stats = alg.update()
    assert len(seen) == 6 and seen[0][0] == 0.0  # the first minibatch: the rollout's parameters
    lr = 1e-3
    for kl, before in seen:
        assert before == pytest.approx(lr)
        lr = fpo_plus_plus_rule(lr, kl, 1e-7)
    assert alg.learning_rate == pytest.approx(lr) and lr < 1e-3  # the changes are far above 2e-7: it went down
    assert stats["Flow/noise_prediction_kl"] == pytest.approx(sum(k for k, _ in seen) / 6, rel=1e-5)
    assert stats["learning_rate"] == pytest.approx(alg.learning_rate)  # logged: Loss/learning_rate


# ---------------------------------------------------------------------------------------------------- kNN entropy
def dense_knn_entropy(x: torch.Tensor, k: int) -> torch.Tensor:
    """FPO++'s _compute_knn_entropy (algorithms/fpo.py:601-646), written out again."""
    b, n, d = x.shape
    dists = torch.cdist(x, x, p=2) + torch.eye(n).unsqueeze(0).expand(b, -1, -1) * 1e10
    rho = torch.topk(dists, k=k, dim=2, largest=False, sorted=True).values[:, :, -1].clamp(1e-6, 1e9)
    psi_n = torch.digamma(torch.tensor(float(n)))
    psi_k = torch.digamma(torch.tensor(float(k)))
    log_cd = (d / 2) * math.log(math.pi) - float(torch.lgamma(torch.tensor(d / 2 + 1)))
    return (psi_n - psi_k + log_cd + d * torch.log(rho).mean(dim=1)).mean()


def test_knn_entropy_hand_worked():
    # 1-D samples 0, 1, 3: nearest-neighbour distances 1, 1, 2; second-nearest 3, 2, 3. c_1 = 2 (the unit "ball"
    # [-1, 1]); psi(3) - psi(1) = 1 + 1/2 = 1.5, psi(3) - psi(2) = 0.5
    x = torch.tensor([[[0.0], [1.0], [3.0]]])
    assert knn_entropy(x, 1).item() == pytest.approx(1.5 + math.log(2) + math.log(2) / 3, rel=1e-6)
    assert knn_entropy(x, 2).item() == pytest.approx(0.5 + math.log(2) + (2 * math.log(3) + math.log(2)) / 3)
    # 2-D: (0, 0), (3, 4), (0, 1): nearest distances 1, sqrt(18), 1; c_2 = pi; the mean over two rows
    y = torch.tensor([[[0.0, 0.0], [3.0, 4.0], [0.0, 1.0]]])
    h = 1.5 + math.log(math.pi) + 2 * math.log(math.sqrt(18.0)) / 3
    assert knn_entropy(y, 1).item() == pytest.approx(h, rel=1e-6)
    both = torch.cat([y, 2 * y])  # scaling by 2 adds d log 2 = 2 log 2
    assert knn_entropy(both, 1).item() == pytest.approx(h + math.log(2), rel=1e-6)


@pytest.mark.parametrize("k", [1, 3])
def test_knn_entropy_and_its_gradient_match_fpo_plus_plus_formula(k, monkeypatch):
    gen = torch.Generator().manual_seed(1)
    x = torch.randn(5, 16, 3, generator=gen, requires_grad=True)
    ours = knn_entropy(x, k)
    (grad,) = torch.autograd.grad(ours, x)
    theirs = dense_knn_entropy(x, k)
    (expected,) = torch.autograd.grad(theirs, x)
    assert ours.item() == pytest.approx(theirs.item(), rel=1e-5)
    torch.testing.assert_close(grad, expected, atol=1e-5, rtol=1e-4)
    monkeypatch.setattr(fpo_pp_module, "KNN_CHUNK_ELEMENTS", 16 * 16 * 2)  # three chunks of states: the same
    assert knn_entropy(x, k).item() == pytest.approx(ours.item(), rel=1e-6)


def test_knn_entropy_of_coincident_samples_is_finite_with_a_finite_gradient():
    x = torch.zeros(2, 4, 2, requires_grad=True)
    h = knn_entropy(x, 1)
    h.backward()
    assert math.isfinite(h.item()) and torch.isfinite(x.grad).all()


def test_the_entropy_term_is_minus_coef_times_the_estimate_of_the_predicted_actions():
    plain, _ = make()
    with_entropy, _ = make(knn_entropy_coef=0.5)  # the same parameters (rollouts.py seeds them)
    random_rollout(plain, T, N, OBS)
    random_rollout(with_entropy, T, N, OBS)
    for alg in (plain, with_entropy):
        alg.before_update()
    batch = whole_rollout(with_entropy)
    tau, eps = batch.field("tau"), batch.field("eps")
    x, v = velocity(with_entropy, batch.observations, batch.actions, tau, eps)
    predicted = x + (1.0 - tau).unsqueeze(-1) * v  # the clean end, FPO++'s x0_pred
    loss, stats = with_entropy.policy_loss(batch)
    loss_plain, _ = plain.policy_loss(whole_rollout(plain))
    assert stats["entropy"].item() == pytest.approx(dense_knn_entropy(predicted, 1).item(), rel=1e-5)
    assert loss.item() == pytest.approx(loss_plain.item() - 0.5 * stats["entropy"].item(), rel=1e-5, abs=1e-6)
    with pytest.raises(ValueError, match="knn_entropy_k=5 needs more pairs"):
        make(knn_entropy_coef=0.1, knn_entropy_k=5)


# ------------------------------------------------------------------------------------------- value loss, minibatches
def test_clipped_value_loss_clips_the_value_change_at_clip_param_as_fpo_plus_plus():
    alg, _ = make(use_clipped_value_loss=True, clip_param=0.03)
    assert alg.value_clip_param == 0.03  # null: clip_param (FPO++ algorithms/fpo.py:489-495)
    random_rollout(alg, T, N, OBS)
    batch = whole_rollout(alg)
    batch.values = batch.values - 0.1  # old values 0.1 below the critic's
    values = alg.critic(batch.observations)
    clipped = batch.values + (values - batch.values).clamp(-0.03, 0.03)
    fpo = torch.max((values - batch.returns).pow(2), (clipped - batch.returns).pow(2)).mean()
    assert alg.value_loss(batch).item() == pytest.approx(fpo.item(), rel=1e-6)
    # hand-worked: old 0, returns (1, -1), new (0.1, -0.05): max(0.81, 0.97^2) and max(0.95^2, 0.97^2)
    got = value_regression_loss(torch.tensor([0.1, -0.05]), torch.zeros(2), torch.tensor([1.0, -1.0]), 0.03)
    assert got.item() == pytest.approx(0.97**2)


def test_one_permutation_serves_every_pass_in_fpo_plus_plus_order():
    torch.manual_seed(4)
    ours = [idx.tolist() for idx in minibatch_indices(50, 4, 3, "cpu", False)]
    # FPO++ storage/rollout_storage.py:207-236: randperm(num_mini_batches * mini_batch_size), the same slices per pass
    torch.manual_seed(4)
    size = 50 // 4
    indices = torch.randperm(4 * size)
    theirs = [indices[i * size : (i + 1) * size].tolist() for _ in range(3) for i in range(4)]
    assert ours == theirs and ours[:4] == ours[4:8] == ours[8:]
    torch.manual_seed(4)
    reshuffled = [idx.tolist() for idx in minibatch_indices(50, 4, 3, "cpu", True)]
    assert reshuffled[:4] == ours[:4] and reshuffled[4:8] != ours[4:8]


# ---------------------------------------------------------------------------------------------------- the config
def test_fpo_pp_small_keeps_its_own_values_over_the_cpu_profile_of_fpo_pp():
    from refpo_warp.config.resolve import resolve_config

    small = resolve_config(["task=dmc_point_mass", "algo=fpo_pp_small", "device=cpu"])
    algorithm, actor = small["algorithm"], small["actor"]
    assert algorithm["class_name"] == "refpo_warp.algorithms:FPOPlusPlus"
    assert (algorithm["learning_rate"], algorithm["num_learning_epochs"], algorithm["num_mini_batches"]) == (3e-4, 5, 4)
    assert (algorithm["schedule"], algorithm["desired_kl"], algorithm["adaptive_kl"]) == (
        "adaptive",
        0.01,
        "noise_prediction",
    )
    assert (algorithm["clip_param"], algorithm["num_mc_samples"], algorithm["knn_entropy_coef"]) == (0.03, 256, 0.005)
    assert (algorithm["use_clipped_value_loss"], algorithm["value_clip_param"]) == (True, None)
    assert (algorithm["reshuffle_each_epoch"], algorithm["joint_grad_clip"], algorithm["max_grad_norm"]) == (
        False,
        True,
        1.0,
    )
    assert (actor["obs_normalization"], small["critic"]["obs_normalization"]) == (False, False)
    assert (actor["output_scale"], actor["action_noise_std"]) == (1.0, 0.02)
    tuned = resolve_config(["task=dmc_point_mass", "algo=fpo_pp", "device=cpu"])  # fpo_pp's own profile is kept
    assert (tuned["algorithm"]["learning_rate"], tuned["actor"]["output_scale"]) == (0.001471564467474972, 0.5)
