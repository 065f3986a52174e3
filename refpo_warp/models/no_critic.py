"""NoCritic: the critic slot of rsl_rl's PPO machinery for algorithms without a value network (Flow-GRPO).

It has no parameters and predicts a value of 0 for every observation, so rsl_rl's storage, time-out bootstrapping
(gamma * V = 0) and checkpoints work unchanged while nothing is learned or stored for it.
"""

from __future__ import annotations

import torch
from tensordict import TensorDict
from torch import nn

from refpo_warp.models.stateless import Stateless


class NoCritic(Stateless, nn.Module):
    """A parameter-free critic with rsl_rl's model constructor and protocol; always 0."""

    def __init__(self, obs: TensorDict, obs_groups: dict[str, list[str]], obs_set: str, output_dim: int) -> None:
        super().__init__()
        self.output_dim = int(output_dim)

    def forward(self, obs: TensorDict, masks=None, hidden_state=None, stochastic_output: bool = False) -> torch.Tensor:
        first = next(iter(obs.values()))
        return torch.zeros(first.shape[0], self.output_dim, device=first.device)

    def update_normalization(self, obs: TensorDict) -> None:
        pass
