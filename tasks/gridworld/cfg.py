"""GridWorld options (Warp-free): grid size, goal reward, the 200-step time-out."""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.utils.option_rules import Int, Real
from refpo_warp.utils.options import option


@dataclass
class GridWorldCfg(EnvCfg):
    # starts lie in rows 2 .. size - 3, between the goal rows: at least 5 rows
    size: int = option(25, Int(5, 100_000), "side of the square grid, in cells")
    goal_reward: float = option(20.0, Real(-1e6, 1e6), "reward for reaching a goal row")
    max_episode_length: int = option(200)
