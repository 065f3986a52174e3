"""Advantage-weighted ReFPO: the Reflow term applied to positive-advantage samples (paper §4.2, "ReFPO,
Trajectory-advantage-weighted"; the paper gives no formula, so the weighting is our choice).

Everything is ReFPO (``refpo_warp.algorithms.refpo``) except the Reflow term. With l_i = (1/K) sum_k L_new,ik the
per-action CFM loss on the stored pairs and A_i the advantage the surrogate uses (normalised GAE):

- ``positive`` (default): sum_i 1[A_i > 0] l_i / max(1, #{A_i > 0}), the mean over positive-advantage actions, so
  lambda keeps the scale it has for the un-weighted term (which it equals when every A_i > 0);
- ``softplus``: weights softplus(A_i) / mean_j softplus(A_j) (the FPO GridWorld ``positive_advantage`` transform);
- ``relu``: weights max(A_i, 0) / mean_j max(A_j, 0) (0 when no advantage is positive);
- ``trajectory``: the ``positive`` mask on a trajectory advantage instead of A_i: the learning rewards of the env's
  episode segment inside the rollout window, summed, minus their mean over the batch's transitions, broadcast to
  every step of the segment (the literal reading of "trajectory-advantage").
"""

from __future__ import annotations

from enum import Enum

import torch
import torch.nn.functional as F

from refpo_warp.algorithms.on_policy import Minibatch
from refpo_warp.algorithms.refpo import ReFPO
from refpo_warp.utils.option_rules import OneOf
from refpo_warp.utils.options import choices, option


class ReflowWeighting(str, Enum):
    POSITIVE = "positive"  # the mean over positive-advantage actions
    SOFTPLUS = "softplus"  # weights softplus(A) / mean softplus(A)
    RELU = "relu"  # weights max(A, 0) / mean max(A, 0)
    TRAJECTORY = "trajectory"  # the positive mask on the episode segment's advantage


def weighted_reflow(per_action_loss: torch.Tensor, advantages: torch.Tensor, weighting: str) -> torch.Tensor:
    """The weighted Reflow term of (B,) per-action CFM losses (see the module docstring; ``trajectory`` uses the
    ``positive`` rule on the trajectory advantages it is given)."""
    if weighting in ("positive", "trajectory"):
        mask = (advantages > 0).to(per_action_loss.dtype)
        return (mask * per_action_loss).sum() / mask.sum().clamp(min=1.0)
    if weighting == "softplus":
        weights = F.softplus(advantages)
    elif weighting == "relu":
        weights = advantages.clamp(min=0.0)
    else:
        raise ValueError(f"reflow_weighting must be one of {choices(ReflowWeighting)}, got '{weighting}'")
    return (weights * per_action_loss).sum() / weights.sum().clamp(min=1e-12)


def segment_returns(rewards: torch.Tensor, dones: torch.Tensor) -> torch.Tensor:
    """For (T, E) rewards and dones: at every step, the sum of the rewards of its episode segment in the window."""
    ended = dones.float()
    after = torch.empty_like(rewards)  # from t to the segment's end
    running = torch.zeros_like(rewards[0])
    for t in reversed(range(rewards.shape[0])):
        running = rewards[t] + (1.0 - ended[t]) * running
        after[t] = running
    before = torch.empty_like(rewards)  # from the segment's start to t
    running = torch.zeros_like(rewards[0])
    for t in range(rewards.shape[0]):
        running = rewards[t] + running
        before[t] = running
        running = running * (1.0 - ended[t])
    return before + after - rewards


class AdvantageWeightedReFPO(ReFPO):
    """ReFPO with the Reflow term weighted by the advantage (``reflow_weighting``, see the module docstring)."""

    reflow_weighting: str = option(
        "positive",
        OneOf(ReflowWeighting),
        "which actions' CFM loss the Reflow term weights, and how (module docstring)",
    )

    def before_update(self, chunk: int = 65536) -> None:
        super().before_update(chunk)
        if self.reflow_weighting == "trajectory":
            st = self.storage
            totals = segment_returns(st.rewards.squeeze(-1), st.dones.squeeze(-1))
            self.store.write_all(trajectory_advantage=(totals - totals.mean()).flatten())

    def reflow_loss(self, new_loss: torch.Tensor, batch: Minibatch) -> torch.Tensor:
        advantages = batch.field("trajectory_advantage") if self.reflow_weighting == "trajectory" else batch.advantages
        return weighted_reflow(new_loss.mean(dim=-1), advantages, self.reflow_weighting)
