"""Point mass (Playground ``PointMass``): drive a planar point mass onto a target sphere at the origin.

Observation (4): x, y positions and velocities. Reward: near_target * small_control with
near_target = tolerance(distance to the target centre, bounds=(0, 0.015), margin=0.015) (Gaussian, 0.1 at margin),
small_control = (4 + mean_j tolerance(u_j, margin=1, 0, quadratic)) / 5.
Reset: x, y U(-0.29, 0.29) (the joint ranges), zero velocity.
"""

from __future__ import annotations

from refpo_warp.tasks.dmc.rewards import DEFAULT_VALUE_AT_MARGIN, GAUSSIAN, small_control, tolerance
from refpo_warp.tasks.dmc.task import DmcTask
from refpo_warp.utils.warp_setup import wp

TARGET_RADIUS = wp.constant(0.015)  # the target geom; it sits at the origin, at the point mass's height


@wp.kernel
def point_mass_reward(
    body_q: wp.array2d(dtype=wp.transform), ctrl: wp.array2d(dtype=float), mass: int, rewards: wp.array(dtype=float)
):
    i = wp.tid()
    p = wp.transform_get_translation(body_q[i, mass])
    dist = wp.length(wp.vec2(p[0], p[1]))
    near = tolerance(dist, 0.0, TARGET_RADIUS, TARGET_RADIUS, GAUSSIAN, DEFAULT_VALUE_AT_MARGIN)
    control = 0.5 * (small_control(ctrl[i, 0]) + small_control(ctrl[i, 1]))
    rewards[i] = near * control


@wp.kernel
def point_mass_obs(joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float), obs: wp.array2d(dtype=float)):
    i = wp.tid()
    for j in range(2):
        obs[i, j] = joint_q[i, j]
        obs[i, 2 + j] = joint_qd[i, j]


class PointMass(DmcTask):
    render_view, render_distance = (-90.0, 90.0), 1.1  # planar in x-y: the whole arena seen from above
    model_file = "point_mass.xml"
    substeps = 1  # ctrl_dt = sim_dt = 0.02
    num_obs = 4
    num_actions = 2
    reward_summary = "tolerance(dist, (0,.015), margin .015) x small_control"
    reset_summary = "x, y U(-.29,.29)"

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.mass = self.views.body_index("pointmass")
        self.reset_ranges = self.uniform_ranges(*self.joint_limits())

    def reset(self, mask) -> None:
        self.reset_uniform_joints(mask, self.reset_ranges)

    def reward(self, rewards) -> None:
        self.launch(point_mass_reward, [self.views.body_q, self.views.ctrl, self.mass, rewards])

    def observe(self, obs, reset_mask) -> None:
        self.launch(point_mass_obs, [self.views.joint_q, self.views.joint_qd, obs])
