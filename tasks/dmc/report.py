"""DMC evaluation extras for refpo_warp.report: the reward-curve PNG next to eval.json."""

from __future__ import annotations

from pathlib import Path

from refpo_warp.plots import read_progress, return_curves


def figures(run_dir: Path, actor, cfg: dict) -> list[Path]:
    """``reward_curve.png``: N = 10 and N = 1 evaluation returns during training, the gap shaded."""
    rows = read_progress(run_dir)
    if not rows:
        return []
    return [return_curves({f"{cfg['task']} {cfg['algo']}": rows}, Path(run_dir) / "reward_curve.png")]
