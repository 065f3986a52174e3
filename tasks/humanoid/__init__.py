"""SMPL humanoid motion tracking (ReFPO paper §4.3): one env, task ids that fix its goal conditioning (and options)."""

from refpo_warp.registry import register_task
from tasks.humanoid.cfg import HumanoidTrackingCfg

# task id: (description, the env options the id fixes); humanoid_all_residual's residual PD targets are in its YAML
TASKS = {
    "humanoid_all": ("every body's targets observed", {"conditioning": "all"}),
    "humanoid_root_hands": ("only pelvis and wrist positions observed", {"conditioning": "root_hands"}),
    "humanoid_all_residual": ("every body's targets observed, PD targets relative to the reference",
                              {"conditioning": "all"}),
    "humanoid_root": ("only the pelvis position observed", {"conditioning": "root"}),
}

for _task_id, (_description, _fixed) in TASKS.items():
    register_task(_task_id, "tasks.humanoid.env:HumanoidTrackingEnv", HumanoidTrackingCfg,
                  description=f"SMPL humanoid tracking, {_description}", **_fixed)  # fmt: skip
