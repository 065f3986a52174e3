"""Residual actions (Puffer-PHC ``res_action``): PD target = the observed reference frame's joint angles + scaled
action, kept within pi/2 of the current joint angles; hands and toes stay frozen at 0."""

import numpy as np
import pytest
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.motion import skeleton as sk

DT = 1.0 / 30.0


@pytest.fixture(scope="module")
def env():
    return make_env("humanoid_all", num_envs=3, device="cpu", seed=5, residual_actions=True)


def frozen_dofs():
    return np.concatenate([np.arange(3 * (sk.body_index(n) - 1), 3 * sk.body_index(n)) for n in sk.FROZEN_HAND_TOE])


def test_zero_action_targets_the_observed_reference_frame(env):
    env.reset()
    obs_time = env.obs_time.numpy().copy()
    np.testing.assert_allclose(obs_time, env.ref_time.numpy() + DT, atol=1e-6)  # one control step ahead
    observed = env.reference_at(torch.from_numpy(obs_time)).dof_pos.numpy().copy()
    current = env.reference_at().dof_pos.numpy().copy()
    env.step(torch.zeros(3, 69))
    target = env.sim.joint_target.numpy()[:, 7:]
    expected = observed.copy()
    expected[:, frozen_dofs()] = 0.0
    np.testing.assert_allclose(target, expected, atol=1e-6)
    # The frame matters: the current frame's angles differ from the observed one's somewhere.
    moving = np.delete(np.abs(observed - current), frozen_dofs(), axis=1).max()
    assert moving > 1e-3, moving


def test_action_adds_scale_times_action_and_the_target_stays_within_half_pi(env):
    env.reset()
    observed = env.reference_at(torch.from_numpy(env.obs_time.numpy().copy())).dof_pos.numpy().copy()
    q = env.sim.joint_q.numpy().copy()  # numpy() aliases the simulator state on the CPU
    q[1, 7 + 4] = observed[1, 4] - 2.5  # env 1, hinge 4 (L_Knee y): 2.5 rad below the reference
    env.sim.joint_q.assign(q)
    actions = torch.zeros(3, 69)
    actions[0, 0] = 0.4  # L_Hip x: scale pi
    actions[0, 4] = -3.0  # L_Knee y: clipped to -1, scale 5 -> 5 rad below the reference, beyond pi/2
    env.step(actions)
    target = env.sim.joint_target.numpy()[:, 7:]
    assert target[0, 0] == pytest.approx(observed[0, 0] + 0.4 * np.pi, abs=1e-5)
    # |ref - 5 - q| > pi/2 (q starts within a few degrees of the reference): the target stops at q - pi/2.
    assert target[0, 4] == pytest.approx(q[0, 7 + 4] - np.pi / 2, abs=1e-5)
    # Env 1: q = ref - 2.5, zero action: the target is clamped to q + pi/2 = ref - 0.929.
    assert target[1, 4] == pytest.approx(observed[1, 4] - 2.5 + np.pi / 2, abs=1e-5)
    assert not target[:, frozen_dofs()].any()
