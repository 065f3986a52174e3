"""An exponential moving average of an actor's weights: after its warm-up, the policy that evaluation, checkpoints'
policy and export use (FPO++).

As FPO++ runs it (``ema_warmup_steps``, "updates before starting EMA"): for the first ``warmup`` updates the average
plays no part and the live weights are the policy; after update number ``warmup`` it starts from the live weights,
and after every later update ``theta_ema <- decay * theta_ema + (1 - decay) * theta``. A run shorter than its
warm-up never uses the average. Only parameters are averaged: buffers (the observation normaliser's statistics) are
copied from the live actor, as FPO++ keeps one normaliser for both. Rollouts never use the average.
"""

from __future__ import annotations

import copy

import torch
from torch import nn


class ActorEMA:
    """The averaged copy of ``actor`` (``model``) and its update rule (see the module docstring)."""

    def __init__(self, actor: nn.Module, decay: float, warmup: int) -> None:
        self.decay = float(decay)
        self.warmup = int(warmup)
        self.model = copy.deepcopy(actor).eval().requires_grad_(False)

    def started(self, num_updates: int) -> bool:
        """Whether the average is the policy after ``num_updates`` updates (else the live actor is)."""
        return num_updates >= self.warmup

    @torch.no_grad()
    def reset(self, actor: nn.Module) -> None:
        self.model.load_state_dict(actor.state_dict())

    @torch.no_grad()
    def update(self, actor: nn.Module, num_updates: int) -> None:
        """After update number ``num_updates`` (counted from 1) of ``actor``."""
        if num_updates < self.warmup:
            return
        if num_updates == self.warmup:
            self.reset(actor)
            return
        ema: list[torch.Tensor] = list(self.model.parameters())
        live = [p.detach() for p in actor.parameters()]
        torch._foreach_lerp_(ema, live, 1.0 - self.decay)
        for mine, theirs in zip(self.model.buffers(), actor.buffers()):
            mine.copy_(theirs)

    def state_dict(self) -> dict:
        return self.model.state_dict()

    def load_state_dict(self, state: dict) -> None:
        self.model.load_state_dict(state)
