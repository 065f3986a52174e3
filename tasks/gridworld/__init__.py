"""Multimodal GridWorld (ReFPO paper §4.1): two goal bands, one at the top and one at the bottom of the grid."""

from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.tasks.gridworld.cfg import GridWorldCfg

TASKS = [
    TaskSpec(
        "gridworld",
        "refpo_warp.tasks.gridworld.env:GridWorldEnv",
        GridWorldCfg,
        description="25x25 grid, goal rows {0,1,23,24} (+20, episode ends), 200-step time-out",
    ),
]
