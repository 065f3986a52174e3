"""GridWorld options (Warp-free): grid size, goal reward, the 200-step time-out."""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.utils.option_rules import Int, Real


@dataclass
class GridWorldCfg(EnvCfg):
    size: int = 25
    goal_reward: float = 20.0
    max_episode_length: int = 200
    # starts lie in rows 2 .. size - 3, between the goal rows: at least 5 rows
    option_rules = {"size": Int(5, 100_000), "goal_reward": Real(-1e6, 1e6)}
