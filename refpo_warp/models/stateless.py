"""rsl_rl's recurrent-state hooks for a model without hidden state (what rsl_rl's ``MLPModel`` answers)."""

from __future__ import annotations

import torch


class Stateless:
    """Mixin: ``reset``, ``get_hidden_state`` and ``detach_hidden_state`` of rsl_rl's model protocol, as no-ops."""

    is_recurrent: bool = False

    def reset(self, dones: torch.Tensor | None = None, hidden_state=None) -> None:
        pass

    def get_hidden_state(self):
        return None

    def detach_hidden_state(self, dones: torch.Tensor | None = None) -> None:
        pass
