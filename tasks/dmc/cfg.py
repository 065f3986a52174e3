"""DMC env options (Warp-free): the suite task, the solver iteration caps, Playground's tanh on actions."""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.tasks.dmc.suite import task_names
from refpo_warp.utils.option_rules import Int, OneOf


@dataclass
class DmcCfg(EnvCfg):
    action_transform: str = "tanh"
    """MuJoCo Playground sends tanh(action) to the DM Control envs (``clip``: the actions clipped to [-1, 1])."""
    task: str = "cartpole_balance"
    """Suite task name (set by the registered task id, e.g. dmc_cheetah_run -> cheetah_run)."""
    solver_iterations: int = 0
    """MuJoCo solver iterations; 0 keeps the model file's (Playground's deliberately low) value."""
    solver_ls_iterations: int = 0
    """MuJoCo line-search iterations; 0 keeps the model file's value."""
    reset_bank_size: int = 0
    """Settled initial states pre-computed by tasks whose reset lets the model settle first (cheetah);
    0 means max(num_envs, 256)."""
    option_rules = {
        "task": OneOf(task_names(), fixed=True),
        "solver_iterations": Int(0, 10_000),
        "solver_ls_iterations": Int(0, 10_000),
        "reset_bank_size": Int(0, 10_000_000),
    }
