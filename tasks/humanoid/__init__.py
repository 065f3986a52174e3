"""SMPL humanoid motion tracking (ReFPO paper §4.3): three goal-conditioning regimes over the same env."""

from refpo_warp.registry import register_task

_ENV = "tasks.humanoid.env:HumanoidTrackingEnv"

register_task("humanoid_all", _ENV, description="SMPL humanoid tracking, every body's targets observed",
              conditioning="all")
register_task("humanoid_root_hands", _ENV,
              description="SMPL humanoid tracking, only pelvis and wrist positions observed", conditioning="root_hands")
register_task("humanoid_all_residual", _ENV, conditioning="all",
              description="SMPL humanoid tracking, every body's targets observed, PD targets relative to the reference")
register_task("humanoid_root", _ENV, description="SMPL humanoid tracking, only the pelvis position observed",
              conditioning="root")
