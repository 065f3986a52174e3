"""Per-transition tensors an algorithm owns, kept beside rsl_rl's ``RolloutStorage`` and drawn in the same minibatches.

rsl_rl's storage holds what every on-policy method needs (observations, actions, rewards, values, returns,
advantages). What is particular to one method lives here under names that method chooses: ReFPO's stored
(tau, eps) pairs and old CFM losses, Flow-GRPO's and ReinFlow's denoising chains and old log-probabilities, Gaussian
PPO's old log-probabilities and distribution parameters. Rows are (step, env) like rsl_rl's buffers; a field is
allocated on its first write, from the shape of the tensor written.
"""

from __future__ import annotations

from collections.abc import Iterator

import torch


class TransitionStore:
    """Named tensors of shape (num_steps, num_envs, ...) written one step at a time."""

    def __init__(self, num_steps: int, num_envs: int, device: str | torch.device) -> None:
        self.num_steps = int(num_steps)
        self.num_envs = int(num_envs)
        self.device = device
        self.fields: dict[str, torch.Tensor] = {}

    def write(self, step: int, **values: torch.Tensor) -> None:
        """Store each value (leading dimension num_envs) at rollout step ``step``."""
        if not 0 <= step < self.num_steps:
            raise IndexError(f"rollout step {step} outside [0, {self.num_steps})")
        for name, value in values.items():
            buf = self.fields.get(name)
            if buf is None:
                buf = torch.zeros(self.num_steps, *value.shape, dtype=value.dtype, device=self.device)
                self.fields[name] = buf
            buf[step].copy_(value)

    def write_all(self, **values: torch.Tensor) -> None:
        """Store whole fields given flat, with (num_steps * num_envs) rows in (step, env) order."""
        for name, value in values.items():
            self.fields[name] = value.reshape(self.num_steps, self.num_envs, *value.shape[1:]).to(self.device)

    def flat(self, name: str) -> torch.Tensor:
        """Field ``name`` with its (step, env) axes flattened into one batch axis (a view)."""
        return self.fields[name].flatten(0, 1)

    def __contains__(self, name: str) -> bool:
        return name in self.fields


def minibatch_indices(
    batch_size: int, num_mini_batches: int, num_epochs: int, device, reshuffle_each_epoch: bool
) -> Iterator[torch.Tensor]:
    """Index tensors of the minibatches of ``num_epochs`` passes over a batch of ``batch_size`` rows.

    One permutation for all passes is rsl_rl's rule (the same draw as its ``mini_batch_generator``, so runs match it
    exactly); ``reshuffle_each_epoch`` draws a new one per pass, as Brax / MuJoCo Playground do. Rows beyond
    ``num_mini_batches * (batch_size // num_mini_batches)`` are left out, as in rsl_rl.
    """
    size = batch_size // num_mini_batches
    if size < 1:
        raise ValueError(f"{batch_size} transitions cannot fill {num_mini_batches} minibatches")
    indices = torch.randperm(num_mini_batches * size, device=device)
    for epoch in range(num_epochs):
        if reshuffle_each_epoch and epoch > 0:
            indices = torch.randperm(num_mini_batches * size, device=device)
        for i in range(num_mini_batches):
            yield indices[i * size : (i + 1) * size]
