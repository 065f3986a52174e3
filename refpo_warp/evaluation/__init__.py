"""Evaluate policies: episodes on a vectorised env, a saved run's ``eval.json`` and figures, the periodic evaluation
during training, and training-curve figures from ``progress.jsonl``."""
