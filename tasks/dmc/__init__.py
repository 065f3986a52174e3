"""DMC-style control suite on Newton (ReFPO paper §4.2): MuJoCo Playground DM Control tasks as Warp envs.

Every module of ``tasks/dmc/suite/`` is one task, declared as ``dmc_<module name>``. Declaring reads the suite
without importing it: the env module (and Newton) is imported only when an env is built. A task with env options of
its own names its cfg class (a ``DmcCfg`` subclass, Warp-free) in ``CFG_CLASSES``; the others take ``DmcCfg``.
"""

from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.tasks.dmc import suite
from refpo_warp.tasks.dmc.cfg import DmcCfg
from refpo_warp.tasks.dmc.point_mass_wall_cfg import PointMassWallCfg

CFG_CLASSES = {"point_mass_wall": PointMassWallCfg}

TASKS = [
    TaskSpec(
        f"dmc_{name}",
        "refpo_warp.tasks.dmc.env:DmcEnv",
        CFG_CLASSES.get(name, DmcCfg),
        {"task": name},
        description=f"DMC {suite.describe(name)}; {DmcCfg.max_episode_length}-step episodes",
    )
    for name in suite.task_names()
]
