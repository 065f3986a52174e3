"""The parts of rsl_rl's model protocol that every sampled (flow) policy answers the same way.

rsl_rl's runner and PPO-style algorithms call these on the actor: recurrent-state hooks (a flow policy has no hidden
state), the observation-normaliser update, and ``output_mean`` / ``output_std``, which rsl_rl logs as the policy's
action statistics; a sampled policy reports those of the last batch it sampled (``_last_actions``).
"""

from __future__ import annotations

import torch
from tensordict import TensorDict


class SampledPolicyProtocol:
    """Mixin for an ``nn.Module`` actor with ``obs_groups``, ``obs_normalization``, ``obs_normalizer``,
    ``action_dim`` and ``_last_actions`` (the last sampled batch, set by its sampler)."""

    def reset(self, dones: torch.Tensor | None = None, hidden_state=None) -> None:
        pass

    def get_hidden_state(self):
        return None

    def detach_hidden_state(self, dones: torch.Tensor | None = None) -> None:
        pass

    def update_normalization(self, obs: TensorDict) -> None:
        if self.obs_normalization:
            self.obs_normalizer.update(torch.cat([obs[g] for g in self.obs_groups], dim=-1))

    @property
    def output_mean(self) -> torch.Tensor:
        return self._last_actions.mean(dim=0)

    @property
    def output_std(self) -> torch.Tensor:
        """Per-dimension spread of the last sampled batch (rsl_rl logs it as the policy's action std)."""
        if self._last_actions.shape[0] < 2:
            return torch.zeros(self.action_dim)
        return self._last_actions.std(dim=0)
