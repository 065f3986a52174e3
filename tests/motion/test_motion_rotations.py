"""Quaternion helpers (xyzw) against closed forms: rotation matrices written out by hand, Rodrigues' formula via
MuJoCo, slerp of rotations about one axis."""

from __future__ import annotations

import mujoco
import numpy as np

from refpo_warp.motion import rotations as rot


def test_known_rotations():
    q = rot.quat_from_axis_angle(np.array([0.0, 0.0, np.pi / 2]))  # 90 deg about z
    np.testing.assert_allclose(q, [0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-15)
    np.testing.assert_allclose(rot.quat_to_matrix(q), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(rot.quat_rotate(q, np.array([1.0, 2.0, 3.0])), [-2.0, 1.0, 3.0], atol=1e-15)
    # x then y: q_y * q_x maps x -> x -> -z after 90 deg about y.
    qx = rot.quat_from_axis_angle(np.array([np.pi / 2, 0.0, 0.0]))
    qy = rot.quat_from_axis_angle(np.array([0.0, np.pi / 2, 0.0]))
    np.testing.assert_allclose(rot.quat_rotate(rot.quat_mul(qy, qx), np.array([0.0, 1.0, 0.0])), [1, 0, 0], atol=1e-15)


def test_against_mujoco_and_round_trips():
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(200, 3))
    angles = np.concatenate([rng.uniform(0, np.pi, 197), [1e-10, 0.0, np.pi - 1e-9]])
    aa = axes / np.linalg.norm(axes, axis=1, keepdims=True) * angles[:, None]
    q = rot.quat_from_axis_angle(aa)
    for i in range(0, 200, 7):
        want = np.zeros(4)
        mujoco.mju_axisAngle2Quat(want, axes[i] / np.linalg.norm(axes[i]), angles[i])  # wxyz
        assert abs(abs(np.dot(np.roll(want, -1), q[i])) - 1) < 1e-12
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, np.roll(q[i], 1))
        np.testing.assert_allclose(rot.quat_to_matrix(q[i]), mat.reshape(3, 3), atol=1e-12)
    np.testing.assert_allclose(rot.quat_to_axis_angle(q)[:-1], aa[:-1], atol=1e-9)  # unique below pi
    back = rot.quat_from_matrix(rot.quat_to_matrix(q))
    np.testing.assert_allclose(np.abs(np.sum(back * q, axis=1)), 1.0, atol=1e-12)
    euler = rng.uniform(-np.pi, np.pi, size=(200, 3))
    for candidate in rot.euler_xyz_candidates(rot.quat_from_euler_xyz(euler)):
        # Both Euler solutions describe the same rotation.
        np.testing.assert_allclose(
            rot.quat_to_matrix(rot.quat_from_euler_xyz(candidate)),
            rot.quat_to_matrix(rot.quat_from_euler_xyz(euler)),
            atol=1e-9,
        )


def test_slerp_and_continuity():
    axis = np.array([0.0, 0.6, 0.8])
    q0, q1 = rot.quat_from_axis_angle(0.2 * axis), rot.quat_from_axis_angle(1.4 * axis)
    for t in (0.0, 0.25, 0.5, 1.0):
        want = rot.quat_from_axis_angle((0.2 + 1.2 * t) * axis)
        assert abs(abs(np.dot(rot.quat_slerp(q0, q1, t), want)) - 1) < 1e-12
        assert abs(abs(np.dot(rot.quat_slerp(q0, -q1, t), want)) - 1) < 1e-12  # sign of q1 does not matter
    # Angular velocity of a constant spin is the spin.
    np.testing.assert_allclose(rot.angular_velocity(q0, q1, 0.5), 2.4 * axis, atol=1e-12)
    rng = np.random.default_rng(1)
    q = rot.quat_normalize(rng.normal(size=(30, 5, 4)))
    c = rot.quat_make_continuous(q)
    assert np.all(np.sum(c[1:] * c[:-1], axis=-1) >= 0) and np.allclose(np.abs(c), np.abs(q))
    np.testing.assert_allclose(c[0], q[0])
