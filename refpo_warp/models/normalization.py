"""Observation normalisation with a clamp of the normalised values (Puffer-PHC's RunningNorm clips at +-10).

Wrapping the normaliser (instead of clamping in the model) keeps the clamp inside every export: rsl_rl's and our
exporters copy ``obs_normalizer`` as a whole.
"""

from __future__ import annotations

import torch
from torch import nn


class ClippedNormalization(nn.Module):
    """``normalizer(x)`` clamped to [-clip, clip]; ``update`` passes through to the wrapped normaliser."""

    def __init__(self, normalizer: nn.Module, clip: float) -> None:
        super().__init__()
        if clip <= 0:
            raise ValueError(f"obs_clip must be > 0 (or null for no clamp), got {clip}")
        self.normalizer = normalizer
        self.clip = float(clip)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.normalizer(x).clamp(-self.clip, self.clip)

    @torch.jit.unused
    def update(self, x: torch.Tensor) -> None:
        update_normalizer(self.normalizer, x)


def update_normalizer(normalizer: nn.Module, x: torch.Tensor) -> None:
    """``normalizer.update(x)`` when the normaliser has an ``update`` (rsl_rl's EmpiricalNormalization, clamped or
    not); an ``nn.Module``'s attribute is untyped to mypy, hence the look-up."""
    update = getattr(normalizer, "update", None)
    if update is not None:
        update(x)


def with_clip(normalizer: nn.Module, clip: float | None) -> nn.Module:
    """The normaliser, clamped to [-clip, clip] when ``clip`` is set."""
    return normalizer if clip is None else ClippedNormalization(normalizer, clip)
