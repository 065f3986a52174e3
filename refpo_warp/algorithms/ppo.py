"""Gaussian PPO: rsl_rl's own PPO plus Brax-style reward scaling (the paper's PPO baseline scales rewards by 10)."""

from __future__ import annotations

import torch
from rsl_rl.algorithms import PPO as RslPPO
from tensordict import TensorDict


class PPO(RslPPO):
    """rsl_rl's PPO; ``reward_scale`` multiplies the rewards it learns from (logged returns stay unscaled)."""

    def __init__(self, *args, reward_scale: float = 1.0, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.reward_scale = float(reward_scale)

    def process_env_step(
        self, obs: TensorDict, rewards: torch.Tensor, dones: torch.Tensor, extras: dict[str, torch.Tensor]
    ) -> None:
        # The runner hands the same reward tensor to its logger afterwards: scale a copy, never in place.
        super().process_env_step(obs, rewards * self.reward_scale, dones, extras)
