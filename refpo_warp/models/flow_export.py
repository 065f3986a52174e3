"""Deployment export of a FlowActor: observation normaliser (with its clamp) + network + an N-step Euler sampler.

By default the exported policy takes the observation only and integrates from zero noise: the flow's deterministic
output, which is what deployment tools that feed ``obs`` alone expect. ``noise_input=True`` adds a second input
``noise`` (the initial x_0) for stochastic use. N is fixed at export (``num_flow_steps``, default the actor's;
N = 1 is the one-step deployment the paper is about); the ONNX exporter unrolls the N steps.
"""

from __future__ import annotations

import copy

import torch
from torch import nn


class FlowSampler(nn.Module):
    """``forward(obs[, noise])`` -> actions; rsl_rl's exporters use ``get_dummy_inputs``/``input_names``."""

    is_recurrent: bool = False

    def __init__(self, actor, num_flow_steps: int | None = None, noise_input: bool = False) -> None:
        super().__init__()
        self.obs_normalizer = copy.deepcopy(actor.obs_normalizer)
        self.velocity = copy.deepcopy(actor.velocity)
        self.num_steps = int(num_flow_steps or actor.num_flow_steps)
        if self.num_steps < 1:
            raise ValueError(f"num_flow_steps must be >= 1, got {self.num_steps}")
        self.obs_dim = actor.obs_dim
        self.input_size = actor.obs_dim  # the name rsl_rl's exporters give it (mjlab's tracking export reads it)
        self.action_dim = actor.action_dim
        self.noise_input = bool(noise_input)

    def forward(self, obs: torch.Tensor, noise: torch.Tensor | None = None) -> torch.Tensor:
        x = torch.zeros(obs.shape[0], self.action_dim, device=obs.device) if noise is None else noise
        return self.velocity.integrate(self.velocity.project_obs(self.obs_normalizer(obs)), x, self.num_steps)

    @torch.jit.export
    def reset(self) -> None:
        pass

    def get_dummy_inputs(self) -> tuple[torch.Tensor, ...]:
        obs = torch.zeros(1, self.obs_dim)
        return (obs, torch.zeros(1, self.action_dim)) if self.noise_input else (obs,)

    @property
    def input_names(self) -> list[str]:
        return ["obs", "noise"] if self.noise_input else ["obs"]

    @property
    def output_names(self) -> list[str]:
        return ["actions"]
