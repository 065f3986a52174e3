"""DMC figures: the reward curve of a run with the 10-step / 1-step evaluation gap shaded (paper §4.2 figure)."""

from __future__ import annotations

from pathlib import Path

from refpo_warp.plots import return_curves


def reward_curve(progress_rows: list[dict], path: str | Path, label: str = "run") -> Path:
    """Plot evaluation returns at N = 10 and N = 1 Euler steps over env steps and shade the gap between them.

    Args:
        progress_rows: Rows of a run's ``progress.jsonl`` (``env_steps`` and, every ``eval.interval`` iterations,
            ``eval/return_N10`` and ``eval/return_N1``; a Gaussian policy's ``eval/return``, or the training
            ``reward_mean`` when a run has no periodic evaluation, is drawn as a single line).
        path: PNG file to write.
        label: Legend label of the run.
    """
    if not progress_rows:
        raise ValueError(f"No progress rows to plot for {path}: train with eval.interval > 0 first")
    return return_curves({label: progress_rows}, Path(path))
