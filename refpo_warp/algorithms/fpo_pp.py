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
"""

from __future__ import annotations

import dataclasses
import math
from enum import Enum

import torch

from refpo_warp.algorithms.on_policy import Minibatch
from refpo_warp.algorithms.refpo import ReFPO
from refpo_warp.utils.option_rules import OneOf, Real
from refpo_warp.utils.options import option


class CfmReduction(str, Enum):
    MEAN = "mean"  # the mean over action dimensions (ReFPO's)
    SQRT_DIM = "sqrt_dim"  # the sum over them / sqrt(D) (FPO++'s "sqrt")


def straight_through_max(x: torch.Tensor, cap: float) -> torch.Tensor:
    """min(x, cap) in the forward pass; the gradient of x in the backward pass (FPO++'s ``clamp_ste``)."""
    return x + (x.clamp(max=cap) - x).detach()


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

    def cfm_losses(self, obs, actions, tau, eps):
        loss, terms = super().cfm_losses(obs, actions, tau, eps)
        if self.cfm_reduction == "sqrt_dim":  # sum_d / sqrt(D) = sqrt(D) * mean_d
            loss = loss * math.sqrt(actions.shape[-1])
        return loss, terms

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
