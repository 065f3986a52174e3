"""DMC-style control suite on Newton (ReFPO paper §4.2): MuJoCo Playground DM Control tasks as Warp envs.

Every module of ``tasks/dmc/suite/`` is one task, declared as ``dmc_<module name>``. Declaring reads the suite
without importing it: the env module (and Newton) is imported only when an env is built. Env options: those every
task reads are ``DmcCfg``'s (``cfg.py``); a task with options of its own has its cfg, a ``DmcCfg`` subclass, in
``<task>_cfg.py`` beside ``cfg.py`` (Warp-free, found by that name), and only that task accepts them.
"""

from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.tasks.dmc import suite
from refpo_warp.tasks.dmc.cfg import DmcCfg, stray_cfg_modules, task_cfg_class
from refpo_warp.utils.errors import ConfigError

if stray_cfg_modules():
    raise ConfigError(f"tasks/dmc/: {stray_cfg_modules()} name no task of tasks/dmc/suite/ (<task>_cfg.py)")

TASKS = [
    TaskSpec(
        f"dmc_{name}",
        "refpo_warp.tasks.dmc.env:DmcEnv",
        task_cfg_class(name),
        {"task": name},
        description=f"DMC {suite.describe(name)}; {DmcCfg.max_episode_length}-step episodes",
    )
    for name in suite.task_names()
]
