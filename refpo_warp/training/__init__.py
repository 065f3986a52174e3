"""Train a run from a resolved config: ``train(["task=gridworld", "algo=refpo"])`` (behind ``refpo train``)."""

from refpo_warp.training.train_run import train

__all__ = ["train"]
