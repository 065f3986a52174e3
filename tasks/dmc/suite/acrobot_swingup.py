"""Acrobot swing-up (Playground ``AcrobotSwingup``): swing a two-link underactuated pendulum up to a target.

The tip of the two-link pendulum (elbow actuated) reaches for a target 4 m above the ground.

Observation (6): z-axis x components of the upper and lower arm frames (horizontal), their z components
(vertical), joint velocities. Reward: tolerance(|tip - target|, bounds=(0, 0.2), margin=1) (Gaussian, 0.1 at margin).
Reset: both joint angles U(-pi, pi), zero velocity.
"""

from __future__ import annotations

import math

from refpo_warp.tasks.dmc.rewards import DEFAULT_VALUE_AT_MARGIN, GAUSSIAN, tolerance
from refpo_warp.tasks.dmc.task import DmcTask
from refpo_warp.utils.warp_setup import wp

TARGET = wp.constant(wp.vec3(0.0, 0.0, 4.0))  # target site (world frame)
TARGET_RADIUS = wp.constant(0.2)
TIP = wp.constant(wp.vec3(0.0, 0.0, 1.0))  # tip site in the lower-arm frame


@wp.kernel
def acrobot_reward(body_q: wp.array2d(dtype=wp.transform), lower: int, rewards: wp.array(dtype=float)):
    i = wp.tid()
    dist = wp.length(wp.transform_point(body_q[i, lower], TIP) - TARGET)
    rewards[i] = tolerance(dist, 0.0, TARGET_RADIUS, 1.0, GAUSSIAN, DEFAULT_VALUE_AT_MARGIN)


@wp.kernel
def acrobot_obs(
    joint_qd: wp.array2d(dtype=float),
    body_q: wp.array2d(dtype=wp.transform),
    upper: int,
    lower: int,
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    ru = wp.quat_to_matrix(wp.transform_get_rotation(body_q[i, upper]))
    rl = wp.quat_to_matrix(wp.transform_get_rotation(body_q[i, lower]))
    obs[i, 0] = ru[0, 2]
    obs[i, 1] = rl[0, 2]
    obs[i, 2] = ru[2, 2]
    obs[i, 3] = rl[2, 2]
    obs[i, 4] = joint_qd[i, 0]
    obs[i, 5] = joint_qd[i, 1]


class AcrobotSwingup(DmcTask):
    model_file = "acrobot.xml"
    substeps = 1  # ctrl_dt = sim_dt = 0.01
    num_obs = 6
    num_actions = 1
    reward_summary = "tolerance(tip-target dist, (0,.2), margin 1)"
    reset_summary = "both angles U(-pi, pi)"

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.upper = self.views.body_index("upper_arm")
        self.lower = self.views.body_index("lower_arm")
        self.reset_ranges = self.uniform_ranges([-math.pi] * 2, [math.pi] * 2)

    def reset(self, mask) -> None:
        self.reset_uniform_joints(mask, self.reset_ranges)

    def reward(self, rewards) -> None:
        self.launch(acrobot_reward, [self.views.body_q, self.lower, rewards])

    def observe(self, obs, reset_mask) -> None:
        self.launch(acrobot_obs, [self.views.joint_qd, self.views.body_q, self.upper, self.lower, obs])
