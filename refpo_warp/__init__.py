"""refpo_warp: ReFPO flow-matching policy gradients on rsl_rl with Warp-kernel environments."""

from refpo_warp.envs.registry import list_tasks, make_env, make_env_cfg, register_task

__all__ = ["list_tasks", "make_env", "make_env_cfg", "register_task"]
__version__ = "0.1.0"
