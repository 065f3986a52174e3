"""Task families, installed as ``refpo_warp.tasks``: every subpackage is one family, found by
``refpo_warp.envs.registry`` (nothing lists them) and imported once; its ``__init__`` declares the family's tasks as
``TASKS = [TaskSpec(...)]`` (``refpo_warp.envs.task_spec``): id, env cfg class (Warp-free), env entry point, training
config file."""
