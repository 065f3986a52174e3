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
Rollouts add FPO++'s 0.02 perturbation to the sampled action (the actor's ``action_noise_std``, set in
``configs/algo/fpo_pp.yaml``) and evaluation and export use an EMA of the actor (decay 0.95, restarted after 500
updates). Every difference from FPO and from FPO++'s code: ``docs/algorithms.md``, "FPO++".
"""

from __future__ import annotations

import dataclasses
import math

import torch

from refpo_warp.algorithms.on_policy import Minibatch
from refpo_warp.algorithms.refpo import ReFPO
from refpo_warp.utils.option_rules import OneOf, Real

CFM_REDUCTIONS = ("mean", "sqrt_dim")


def straight_through_max(x: torch.Tensor, cap: float) -> torch.Tensor:
    """min(x, cap) in the forward pass; the gradient of x in the backward pass (FPO++'s ``clamp_ste``)."""
    return x + (x.clamp(max=cap) - x).detach()


class FPOPlusPlus(ReFPO):
    """FPO++ on ReFPO's machinery; its defaults are FPO++'s algorithm (module docstring).

    Args (besides ReFPO's, whose defaults change to FPO++'s: ``reflow_coef`` 0, ``ratio_mode`` per_sample,
    ``trust_region`` aspo, ``tau_sampling`` uniform_inset, ``output_mode`` u, ``ema_decay`` 0.95):
        cfm_reduction: ``"sqrt_dim"`` (sum over action dimensions / sqrt(D), FPO++) or ``"mean"`` (ReFPO's).
        loss_cap: Cap on the old and new CFM losses of the ratio (None: none).
        negative_advantage_loss_cap: Cap on the new CFM loss where A < 0 (None: none).
        log_ratio_cap: Straight-through upper cap on each pair's log-ratio (None: none).
        advantage_clip: Clamp of the normalised advantages to [-c, c] (None: none).
    """

    option_rules = {  # valid values, checked by the config resolver and the constructor (refpo_warp.utils.option_rules)
        "cfm_reduction": OneOf(CFM_REDUCTIONS),
        "loss_cap": Real(0, None, lo_open=True, optional=True),
        "negative_advantage_loss_cap": Real(0, None, lo_open=True, optional=True),
        "log_ratio_cap": Real(0, None, lo_open=True, optional=True),
        "advantage_clip": Real(0, None, lo_open=True, optional=True),
    }

    def __init__(
        self,
        actor,
        critic,
        storage,
        cfm_reduction: str = "sqrt_dim",
        loss_cap: float | None = 20.0,
        negative_advantage_loss_cap: float | None = 20.0,
        log_ratio_cap: float | None = 10.0,
        advantage_clip: float | None = 100.0,
        reflow_coef: float = 0.0,
        ratio_mode: str = "per_sample",
        trust_region: str = "aspo",
        tau_sampling: str = "uniform_inset",
        output_mode: str | None = "u",
        ema_decay: float | None = 0.95,
        **kwargs,
    ) -> None:
        super().__init__(actor, critic, storage, reflow_coef=reflow_coef, ratio_mode=ratio_mode,
                         trust_region=trust_region, tau_sampling=tau_sampling, output_mode=output_mode,
                         ema_decay=ema_decay, **kwargs)  # fmt: skip
        self.cfm_reduction = cfm_reduction
        self.loss_cap = None if loss_cap is None else float(loss_cap)
        self.negative_advantage_loss_cap = None if negative_advantage_loss_cap is None else float(negative_advantage_loss_cap)
        self.log_ratio_cap = None if log_ratio_cap is None else float(log_ratio_cap)
        self.advantage_clip = None if advantage_clip is None else float(advantage_clip)

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
            batch = dataclasses.replace(batch, advantages=batch.advantages.clamp(-self.advantage_clip,
                                                                                 self.advantage_clip))  # fmt: skip
        return super().policy_loss(batch)
