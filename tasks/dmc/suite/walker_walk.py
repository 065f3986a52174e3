"""Walker walk (Playground ``WalkerWalk``): a planar biped walks forward at 1 m/s.

Observation (24): xx and xz entries of the frames of the 7 bodies (torso, right thigh/leg/foot, left thigh/leg/foot),
the torso's zz entry, joint velocities (9).
Reward: stand * (5 * move + 1) / 6 with stand = (3 * standing + upright) / 4,
standing = tolerance(torso height, bounds=(1.2, inf), margin=0.6) (Gaussian), upright = (1 + torso zz) / 2,
move = tolerance(v, bounds=(1, inf), margin=0.5, value 0.5 at margin, linear), v = centre-of-mass x velocity.
Reset: rooty U(-pi, pi), the six leg joints U(joint range), root x/z at zero, zero velocity.
"""

from __future__ import annotations

import math

from refpo_warp.sim import world_com_velocity
from refpo_warp.tasks.dmc.rewards import DEFAULT_VALUE_AT_MARGIN, GAUSSIAN, LINEAR, tolerance
from refpo_warp.tasks.dmc.task import DmcTask
from refpo_warp.utils.warp_setup import wp

STAND_HEIGHT = wp.constant(1.2)
WALK_SPEED = wp.constant(1.0)
BODIES = ("torso", "right_thigh", "right_leg", "right_foot", "left_thigh", "left_leg", "left_foot")
ROOT_PITCH = 2  # joint order: rootz, rootx, rooty, then the six leg hinges


@wp.kernel
def walker_reward(
    body_q: wp.array2d(dtype=wp.transform),
    body_qd: wp.array2d(dtype=wp.spatial_vector),
    body_mass: wp.array2d(dtype=float),
    torso: int,
    rewards: wp.array(dtype=float),
):
    i = wp.tid()
    pose = body_q[i, torso]
    height = wp.transform_get_translation(pose)[2]
    standing = tolerance(height, STAND_HEIGHT, wp.inf, 0.5 * STAND_HEIGHT, GAUSSIAN, DEFAULT_VALUE_AT_MARGIN)
    upright = 0.5 * (1.0 + wp.quat_to_matrix(wp.transform_get_rotation(pose))[2, 2])
    stand = (3.0 * standing + upright) / 4.0
    speed = world_com_velocity(body_qd, body_mass, i)[0]
    move = tolerance(speed, WALK_SPEED, wp.inf, 0.5 * WALK_SPEED, LINEAR, 0.5)
    rewards[i] = stand * (5.0 * move + 1.0) / 6.0


@wp.kernel
def walker_obs(
    joint_qd: wp.array2d(dtype=float),
    body_q: wp.array2d(dtype=wp.transform),
    bodies: wp.array(dtype=int),
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    nb = bodies.shape[0]
    for k in range(nb):
        r = wp.quat_to_matrix(wp.transform_get_rotation(body_q[i, bodies[k]]))
        obs[i, 2 * k] = r[0, 0]
        obs[i, 2 * k + 1] = r[0, 2]
    torso = wp.quat_to_matrix(wp.transform_get_rotation(body_q[i, bodies[0]]))
    obs[i, 2 * nb] = torso[2, 2]
    for j in range(joint_qd.shape[1]):
        obs[i, 2 * nb + 1 + j] = joint_qd[i, j]


class WalkerWalk(DmcTask):
    render_camera, track_body = "track", "torso"
    model_file = "walker.xml"
    substeps = 10  # ctrl_dt 0.025, sim_dt 0.0025
    num_obs = 24
    num_actions = 6
    reward_summary = "stand x (5 move + 1) / 6"
    reset_summary = "pitch U(-pi,pi), legs U(joint ranges)"

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.bodies: wp.array = wp.array([self.views.body_index(b) for b in BODIES], dtype=int, device=self.device)
        self.torso = self.views.body_index("torso")
        lower, upper = self.joint_limits()  # the six leg hinges within their limits
        lower[:ROOT_PITCH], upper[:ROOT_PITCH] = 0.0, 0.0  # root height and x offsets at the model's origin
        lower[ROOT_PITCH], upper[ROOT_PITCH] = -math.pi, math.pi
        self.reset_ranges = self.uniform_ranges(lower, upper)

    def reset(self, mask) -> None:
        self.reset_uniform_joints(mask, self.reset_ranges)

    def reward(self, rewards) -> None:
        v = self.views
        self.launch(walker_reward, [v.body_q, v.body_qd, v.body_mass, self.torso, rewards])

    def observe(self, obs, reset_mask) -> None:
        self.launch(walker_obs, [self.views.joint_qd, self.views.body_q, self.bodies, obs])
