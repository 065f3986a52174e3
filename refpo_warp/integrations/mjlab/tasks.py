"""The ReFPO variants of mjlab's tasks, registered in mjlab's task registry as ``<task id>-ReFPO`` (the paper's
ReFPO) and ``<task id>-ReFPO-OneStep`` (the one-step configuration, ``configs/algo/refpo_onestep.yaml``).

A variant is made from the registered task itself (its env and play configs, its PPO runner config, its runner
class), so a user's own task gets one with ``register_refpo_variant("My-Task")`` after registering it.
"""

from __future__ import annotations

import mjlab.tasks  # noqa: F401  (registers mjlab's own tasks, the bases of the variants)
from mjlab.tasks.registry import list_tasks, load_env_cfg, load_rl_cfg, load_runner_cls, register_mjlab_task

from refpo_warp.integrations.mjlab.cfg import refpo_runner_cfg
from refpo_warp.integrations.mjlab.runner import refpo_runner_cls

REFPO_SUFFIX = "-ReFPO"
# variant suffix -> the ReFPO configuration (configs/algo/<algo>.yaml) it trains with
CONFIGURATIONS = {REFPO_SUFFIX: "refpo", REFPO_SUFFIX + "-OneStep": "refpo_onestep"}
# mjlab 1.6.0's on-policy MLP tasks. The tracking task trains as mjlab's does, given a motion file
# (--env.commands.motion.motion-file); the lift task's vision variants have CNN actors, which FlowActor is not.
VARIANT_BASES = (
    "Mjlab-Cartpole-Balance",
    "Mjlab-Cartpole-Swingup",
    "Mjlab-Velocity-Flat-Unitree-G1",
    "Mjlab-Velocity-Rough-Unitree-G1",
    "Mjlab-Velocity-Flat-Unitree-Go1",
    "Mjlab-Velocity-Rough-Unitree-Go1",
    "Mjlab-Tracking-Flat-Unitree-G1",
    "Mjlab-Lift-Cube-Yam",
)


def register_refpo_variant(task_id: str, variant_id: str | None = None, algo: str = "refpo") -> str:
    """Register the ReFPO variant of the registered mjlab task ``task_id`` as ``variant_id`` (default
    ``<task_id>-ReFPO``), with the ReFPO configuration of ``configs/algo/<algo>.yaml``, and return its id."""
    if task_id not in list_tasks():
        raise KeyError(f"'{task_id}' is not a registered mjlab task; registered: {', '.join(list_tasks())}")
    variant_id = variant_id or task_id + REFPO_SUFFIX
    register_mjlab_task(
        task_id=variant_id,
        env_cfg=load_env_cfg(task_id),
        play_env_cfg=load_env_cfg(task_id, play=True),
        rl_cfg=refpo_runner_cfg(load_rl_cfg(task_id), algo),
        runner_cls=refpo_runner_cls(load_runner_cls(task_id)),
    )
    return variant_id


def register_variants() -> list[str]:
    """Register the variants of ``VARIANT_BASES`` that this mjlab has and that are not registered yet (mjlab may
    load the entry point twice); returns the ids registered now."""
    registered = set(list_tasks())
    return [
        register_refpo_variant(base, base + suffix, algo)
        for base in VARIANT_BASES
        for suffix, algo in CONFIGURATIONS.items()
        if base in registered and base + suffix not in registered
    ]
