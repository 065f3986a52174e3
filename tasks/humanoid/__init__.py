"""SMPL humanoid motion tracking (ReFPO paper §4.3): one env, task ids that fix its goal conditioning (and options)."""

from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.tasks.humanoid.cfg import HumanoidTrackingCfg

# task id: (description, the env options the id fixes); humanoid_all_residual's residual PD targets are in its YAML
_VARIANTS = {
    "humanoid_all": ("every body's targets observed", {"conditioning": "all"}),
    "humanoid_root_hands": ("only pelvis and wrist positions observed", {"conditioning": "root_hands"}),
    "humanoid_all_residual": (
        "every body's targets observed, PD targets relative to the reference",
        {"conditioning": "all"},
    ),
    "humanoid_root": ("only the pelvis position observed", {"conditioning": "root"}),
}

TASKS = [
    TaskSpec(
        task_id,
        "refpo_warp.tasks.humanoid.env:HumanoidTrackingEnv",
        HumanoidTrackingCfg,
        fixed,
        description=f"SMPL humanoid tracking, {description}",
    )
    for task_id, (description, fixed) in _VARIANTS.items()
]
