"""Generic Newton helpers for Warp environments: N-world MJCF models on SolverMuJoCo, per-world views, resets."""

from refpo_warp.sim.body_kinematics import world_com_velocity
from refpo_warp.sim.health import world_state_finite
from refpo_warp.sim.mjcf_worlds import build_mjcf_worlds, mjcf_timestep
from refpo_warp.sim.mujoco_worlds import MuJoCoWorlds
from refpo_warp.sim.world_views import WorldViews, make_world_views

__all__ = [
    "MuJoCoWorlds",
    "WorldViews",
    "build_mjcf_worlds",
    "make_world_views",
    "mjcf_timestep",
    "world_com_velocity",
    "world_state_finite",
]
