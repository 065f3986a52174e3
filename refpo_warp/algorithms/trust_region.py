"""The trust regions of the ratio surrogate (losses to minimise), for a ratio rho per action (B,) or per (action, pair)
(B, K), with the advantage A (B,) broadcast over the pairs:

- ``ppo``: PPO's clip, -min(rho A, clip(rho, 1 - e, 1 + e) A) (FPO's and ReFPO's);
- ``spo``: SPO's quadratic penalty, -(rho A - |A| / (2 e) (rho - 1)^2), whose optimum for one sample sits at
  rho = 1 + e sign(A) and whose gradient pulls rho back beyond it instead of vanishing;
- ``aspo``: FPO++'s asymmetric choice, PPO's clip where A > 0 and SPO's penalty where A <= 0 (the negative-advantage
  samples are the ones that push a flow's CFM loss up without a bound under PPO's clip).

The loss is the mean over every sample (and pair).
"""

from __future__ import annotations

from enum import Enum

import torch


class TrustRegion(str, Enum):
    PPO = "ppo"  # PPO's clip
    SPO = "spo"  # SPO's quadratic penalty
    ASPO = "aspo"  # FPO++: the clip where A > 0, the penalty otherwise


def ppo_clip(ratio: torch.Tensor, adv: torch.Tensor, clip: float) -> torch.Tensor:
    return torch.max(-adv * ratio, -adv * ratio.clamp(1.0 - clip, 1.0 + clip))


def spo_penalty(ratio: torch.Tensor, adv: torch.Tensor, clip: float) -> torch.Tensor:
    return -(ratio * adv - adv.abs() / (2.0 * clip) * (ratio - 1.0).square())


def surrogate(ratio: torch.Tensor, advantages: torch.Tensor, clip: float, trust_region: str = "ppo") -> torch.Tensor:
    """The mean surrogate loss of ``ratio`` under ``trust_region`` (see the module docstring)."""
    adv = advantages.reshape(-1, *([1] * (ratio.dim() - 1)))
    if trust_region == "ppo":
        return ppo_clip(ratio, adv, clip).mean()
    if trust_region == "spo":
        return spo_penalty(ratio, adv, clip).mean()
    if trust_region == "aspo":
        return torch.where(adv > 0, ppo_clip(ratio, adv, clip), spo_penalty(ratio, adv, clip)).mean()
    raise ValueError(f"trust_region must be one of {[t.value for t in TrustRegion]}, got '{trust_region}'")
