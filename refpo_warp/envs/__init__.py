"""Environments: ``EnvCfg`` (Warp-free options), the Warp-kernel rsl_rl VecEnv base ``WarpVecEnv`` (episode rules:
``episode.py``), action chunks and a gymnasium vector-env adapter.

Importing this package loads no Warp: ``WarpVecEnv`` is imported on first use, so config dataclasses stay cheap.
"""

from refpo_warp.envs.env_cfg import EnvCfg

__all__ = ["EnvCfg", "WarpVecEnv"]


def __getattr__(name: str):
    if name == "WarpVecEnv":  # loads Warp (and configures it first)
        from refpo_warp.envs.warp_vec_env import WarpVecEnv

        return WarpVecEnv
    raise AttributeError(f"module 'refpo_warp.envs' has no attribute {name!r}")
