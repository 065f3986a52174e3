"""Humanoid evaluation summary: the paper's table columns (success rate, alive duration, MPJPE) per flow-step count.

Each evaluation env plays one clip once from its start (``eval_mode``), so every number below is a mean over clips.
"""

from __future__ import annotations

import torch

# The generic means these numbers stand for, dropped so each metric has one name (the paper's) in eval.json: an
# evaluation episode ends when the clip ends or the humanoid falls, so its length is the alive duration.
REPLACES = ("success_mean", "mpjpe_mm_mean", "alive_steps_mean", "length_mean")


def summarize(episodes: dict[str, torch.Tensor]) -> dict[str, float]:
    """``success_rate_pct``: clips played to their end (%); ``alive_duration``: control steps survived (30 Hz; the
    episode length); ``mpjpe_mm``: per clip, the mean over its frames of the mean global body-position error (mm)."""
    if not episodes["success"].numel():
        return {}
    return {
        "success_rate_pct": 100.0 * float(episodes["success"].float().mean()),
        "alive_duration": float(episodes["alive_steps"].float().mean()),
        "mpjpe_mm": float(episodes["mpjpe_mm"].float().mean()),
    }
