"""DMC env options (Warp-free): the suite task, the solver iteration caps, Playground's tanh on actions, the reset
bank."""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.tasks.dmc.suite import task_names
from refpo_warp.utils.option_rules import Int, OneOf
from refpo_warp.utils.options import option

MIN_RESET_BANK = 256


@dataclass
class DmcCfg(EnvCfg):
    action_transform: str = option(
        "tanh", doc="MuJoCo Playground sends tanh(action) to the DM Control envs (clip: the actions clipped to [-1, 1])"
    )
    task: str = option(
        "cartpole_balance",
        OneOf(task_names(), fixed=True),
        "suite task name (set by the registered task id, e.g. dmc_cheetah_run -> cheetah_run)",
    )
    solver_iterations: int = option(
        0, Int(0, 10_000), "MuJoCo solver iterations; 0 keeps the model file's (Playground's deliberately low) value"
    )
    solver_ls_iterations: int = option(
        0, Int(0, 10_000), "MuJoCo line-search iterations; 0 keeps the model file's value"
    )
    reset_bank_size: int = option(
        0,
        Int(0, 10_000_000),
        "settled initial states pre-computed by tasks whose reset lets the model settle first (cheetah); "
        f"0: max(num_envs, {MIN_RESET_BANK}) (reset_bank)",
    )

    def reset_bank(self, num_envs: int) -> int:
        """The number of settled initial states to pre-compute for ``num_envs`` envs (``reset_bank_size``)."""
        return self.reset_bank_size or max(num_envs, MIN_RESET_BANK)
