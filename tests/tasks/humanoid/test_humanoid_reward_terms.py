"""The tracking reward's named terms: hand-worked values on a hand-made state, weights and scales from the cfg, the
terms adding up to the reward, and their episode sums (kept by the base env) logged as ``Episode_Reward/<term>``."""

import dataclasses
import math

import numpy as np
import pytest
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.tasks.humanoid.cfg import HumanoidTrackingCfg
from refpo_warp.tasks.humanoid.reward_terms import TERMS, reward_params
from refpo_warp.utils.warp_setup import wp

NB, NDOF = 24, 69


def _launch(params, episode_length=5):
    """One evaluation, at step ``episode_length`` of an episode, of a hand-made state (2 identical envs): every
    simulated body at rest with identity rotation; the reference 0.1 m further along x, turned 0.2 rad about z, moving
    at 1 m/s along x and spinning at 2 rad/s about z; every hinge at angle 0 with rate 1 rad/s and PD target 0.01 rad
    (kp 100, kd 10)."""
    from refpo_warp.motion.motion_library import MotionFrames
    from refpo_warp.tasks.humanoid.tracking_kernels import reward_and_termination_kernel

    n = 2
    pos = np.stack([np.zeros(NB), np.zeros(NB), 1.0 + 0.01 * np.arange(NB)], -1)
    body_q = np.concatenate([pos, np.tile([0.0, 0.0, 0.0, 1.0], (NB, 1))], -1)
    half = 0.1  # half of the 0.2 rad turn
    arrays = {
        "body_q": wp.array(np.tile(body_q, (n, 1, 1)).astype(np.float32), dtype=wp.transform),
        "body_qd": wp.zeros((n, NB), dtype=wp.spatial_vector),
        "body_com": wp.zeros(NB, dtype=wp.vec3),
        "joint_q": wp.zeros((n, 7 + NDOF), dtype=float),
        "joint_qd": wp.array(np.concatenate([np.zeros((n, 6)), np.ones((n, NDOF))], 1).astype(np.float32)),
        "joint_target": wp.array(np.concatenate([np.zeros((n, 7)), np.full((n, NDOF), 0.01)], 1).astype(np.float32)),
    }
    ref = MotionFrames()  # the body arrays: the reward reads no joint angles or rates
    ref.body_pos = wp.array(np.tile(pos + [0.1, 0.0, 0.0], (n, 1, 1)).astype(np.float32), dtype=wp.vec3)
    turned = np.tile([0.0, 0.0, math.sin(half), math.cos(half)], (n, NB, 1))
    ref.body_rot = wp.array(turned.astype(np.float32), dtype=wp.quat)
    ref.body_vel = wp.array(np.tile([1.0, 0.0, 0.0], (n, NB, 1)).astype(np.float32), dtype=wp.vec3)
    ref.body_angvel = wp.array(np.tile([0.0, 0.0, 2.0], (n, NB, 1)).astype(np.float32), dtype=wp.vec3)
    rewards, step_terms = wp.zeros(n, dtype=float), wp.zeros((n, len(TERMS)), dtype=float)
    flags = [wp.zeros(n, dtype=wp.bool) for _ in range(2)]  # terminated, clip end
    metrics = [wp.zeros(n, dtype=float) for _ in range(3)]
    wp.launch(
        reward_and_termination_kernel,
        dim=n,
        inputs=[
            *arrays.values(),
            wp.full(NDOF, 100.0, dtype=float),
            wp.full(NDOF, 10.0, dtype=float),
            500.0,
            ref,
            wp.ones(NB, dtype=float),
            wp.zeros(n, dtype=int),
            wp.zeros(n, dtype=float),
            wp.array([10.0], dtype=float),
            wp.full(n, episode_length - 1, dtype=wp.int32),
            0,
            0.25,
            0.5,
            100.0,
            params,
            wp.zeros(n, dtype=float),
        ],
        outputs=[rewards, *flags, *metrics, step_terms],
        device="cpu",
    )
    assert not flags[0].numpy().any()  # 0.1 m off the reference: no termination
    return rewards.numpy()[0], step_terms.numpy()[0]


def test_terms_on_a_hand_made_state_sum_to_the_reward():
    reward, terms = _launch(reward_params(HumanoidTrackingCfg()))
    # Mean squared errors: position 0.1^2 / 3 (x only, averaged over x/y/z), angle 0.2^2, velocity 1 / 3,
    # angular velocity 4 / 3; power: |(100 * 0.01 - 10 * 1) * 1| = 9 N m rad/s on each of 69 hinges.
    expected = [
        0.5 * math.exp(-100 * 0.01 / 3),
        0.3 * math.exp(-10 * 0.04),
        0.1 * math.exp(-0.1 / 3),
        0.1 * math.exp(-0.1 * 4 / 3),
        -0.0005 * 9 * 69,
    ]
    np.testing.assert_allclose(terms, expected, rtol=1e-5)
    assert reward == pytest.approx(sum(expected), rel=1e-5)  # 0.433105
    assert reward == pytest.approx(terms.sum(), abs=1e-6)


def test_weights_and_scales_come_from_the_cfg_and_power_is_off_at_the_start():
    cfg = dataclasses.replace(
        HumanoidTrackingCfg(),
        reward_pos_weight=1.0,
        reward_rot_weight=2.0,
        reward_vel_weight=3.0,
        reward_angvel_weight=4.0,
        reward_pos_scale=1.0,
        reward_rot_scale=1.0,
        reward_vel_scale=1.0,
        reward_angvel_scale=1.0,
        power_coef=0.001,
    )
    first_reward, first = _launch(reward_params(cfg))
    expected = [math.exp(-0.01 / 3), 2 * math.exp(-0.04), 3 * math.exp(-1 / 3), 4 * math.exp(-4 / 3), -0.001 * 621]
    np.testing.assert_allclose(first, expected, rtol=1e-5)
    assert first_reward == pytest.approx(sum(expected), rel=1e-5)
    _, third = _launch(reward_params(cfg), episode_length=3)  # power off in the first 3 steps
    np.testing.assert_allclose(third, expected[:4] + [0.0], rtol=1e-5)
    _, fourth = _launch(reward_params(cfg), episode_length=4)
    np.testing.assert_allclose(fourth, expected, rtol=1e-5)


def test_episode_reward_terms_are_logged_and_add_up_to_the_return():
    env = make_env("humanoid_all", num_envs=8, device="cpu", seed=1)
    generator = torch.Generator().manual_seed(0)
    returns = torch.zeros(8)
    checked = 0
    for _ in range(8):
        _, rewards, dones, extras = env.step(torch.randn(8, 69, generator=generator))
        returns += rewards
        if dones.any():
            log = extras["log"]
            sums = torch.stack([log[f"Episode_Reward/{t}"] for t in TERMS], 1)
            assert sums.shape == (int(dones.sum()), len(TERMS))
            torch.testing.assert_close(sums.sum(1), returns[dones], rtol=1e-5, atol=1e-5)
            assert (sums[:, :4] > 0).all() and (sums[:, 4] <= 0).all()
            checked += int(dones.sum())
        returns[dones] = 0.0
    assert checked > 0
