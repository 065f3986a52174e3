"""Pendulum swing-up (Playground ``PendulumSwingup``): swing a torque-limited pendulum upright.

Observation (3): pole frame zz and xz (cos and sin of the angle from upright; dm_control's order), hinge angular
velocity.
Reward: 1 when the pole is within 8 degrees of upright (tolerance(zz, bounds=(cos 8deg, 1)), margin 0), else 0.
Reset: hinge angle U(0, pi) (Playground; dm_control uses U(-pi, pi)), zero velocity.
"""

from __future__ import annotations

import math

from refpo_warp.tasks.dmc.rewards import GAUSSIAN, tolerance
from refpo_warp.tasks.dmc.task import DmcTask
from refpo_warp.utils.warp_setup import wp

COS_8_DEG = wp.constant(math.cos(math.radians(8.0)))


@wp.kernel
def pendulum_reward(body_q: wp.array2d(dtype=wp.transform), pole: int, rewards: wp.array(dtype=float)):
    i = wp.tid()
    zz = wp.quat_to_matrix(wp.transform_get_rotation(body_q[i, pole]))[2, 2]
    rewards[i] = tolerance(zz, COS_8_DEG, 1.0, 0.0, GAUSSIAN, 0.1)


@wp.kernel
def pendulum_obs(
    joint_qd: wp.array2d(dtype=float),
    body_q: wp.array2d(dtype=wp.transform),
    pole: int,
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    r = wp.quat_to_matrix(wp.transform_get_rotation(body_q[i, pole]))
    obs[i, 0] = r[2, 2]
    obs[i, 1] = r[0, 2]
    obs[i, 2] = joint_qd[i, 0]


class PendulumSwingup(DmcTask):
    model_file = "pendulum.xml"
    substeps = 2  # ctrl_dt 0.02, sim_dt 0.01
    num_obs = 3
    num_actions = 1
    reward_summary = "1 within 8 deg of upright"
    reset_summary = "angle U(0, pi)"

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.pole = self.views.body_index("pole")
        self.reset_ranges = self.uniform_ranges([0.0], [math.pi])

    def reset(self, mask) -> None:
        self.reset_uniform_joints(mask, self.reset_ranges)

    def reward(self, rewards) -> None:
        self.launch(pendulum_reward, [self.views.body_q, self.pole, rewards])

    def observe(self, obs, reset_mask) -> None:
        self.launch(pendulum_obs, [self.views.joint_qd, self.views.body_q, self.pole, obs])
