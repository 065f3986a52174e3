"""FPO++ (Flow Policy Gradients for Robot Control, arXiv 2602.02481): FPO with a ratio per (tau, eps) pair, capped CFM
losses, a straight-through cap on the log-ratio and an asymmetric trust region; with ``reflow_coef > 0`` it is ReFPO
on FPO++ (``algo=refpo_pp``).

Per action a with stored pairs (tau_k, eps_k) and CFM losses L_k = sum_d (v_d - (a - eps_k)_d)^2 / sqrt(D) (FPO++'s
"sqrt" reduction: sqrt(D) times ReFPO's mean over the D action dimensions):

    L_old,k <- min(L_old,k, loss_cap),  L_new,k <- min(L_new,k, loss_cap)       (both, and again where A < 0 with
                                                                               negative_advantage_loss_cap)
    delta_k = L_old,k - L_new,k,  forward min(delta_k, log_ratio_cap), gradient of delta_k (straight through)
    rho_k   = exp(delta_k);  loss = mean_k aspo(rho_k, A) + c_v L_value + reflow_coef * mean_k L_new,k (uncapped)

with A the GAE advantage normalised over the whole rollout and clamped to +-advantage_clip, and ``aspo`` PPO's clip
for A > 0 and SPO's penalty otherwise (``refpo_warp.algorithms.trust_region``). The Reflow term keeps ReFPO's
definition (the mean CFM loss of the current parameters on the same pairs), in the same sqrt(D)-reduced units as the
ratio, so lambda weighs it against the surrogate as in ReFPO; uncapped, because the caps only guard the ratio.
Rollouts add FPO++'s 0.02 perturbation to the sampled action (the actor's ``action_noise_std``); after 500 updates
evaluation and export use an EMA of the actor (decay 0.95), before them the live actor, as FPO++ does. FPO++'s other
values (64 Euler steps, 16 pairs, AdamW, ...) are in ``configs/algo/fpo_pp.yaml``, each with its place in FPO++'s
code. Every difference from FPO and from FPO++'s code: ``docs/algorithms.md``, "FPO++".

Two pieces of FPO++'s small-task recipe (its Isaac cartpole, ``configs/algo/fpo_pp_small.yaml``), off by default:

- ``adaptive_kl: noise_prediction``: rsl_rl's adaptive learning rate (``schedule: adaptive``, ``desired_kl``) driven,
  as in FPO++ (``algorithms/fpo.py:383-409``, ``modules/actor_critic.py:205-206``), by the squared change of each
  pair's prediction of the NOISE end of its path from the rollout parameters' prediction, per minibatch::

      eps_hat = x_tau - tau v = eps - tau e_v       (FPO++'s x1_pred = x_t + (1 - t) u, with t = 1 - tau and u = -v)
      kl      = mean over (B, K, D) of (eps_hat_new - eps_hat_old)^2 = mean tau^2 (v_new - v_old)^2

- ``knn_entropy_coef``: minus coef times FPO++'s Kozachenko-Leonenko entropy estimate of the actions the K pairs of a
  state predict (the clean ends a_hat = x_tau + (1 - tau) v; FPO++'s x0_pred, ``algorithms/fpo.py:374-380, 601-646``).
"""

from __future__ import annotations

import dataclasses
import math
from enum import Enum

import torch
from tensordict import TensorDict

from refpo_warp.algorithms.on_policy import Minibatch
from refpo_warp.algorithms.refpo import ReFPO
from refpo_warp.models.flow_actor import CfmTerms
from refpo_warp.utils.option_rules import Int, OneOf, Real
from refpo_warp.utils.options import option


class CfmReduction(str, Enum):
    MEAN = "mean"  # the mean over action dimensions (ReFPO's)
    SQRT_DIM = "sqrt_dim"  # the sum over them / sqrt(D) (FPO++'s "sqrt")


class AdaptiveKl(str, Enum):
    RATIO = "ratio"  # the proxy ratio's E[(rho - 1) - log rho] (ReFPO's)
    NOISE_PREDICTION = "noise_prediction"  # the change of the predicted noise end (FPO++'s)


# The neighbour search's distance matrices, in elements per chunk of states: 2M floats (8 MB) stay in a CPU's
# cache, where 16M ran 2-3x slower (docs/algorithms.md, "FPO++").
KNN_CHUNK_ELEMENTS = 1 << 21


def straight_through_max(x: torch.Tensor, cap: float) -> torch.Tensor:
    """min(x, cap) in the forward pass; the gradient of x in the backward pass (FPO++'s ``clamp_ste``)."""
    return x + (x.clamp(max=cap) - x).detach()


def noise_end_prediction(tau: torch.Tensor, eps: torch.Tensor, velocity_residual: torch.Tensor) -> torch.Tensor:
    """The noise end each pair's velocity points back to, eps_hat = x_tau - tau v (B, K, A), from tau (B, K), eps and
    e_v = v - (a - eps) (B, K, A): x_tau - tau v = (1 - tau) eps + tau a - tau (e_v + a - eps) = eps - tau e_v. FPO++'s
    ``x1_pred`` (t = 1 - tau is its noise end; ``modules/actor_critic.py:205-206``)."""
    return eps - tau.unsqueeze(-1) * velocity_residual


def knn_entropy(samples: torch.Tensor, k: int = 1) -> torch.Tensor:
    """FPO++'s Kozachenko-Leonenko entropy estimate (``algorithms/fpo.py:601-646``) of each row's n samples in R^d,
    averaged over the rows: with rho_i the distance from sample i to its k-th nearest other sample (clamped to
    [1e-6, 1e9]) and c_d = pi^(d/2) / Gamma(d/2 + 1) the volume of the unit ball,

        H = psi(n) - psi(k) + log c_d + d * mean_i log rho_i              samples (B, n, d), 1 <= k < n

    The neighbours are found without gradient, in chunks of states, by exact squared distances (summed one dimension
    at a time: the same order as the distances, 0.27-0.43 times ``torch.cdist``'s time at 1-2 action dimensions); the
    gradient flows through the distances to them, as through FPO++'s ``torch.cdist``."""
    b, n, d = samples.shape
    if not 1 <= k < n:
        raise ValueError(f"the kNN entropy needs 1 <= k < n samples, got k={k}, n={n}")
    with torch.no_grad():
        step = max(1, KNN_CHUNK_ELEMENTS // (n * n))
        found = []
        for i in range(0, b, step):
            x = samples[i : i + step].detach()
            squared = (x[..., 0].unsqueeze(-1) - x[..., 0].unsqueeze(-2)).square_()
            for j in range(1, d):
                squared.add_((x[..., j].unsqueeze(-1) - x[..., j].unsqueeze(-2)).square_())
            squared.diagonal(dim1=-2, dim2=-1).fill_(math.inf)  # not its own neighbour
            if k == 1:
                found.append(squared.argmin(dim=-1))
            else:
                found.append(squared.topk(k, dim=-1, largest=False).indices[..., -1])
        neighbour = torch.cat(found)
    other = torch.gather(samples, 1, neighbour.unsqueeze(-1).expand(-1, -1, d))
    rho = torch.linalg.vector_norm(samples - other, dim=-1).clamp(1e-6, 1e9)
    digamma = torch.special.digamma(torch.tensor([float(n), float(k)], dtype=torch.float64))
    log_unit_ball = (d / 2) * math.log(math.pi) - math.lgamma(d / 2 + 1)
    return float(digamma[0] - digamma[1]) + log_unit_ball + d * rho.log().mean()


class FPOPlusPlus(ReFPO):
    """FPO++ on ReFPO's machinery; its defaults are FPO++'s algorithm (module docstring)."""

    # Options (refpo_warp/utils/options.py): FPO++'s own, and its defaults for ReFPO's.
    cfm_reduction: str = option(
        "sqrt_dim",
        OneOf(CfmReduction),
        "sqrt_dim: the CFM loss summed over action dimensions / sqrt(D) (FPO++); mean: ReFPO's mean over them",
    )
    loss_cap: float | None = option(
        20.0,
        Real(0, None, lo_open=True, optional=True),
        "cap on the old and new CFM losses of the ratio (FPO++: 20); null: none",
    )
    negative_advantage_loss_cap: float | None = option(
        20.0,
        Real(0, None, lo_open=True, optional=True),
        "cap on the new CFM loss where A < 0 (FPO++: 20); null: none",
    )
    log_ratio_cap: float | None = option(
        10.0,
        Real(0, None, lo_open=True, optional=True),
        "straight-through upper cap on each pair's log-ratio (FPO++: 10); null: none",
    )
    advantage_clip: float | None = option(
        100.0,
        Real(0, None, lo_open=True, optional=True),
        "clamp of the normalised advantages to [-c, c] (FPO++: 100); null: none",
    )
    reflow_coef: float = option(0.0, doc="lambda; 0 is FPO++, > 0 ReFPO on FPO++ (algo=refpo_pp: 0.04)")
    ratio_mode: str = option("per_sample", doc="one ratio per (tau, eps) pair (FPO++)")
    trust_region: str = option("aspo", doc="PPO's clip for A > 0, SPO's penalty otherwise (FPO++)")
    tau_sampling: str = option("uniform_inset", doc="flow times U[0.005, 0.995] (FPO++)")
    output_mode: str | None = option("u", doc="velocity regression (FPO++ hard-codes it)")
    ema_decay: float | None = option(
        0.95, doc="the EMA actor that evaluation and export use after its warm-up (FPO++: 0.95)"
    )
    adaptive_kl: str = option(
        "ratio",
        OneOf(AdaptiveKl),
        "what schedule=adaptive reads per minibatch: ratio, the proxy ratio's KL estimate; noise_prediction, FPO++'s "
        "mean squared change of the predicted noise end x_tau - tau v (algorithms/fpo.py:383-409; its cartpole)",
    )
    knn_entropy_coef: float = option(
        0.0,
        Real(0, 1e6),
        "weight of minus FPO++'s kNN entropy estimate of the actions a state's pairs predict (algorithms/fpo.py:"
        "374-380; its cartpole: 0.005); 0: off",
    )
    knn_entropy_k: int = option(
        1, Int(1, 1023), "the k of that estimate, below num_mc_samples (FPO++ rl_cfg.py:160 knn_entropy_k = 1)"
    )

    def __init__(self, actor, critic, storage, **kwargs) -> None:
        super().__init__(actor, critic, storage, **kwargs)
        if self.knn_entropy_coef > 0 and self.knn_entropy_k >= self.num_mc_samples:
            raise ValueError(
                f"knn_entropy_k={self.knn_entropy_k} needs more pairs per action: num_mc_samples="
                f"{self.num_mc_samples} (the k-th nearest of the other pairs' predicted actions)"
            )

    def kl_from_ratio(self) -> bool:
        return self.adaptive_kl == "ratio"

    def noise_prediction_kl(self) -> bool:
        """Whether the adaptive schedule runs on FPO++'s noise-end prediction (its old values are then stored)."""
        return self.schedule == "adaptive" and self.adaptive_kl == "noise_prediction"

    def cfm_losses(self, obs, actions, tau, eps):
        loss, terms = super().cfm_losses(obs, actions, tau, eps)
        if self.cfm_reduction == "sqrt_dim":  # sum_d / sqrt(D) = sqrt(D) * mean_d
            loss = loss * math.sqrt(actions.shape[-1])
        return loss, terms

    def old_pair_values(
        self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor
    ) -> dict[str, torch.Tensor]:
        if not self.noise_prediction_kl():
            return super().old_pair_values(obs, actions, tau, eps)
        loss, terms = self.cfm_losses(obs, actions, tau, eps)
        assert terms.velocity_residual is not None
        return {"old_loss": loss, "old_noise_prediction": noise_end_prediction(tau, eps, terms.velocity_residual)}

    def pair_terms_loss(
        self, batch: Minibatch, tau: torch.Tensor, eps: torch.Tensor, terms: CfmTerms
    ) -> tuple[torch.Tensor | None, dict[str, torch.Tensor]]:
        loss, stats = None, {}
        if self.knn_entropy_coef > 0:
            stats["entropy"] = knn_entropy(terms.clean_action, self.knn_entropy_k)
            loss = -self.knn_entropy_coef * stats["entropy"]
        if self.noise_prediction_kl():
            assert terms.velocity_residual is not None
            with torch.no_grad():
                new = noise_end_prediction(tau, eps, terms.velocity_residual)
                change = new - batch.field("old_noise_prediction")
                stats["Flow/noise_prediction_kl"] = change.square().mean()
        return loss, stats

    def kl_estimate(self, stats: dict[str, torch.Tensor]) -> torch.Tensor | None:
        if self.adaptive_kl == "noise_prediction":
            return stats.get("Flow/noise_prediction_kl")
        return super().kl_estimate(stats)

    def pair_log_ratios(self, old_loss, new_loss, advantages=None):
        if self.loss_cap is not None:
            old_loss = old_loss.clamp(max=self.loss_cap)
            new_loss = new_loss.clamp(max=self.loss_cap)
        if self.negative_advantage_loss_cap is not None and advantages is not None:
            negative = (advantages < 0).reshape(-1, *([1] * (new_loss.dim() - 1)))
            new_loss = torch.where(negative, new_loss.clamp(max=self.negative_advantage_loss_cap), new_loss)
        diff = super().pair_log_ratios(old_loss, new_loss, advantages)
        return diff if self.log_ratio_cap is None else straight_through_max(diff, self.log_ratio_cap)

    def policy_loss(self, batch: Minibatch):
        if self.advantage_clip is not None:
            batch = dataclasses.replace(
                batch, advantages=batch.advantages.clamp(-self.advantage_clip, self.advantage_clip)
            )
        return super().policy_loss(batch)
