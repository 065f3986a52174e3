"""DMC-style control suite on Newton (ReFPO paper §4.2): MuJoCo Playground DM Control tasks as Warp envs.

Every module of ``tasks/dmc/suite/`` is one task, registered as ``dmc_<module name>``. Registering reads the suite
without importing it: the env module (and Newton) is imported only when an env is built.
"""

from refpo_warp.registry import register_task
from tasks.dmc import suite
from tasks.dmc.cfg import DmcCfg

for _name in suite.task_names():
    register_task(f"dmc_{_name}", "tasks.dmc.env:DmcEnv", DmcCfg,
                  description=f"DMC {suite.describe(_name)}; {DmcCfg.max_episode_length}-step episodes",
                  task=_name)  # fmt: skip
