"""ReinFlow: PPO on the normalised log-likelihood of a flow policy's noisy Euler chain (Zhang et al. 2025).

The actor (``refpo_warp.models:ReinFlowActor``) samples the chain x_0..x_K with learned exploration noise and gives
its normalised log-probability and entropy. The rollout stores the chain and its log-probability in the algorithm's
``TransitionStore``; each minibatch teacher-forces the stored chain under the current parameters and minimises

    -min(rho A, clip(rho, 1 - e, 1 + e) A) - entropy_coef * H + value_loss_coef * L_value,
    rho = exp(clamp(log pi_new) - clamp(log pi_old))

with A the GAE advantage normalised per minibatch (``ppoflow.py``), the log-probabilities clamped to ``logprob_clip``
(ReinFlow's gym configs: [-1, 1]), PPO clip 0.1, entropy 0.05 and value coefficient 0.3 (ReinFlow's 0.5 MSE x 0.6;
rsl_rl's value loss has no 0.5) from the ReFPO paper's table (d). Action chunks (table (d): 4) come from the env
option ``action_chunk`` (``refpo_warp.envs.action_chunk``): the actor's action is the whole chunk.

``noise_decay_updates`` turns on ReinFlow's ``learn_decay`` bound: sigma_max is held for ``noise_hold_ratio`` of that
many updates, then decays by a cosine to sigma_min + ``noise_decay_ratio`` (sigma_max - sigma_min). Off by default:
the table's noise scheduler is "Linear", not ``learn_decay``.
"""

from __future__ import annotations

import math
import warnings

import torch
from tensordict import TensorDict
from torch import nn

from refpo_warp.algorithms.on_policy import Minibatch, OnPolicyAlgorithm
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Check, Int, ListOf, Real
from refpo_warp.utils.options import option


def decayed_sigma_max(
    update: int, total: int, sigma_min: float, sigma_max: float, hold_ratio: float, decay_ratio: float
) -> float:
    """ReinFlow's ``learn_decay`` upper bound after ``update`` of ``total`` updates (see the module docstring)."""
    floor = sigma_min + decay_ratio * (sigma_max - sigma_min)
    hold = hold_ratio * total
    if update <= hold:
        return sigma_max
    progress = min(1.0, (update - hold) / max(total - hold, 1e-9))
    return floor + 0.5 * (sigma_max - floor) * (1.0 + math.cos(math.pi * progress))


def log_prob_range(key: str, value) -> list[float]:
    low, high = ListOf(Real(-1e6, 1e6), min_len=2, max_len=2).check(key, value)
    if low >= high:
        raise ConfigError(f"{key}={value} is invalid: the minimum must be below the maximum")
    return [low, high]


class ReinFlow(OnPolicyAlgorithm):
    """ReinFlow on rsl_rl's PPO machinery (see the module docstring); defaults from the ReFPO paper's table (d)."""

    # Options (refpo_warp/utils/options.py), besides the shared ones (OnPolicyAlgorithm) and rsl_rl's PPO arguments.
    logprob_clip: tuple[float, float] | None = option(
        (-1.0, 1.0),
        Check(log_prob_range, "null or [min, max] with min < max", optional=True),
        "[min, max] clamp of the old and new normalised log-probabilities; null: no clamp",
    )
    noise_decay_updates: int | None = option(
        None, Int(1, None, optional=True), "updates over which the noise bound decays; null: constant bounds"
    )
    noise_hold_ratio: float = option(0.35, Real(0, 1), "ReinFlow's hold fraction of the decay")
    noise_decay_ratio: float = option(0.7, Real(0, 1), "ReinFlow's decayed-bound ratio")
    explosion_threshold: float = option(
        3.0, Real(0, None, lo_open=True), "|log rho| above which a sample counts in Flow/explosion_rate"
    )
    clip_param: float = option(0.1, doc="PPO clip range (table (d))")
    entropy_coef: float = option(0.05, doc="entropy bonus (table (d))")
    value_loss_coef: float = option(0.3, doc="value loss weight (table (d))")
    learning_rate: float = option(3e-5, doc="learning rate (table (d))")
    gamma: float = option(0.99, doc="discount (table (d))")
    lam: float = option(0.95, doc="GAE lambda (table (d))")
    schedule: str = option("fixed", doc="learning-rate schedule (rsl_rl's default: adaptive)")
    use_clipped_value_loss: bool = option(False, doc="PPO's clipped value loss (rsl_rl's default: true)")
    normalize_advantage_per_mini_batch: bool = option(True, doc="normalise advantages per minibatch (ReinFlow's)")

    def check_actor(self, actor: nn.Module) -> None:
        if not (hasattr(actor, "sample_chain") and hasattr(actor, "chain_log_prob")):
            raise TypeError(
                "ReinFlow needs a noisy-chain actor; set actor.class_name to refpo_warp.models:ReinFlowActor"
            )

    def __init__(self, actor: nn.Module, critic: nn.Module, storage, **kwargs) -> None:
        super().__init__(actor, critic, storage, **kwargs)
        if self.bound_coef > 0:
            warnings.warn("ReinFlow ignores bound_coef: its chain already clamps the action to [-1, 1].")
        self.initial_sigma_max = float(actor.get_buffer("sigma_max"))

    # ---------------------------------------------------------------------------------------------- rollout
    def act(self, obs: TensorDict) -> torch.Tensor:
        chain, log_prob = self.actor.sample_chain(obs)
        self.store.write(self.storage.step, chain=chain, old_log_prob=log_prob)
        t = self.transition
        t.actions = chain[:, -1]
        t.values = self.critic(obs).detach()
        t.actions_log_prob = log_prob
        t.distribution_params = ()
        t.observations = obs
        return t.actions

    # ---------------------------------------------------------------------------------------------- update
    def clamp_log_prob(self, log_prob: torch.Tensor) -> torch.Tensor:
        return log_prob if self.logprob_clip is None else log_prob.clamp(*self.logprob_clip)

    def policy_loss(self, batch: Minibatch) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        log_prob, entropy, std = self.actor.chain_log_prob(batch.observations, batch.field("chain"), with_entropy=True)
        log_ratio = self.clamp_log_prob(log_prob) - self.clamp_log_prob(batch.field("old_log_prob"))
        ratio = torch.exp(log_ratio)
        adv = batch.advantages
        surrogate = torch.max(-adv * ratio, -adv * ratio.clamp(1.0 - self.clip_param, 1.0 + self.clip_param)).mean()
        entropy = entropy.mean()
        loss = surrogate - self.entropy_coef * entropy
        with torch.no_grad():
            stats = {
                "Flow/ratio_mean": ratio.mean(),
                "Flow/ratio_max": ratio.max(),
                "Flow/clip_fraction": ((ratio - 1.0).abs() > self.clip_param).float().mean(),
                "Flow/explosion_rate": (log_ratio.abs() > self.explosion_threshold).float().mean(),
                "Flow/approx_kl": ((ratio - 1.0) - log_ratio).mean(),
                "Flow/noise_std": std.detach(),
            }
        stats.update(surrogate=surrogate, entropy=entropy)
        return loss, stats

    def kl_estimate(self, stats: dict[str, torch.Tensor]) -> torch.Tensor | None:
        return stats.get("Flow/approx_kl")

    def update(self) -> dict[str, float]:
        out = super().update()
        if self.noise_decay_updates is not None:
            value = decayed_sigma_max(
                self.num_updates,
                self.noise_decay_updates,
                self.actor.sigma_min,
                self.initial_sigma_max,
                self.noise_hold_ratio,
                self.noise_decay_ratio,
            )
            self.actor.sigma_max.fill_(value)
        out["Flow/sigma_max"] = float(self.actor.sigma_max)
        return out
