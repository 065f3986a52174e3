"""dmc_cheetah_run's env options (Warp-free): the bank of settled initial states its reset draws from."""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.tasks.dmc.cfg import DmcCfg
from refpo_warp.utils.option_rules import Int
from refpo_warp.utils.options import option

MIN_RESET_BANK = 256


@dataclass
class CheetahRunCfg(DmcCfg):
    reset_bank_size: int = option(
        0,
        Int(0, 10_000_000),
        "settled initial states pre-computed when the env is built (the reset lets the model settle for 200 physics "
        f"steps, which cannot run inside a captured step); 0: max(num_envs, {MIN_RESET_BANK})",
    )

    def reset_bank(self, num_envs: int) -> int:
        """The number of settled initial states to pre-compute for ``num_envs`` envs (``reset_bank_size``)."""
        return self.reset_bank_size or max(num_envs, MIN_RESET_BANK)
