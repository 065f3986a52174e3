"""Cartpole balance (Playground ``CartpoleBalance``): keep a pole upright on a cart (dense reward).

The swing-up task (``cartpole_swingup.py``) shares this model, reward and observation; only its reset differs.

Observation (5): cart position, cos and sin of the pole angle (pole frame zz and xz), cart and pole velocities.
Reward: upright * centered * small_control * small_velocity with upright = (cos + 1) / 2,
centered = (1 + tolerance(x, margin=2)) / 2, small_control = (4 + tolerance(u, margin=1, 0, quadratic)) / 5,
small_velocity = (1 + tolerance(pole angular velocity, margin=5)) / 2 (Gaussian tolerances, value 0.1 at margin).
Reset: balance - cart U(-0.1, 0.1), pole U(-0.034, 0.034); swing-up - cart 0.01 N(0,1), pole pi + 0.01 N(0,1);
both - velocities 0.01 N(0,1).
"""

from __future__ import annotations

from refpo_warp.tasks.dmc.rewards import DEFAULT_VALUE_AT_MARGIN, GAUSSIAN, small_control, tolerance
from refpo_warp.tasks.dmc.task import DmcTask, reset_kernel
from refpo_warp.utils.warp_setup import wp


@wp.func
def pole_cos_sin(body_q: wp.array2d(dtype=wp.transform), i: int, pole: int) -> wp.vec2:
    r = wp.quat_to_matrix(wp.transform_get_rotation(body_q[i, pole]))
    return wp.vec2(r[2, 2], r[0, 2])


@wp.func
def draw_cartpole(
    i: int, state: wp.uint32, swing_up: int, joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float)
) -> wp.uint32:
    s = state
    if swing_up != 0:
        joint_q[i, 0] = 0.01 * wp.randn(s)
        joint_q[i, 1] = wp.pi + 0.01 * wp.randn(s)
    else:
        joint_q[i, 0] = wp.randf(s, -0.1, 0.1)
        joint_q[i, 1] = wp.randf(s, -0.034, 0.034)
    joint_qd[i, 0] = 0.01 * wp.randn(s)
    joint_qd[i, 1] = 0.01 * wp.randn(s)
    return s


reset_cartpole = reset_kernel(draw_cartpole, int)


@wp.kernel
def cartpole_reward(
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
    body_q: wp.array2d(dtype=wp.transform),
    ctrl: wp.array2d(dtype=float),
    pole: int,
    rewards: wp.array(dtype=float),
):
    i = wp.tid()
    upright = (pole_cos_sin(body_q, i, pole)[0] + 1.0) * 0.5
    centered = (1.0 + tolerance(joint_q[i, 0], 0.0, 0.0, 2.0, GAUSSIAN, DEFAULT_VALUE_AT_MARGIN)) * 0.5
    small_velocity = (1.0 + tolerance(joint_qd[i, 1], 0.0, 0.0, 5.0, GAUSSIAN, DEFAULT_VALUE_AT_MARGIN)) * 0.5
    rewards[i] = upright * centered * small_control(ctrl[i, 0]) * small_velocity


@wp.kernel
def cartpole_obs(
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
    body_q: wp.array2d(dtype=wp.transform),
    pole: int,
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    cs = pole_cos_sin(body_q, i, pole)
    obs[i, 0] = joint_q[i, 0]
    obs[i, 1] = cs[0]
    obs[i, 2] = cs[1]
    obs[i, 3] = joint_qd[i, 0]
    obs[i, 4] = joint_qd[i, 1]


class CartpoleBalance(DmcTask):
    model_file = "cartpole.xml"
    substeps = 1  # ctrl_dt 0.01 = sim_dt 0.01
    num_obs = 5
    num_actions = 1
    reward_summary = "upright x centered x small_control x small_velocity"
    reset_summary = "cart U(-.1,.1), pole U(-.034,.034), vel .01 N(0,1)"
    swing_up = 0  # the reset's distribution (cartpole_swingup.py sets 1)

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.pole = self.views.body_index("pole_1")

    def reset(self, mask) -> None:
        self.launch_reset(reset_cartpole, mask, self.swing_up)

    def reward(self, rewards) -> None:
        v = self.views
        self.launch(cartpole_reward, [v.joint_q, v.joint_qd, v.body_q, v.ctrl, self.pole, rewards])

    def observe(self, obs, reset_mask) -> None:
        v = self.views
        self.launch(cartpole_obs, [v.joint_q, v.joint_qd, v.body_q, self.pole, obs])
