"""Cheetah run (Playground ``CheetahRun``): run a planar half-cheetah forward as fast as possible.

Observation (17): joint positions without the root x (8), joint velocities (9).
Reward: tolerance(v, bounds=(10, inf), margin=10, value 0 at margin, linear) = clip(v / 10, 0, 1), where v is the
x velocity of the centre of mass (the torso's subtree linear velocity).
Reset: root at zero, the six leg joints U(joint range), then 200 physics steps at zero control let the model settle
(as in Playground and dm_control). Settling in the middle of a captured step is impossible, so ``prepare`` settles
``reset_bank_size`` (``cheetah_run_cfg.py``) such states once and resets draw one of them uniformly.
"""

from __future__ import annotations

import math

import torch

from refpo_warp.sim import world_com_velocity
from refpo_warp.tasks.dmc.rewards import LINEAR, tolerance
from refpo_warp.tasks.dmc.task import DmcTask, reset_kernel
from refpo_warp.utils.warp_setup import wp

RUN_SPEED = wp.constant(10.0)
SETTLE_STEPS = 200
NUM_ROOT = 3  # rootx, rootz, rooty


@wp.struct
class Bank:
    q: wp.array2d(dtype=float)
    qd: wp.array2d(dtype=float)


@wp.func
def draw_from_bank(
    i: int, state: wp.uint32, bank: Bank, joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float)
) -> wp.uint32:
    s = state
    k = wp.randi(s, 0, bank.q.shape[0])
    for j in range(joint_q.shape[1]):
        joint_q[i, j] = bank.q[k, j]
        joint_qd[i, j] = bank.qd[k, j]
    return s


reset_from_bank = reset_kernel(draw_from_bank, Bank)


@wp.kernel
def cheetah_reward(
    body_qd: wp.array2d(dtype=wp.spatial_vector), body_mass: wp.array2d(dtype=float), rewards: wp.array(dtype=float)
):
    i = wp.tid()
    speed = world_com_velocity(body_qd, body_mass, i)[0]
    rewards[i] = tolerance(speed, RUN_SPEED, wp.inf, RUN_SPEED, LINEAR, 0.0)


@wp.kernel
def cheetah_obs(joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float), obs: wp.array2d(dtype=float)):
    i = wp.tid()
    nq = joint_q.shape[1]
    for j in range(1, nq):
        obs[i, j - 1] = joint_q[i, j]
    for j in range(joint_qd.shape[1]):
        obs[i, nq - 1 + j] = joint_qd[i, j]


class CheetahRun(DmcTask):
    render_camera, track_body = "track", "torso"
    model_file = "cheetah.xml"
    substeps = 1  # ctrl_dt = sim_dt = 0.01
    num_obs = 17
    num_actions = 6
    reward_summary = "clip(v_x / 10, 0, 1), v_x of the centre of mass"
    reset_summary = "legs U(joint ranges), then 200 settling steps"

    def prepare(self) -> None:
        """Settle ``cfg.reset_bank(num_envs)`` random leg poses for SETTLE_STEPS physics steps at zero control."""
        n, v, sim = self.num_envs, self.views, self.sim
        size = self.cfg.reset_bank(n)
        rounds = math.ceil(size / n)
        bank_q = torch.zeros(rounds * n, v.joint_q.shape[1], device=wp.device_to_torch(self.device))
        bank_qd = torch.zeros(rounds * n, v.joint_qd.shape[1], device=bank_q.device)
        everyone = wp.ones(n, dtype=wp.bool, device=self.device)
        lower, upper = self.joint_limits()  # the six leg joints within their limits, the root at zero
        lower[:NUM_ROOT], upper[:NUM_ROOT] = 0.0, 0.0
        leg_ranges = self.uniform_ranges(lower, upper)
        assert v.ctrl is not None  # DmcEnv checked the actuators
        wp.to_torch(v.ctrl).zero_()
        for r in range(rounds):
            self.reset_uniform_joints(everyone, leg_ranges)
            sim.after_reset(everyone)
            sim.simulate_many(SETTLE_STEPS // self.substeps)
            bank_q[r * n : (r + 1) * n] = wp.to_torch(v.joint_q)
            bank_qd[r * n : (r + 1) * n] = wp.to_torch(v.joint_qd)
        self.bank = Bank()
        self.bank.q, self.bank.qd = wp.from_torch(bank_q[:size]), wp.from_torch(bank_qd[:size])

    def reset(self, mask) -> None:
        self.launch_reset(reset_from_bank, mask, self.bank)

    def reward(self, rewards) -> None:
        self.launch(cheetah_reward, [self.views.body_qd, self.views.body_mass, rewards])

    def observe(self, obs, reset_mask) -> None:
        self.launch(cheetah_obs, [self.views.joint_q, self.views.joint_qd, obs])
