"""Ball in cup (Playground ``BallInCup``): swing a ball tied to a cup by a string into the cup.

Observation (8): joint positions (cup x, cup z, ball x, ball z) and velocities.
Reward: 1 when the ball centre is inside the cup's target box shrunk by the ball radius
(|dx| < 0.05 - 0.025 and |dz| < 0.05 - 0.025, target box centre 0.05 below the cup frame), else 0.
Reset: the model's default pose at rest (Playground does not randomise this task).
"""

from __future__ import annotations

from refpo_warp.tasks.dmc.task import DmcTask
from refpo_warp.utils.warp_setup import wp

TARGET_OFFSET = wp.constant(wp.vec3(0.0, 0.0, -0.05))  # target site in the cup frame
INSIDE_HALF_WIDTH = wp.constant(0.05 - 0.025)  # target box half-size (x and z) minus the ball radius


@wp.kernel
def ball_in_cup_reward(body_q: wp.array2d(dtype=wp.transform), cup: int, ball: int, rewards: wp.array(dtype=float)):
    i = wp.tid()
    target = wp.transform_point(body_q[i, cup], TARGET_OFFSET)
    d = wp.transform_get_translation(body_q[i, ball]) - target
    inside = wp.abs(d[0]) < INSIDE_HALF_WIDTH and wp.abs(d[2]) < INSIDE_HALF_WIDTH
    rewards[i] = wp.where(inside, 1.0, 0.0)


@wp.kernel
def ball_in_cup_obs(joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float), obs: wp.array2d(dtype=float)):
    i = wp.tid()
    for j in range(4):
        obs[i, j] = joint_q[i, j]
        obs[i, 4 + j] = joint_qd[i, j]


class BallInCup(DmcTask):
    model_file = "ball_in_cup.xml"
    substeps = 10  # ctrl_dt 0.02, sim_dt 0.002
    num_obs = 8
    num_actions = 2
    reward_summary = "1 when the ball is in the cup"
    reset_summary = "the model's rest pose"

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.cup = self.views.body_index("cup")
        self.ball = self.views.body_index("ball")
        self.reset_ranges = self.uniform_ranges([0.0] * 4, [0.0] * 4)  # the model's rest pose

    def reset(self, mask) -> None:
        self.reset_uniform_joints(mask, self.reset_ranges)

    def reward(self, rewards) -> None:
        self.launch(ball_in_cup_reward, [self.views.body_q, self.cup, self.ball, rewards])

    def observe(self, obs, reset_mask) -> None:
        self.launch(ball_in_cup_obs, [self.views.joint_q, self.views.joint_qd, obs])
