"""Reacher easy (Playground ``ReacherEasy``): touch a random target with the tip of a two-link arm.

Observation (6): shoulder and wrist angles, target minus fingertip (x, y), joint velocities.
Reward: 1 when the fingertip-target distance is at most 0.05 + 0.01 (target radius + fingertip radius), else 0.
Reset: shoulder U(-pi, pi), wrist U(-160, 160) deg, zero velocity; target at radius U(0.05, 0.2), angle U(0, 2 pi),
position radius * (sin, cos). The target is a mocap body in the file; each env keeps its own target here.
"""

from __future__ import annotations

import numpy as np

from refpo_warp.tasks.dmc.rewards import GAUSSIAN, tolerance
from refpo_warp.tasks.dmc.task import DmcTask, reset_kernel
from refpo_warp.utils.warp_setup import wp

TARGET_RADIUS = 0.05  # easy; hard would be 0.015
FINGER_RADIUS = 0.01


@wp.struct
class ReacherReset:
    wrist_lower: float
    wrist_upper: float
    target: wp.array(dtype=wp.vec2)  # written: each env's target


@wp.func
def draw_reacher(
    i: int, state: wp.uint32, p: ReacherReset, joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float)
) -> wp.uint32:
    s = state
    joint_q[i, 0] = wp.randf(s, -wp.pi, wp.pi)
    joint_q[i, 1] = wp.randf(s, p.wrist_lower, p.wrist_upper)
    joint_qd[i, 0] = 0.0
    joint_qd[i, 1] = 0.0
    angle = wp.randf(s) * 2.0 * wp.pi
    radius = wp.randf(s, 0.05, 0.2)
    p.target[i] = radius * wp.vec2(wp.sin(angle), wp.cos(angle))
    return s


reset_reacher = reset_kernel(draw_reacher, ReacherReset)


@wp.func
def finger_to_target(body_q: wp.array2d(dtype=wp.transform), i: int, finger: int, target: wp.vec2) -> wp.vec2:
    p = wp.transform_get_translation(body_q[i, finger])
    return target - wp.vec2(p[0], p[1])


@wp.kernel
def reacher_reward(
    body_q: wp.array2d(dtype=wp.transform),
    target: wp.array(dtype=wp.vec2),
    finger: int,
    reach: float,
    rewards: wp.array(dtype=float),
):
    i = wp.tid()
    dist = wp.length(finger_to_target(body_q, i, finger, target[i]))
    rewards[i] = tolerance(dist, 0.0, reach, 0.0, GAUSSIAN, 0.1)


@wp.kernel
def reacher_obs(
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
    body_q: wp.array2d(dtype=wp.transform),
    target: wp.array(dtype=wp.vec2),
    finger: int,
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    to_target = finger_to_target(body_q, i, finger, target[i])
    obs[i, 0] = joint_q[i, 0]
    obs[i, 1] = joint_q[i, 1]
    obs[i, 2] = to_target[0]
    obs[i, 3] = to_target[1]
    obs[i, 4] = joint_qd[i, 0]
    obs[i, 5] = joint_qd[i, 1]


class ReacherEasy(DmcTask):
    render_view, render_distance = (-90.0, 90.0), 1.1  # planar in x-y: the whole arena seen from above
    model_file = "reacher_easy.xml"
    substeps = 4  # ctrl_dt 0.02, sim_dt 0.005
    num_obs = 6
    num_actions = 2
    reward_summary = "1 when fingertip-target distance <= .05 + .01"
    reset_summary = "shoulder U(-pi,pi), wrist U(-160,160) deg, target r U(.05,.2)"

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.finger = self.views.body_index("finger")
        self.target = wp.zeros(self.num_envs, dtype=wp.vec2, device=self.device)
        lower, upper = self.joint_limits()
        self.reset_params = ReacherReset()
        self.reset_params.wrist_lower, self.reset_params.wrist_upper = float(lower[1]), float(upper[1])
        self.reset_params.target = self.target

    def reset(self, mask) -> None:
        self.launch_reset(reset_reacher, mask, self.reset_params)

    def reward(self, rewards) -> None:
        self.launch(
            reacher_reward, [self.views.body_q, self.target, self.finger, TARGET_RADIUS + FINGER_RADIUS, rewards]
        )

    def observe(self, obs, reset_mask) -> None:
        v = self.views
        self.launch(reacher_obs, [v.joint_q, v.joint_qd, v.body_q, self.target, self.finger, obs])

    def render_mocap(self, i: int) -> np.ndarray:
        return np.array([[*self.target.numpy()[i], 0.01]], dtype=np.float64)  # the target body at its height
