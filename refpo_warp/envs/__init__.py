"""Environment base classes: the Warp-kernel rsl_rl VecEnv and a gymnasium vector-env adapter."""

from refpo_warp.device import configure_warp

configure_warp()  # before any kernel module (ours or Newton's) is imported

from refpo_warp.envs.warp_vec_env import EnvCfg, WarpVecEnv  # noqa: E402

__all__ = ["EnvCfg", "WarpVecEnv"]
