"""Forward kinematics on the SMPL skeleton and conversions between AMASS poses, model-frame rotations and the
simulator's hinge angles (numpy, float64, vectorised over frames).

Frames: the model frame is z-up, x forward, y left (the MJCF's body frames at rest and the simulator's world).
AMASS rotations are axis-angle in SMPL's y-up template frame (x left, y up, z forward) and in SMPL joint order.
A template-frame vector v_t is the model-frame vector M^T v_t with M = ``MODEL_TO_TEMPLATE``, so
- a joint's local rotation in the model frame is M^T R_t M,
- the root's world rotation in the model frame is R_root M (AMASS ``root_orient`` maps the template into the z-up
  world; at rest it is the upright rotation M^T, a 120 degree turn about (1, 1, 1)),
- the pelvis world position is ``trans + J0`` (SMPL rotates the body about the template pelvis joint J0).
"""

from __future__ import annotations

import numpy as np

from refpo_warp.motion import rotations as rot
from refpo_warp.motion.skeleton import (
    BODY_TO_SMPL,
    MODEL_TO_TEMPLATE,
    NUM_BODIES,
    NUM_DOFS,
    PARENTS,
    PELVIS_J0_TEMPLATE,
    REST_OFFSETS,
    SMPL_TO_BODY,
)

# Quaternion (xyzw) of MODEL_TO_TEMPLATE: a -120 degree turn about (1, 1, 1); its inverse is the upright rotation.
_M_QUAT = rot.quat_from_matrix(MODEL_TO_TEMPLATE)
UPRIGHT_QUAT = rot.quat_conjugate(_M_QUAT)  # (0.5, 0.5, 0.5, 0.5): template y-up body -> z-up world facing +x

NUM_AMASS_BODY_JOINTS = 22  # pelvis (root_orient) + 21 body joints; AMASS hands/jaw/eyes are dropped


def forward_kinematics(
    root_pos: np.ndarray, root_rot: np.ndarray, local_rot: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World body positions (T, 24, 3) and rotations (T, 24, 4 xyzw) from the root pose and per-body local rotations.

    ``local_rot[:, b]`` rotates body b's frame relative to its parent (relative to the rest pose); entry 0 is
    ignored (the root rotation is ``root_rot``). Bodies are in skeleton order, whose parents always come first.
    """
    root_pos = np.asarray(root_pos, dtype=np.float64)
    local_rot = np.asarray(local_rot, dtype=np.float64)
    num_frames = local_rot.shape[0]
    body_pos = np.empty((num_frames, NUM_BODIES, 3))
    body_rot = np.empty((num_frames, NUM_BODIES, 4))
    body_pos[:, 0] = root_pos
    body_rot[:, 0] = rot.quat_normalize(np.asarray(root_rot, dtype=np.float64))
    for b in range(1, NUM_BODIES):
        p = PARENTS[b]
        offset = np.broadcast_to(REST_OFFSETS[b], root_pos.shape)
        body_pos[:, b] = body_pos[:, p] + rot.quat_rotate(body_rot[:, p], offset)
        body_rot[:, b] = rot.quat_normalize(rot.quat_mul(body_rot[:, p], local_rot[:, b]))
    return body_pos, body_rot


def amass_to_model(root_orient: np.ndarray, body_pose: np.ndarray, trans: np.ndarray) -> tuple[np.ndarray, ...]:
    """Convert an AMASS pose sequence to the model frame.

    root_orient (T, 3) and body_pose (T, 63): axis-angle in the template frame, SMPL order (21 body joints after the
    pelvis); trans (T, 3). Returns (root_pos (T, 3), root_rot (T, 4), local_rot (T, 24, 4)) in skeleton order, with
    the hand joints (absent from AMASS's 22 body joints) at rest.
    """
    num_frames = root_orient.shape[0]
    smpl_aa = np.zeros((num_frames, NUM_BODIES, 3))
    smpl_aa[:, 0] = root_orient
    smpl_aa[:, 1:NUM_AMASS_BODY_JOINTS] = body_pose.reshape(num_frames, NUM_AMASS_BODY_JOINTS - 1, 3)
    q_template = rot.quat_from_axis_angle(smpl_aa)[:, BODY_TO_SMPL]  # reorder SMPL -> skeleton order
    local_rot = rot.quat_mul(rot.quat_mul(UPRIGHT_QUAT, q_template), _M_QUAT)  # M^T R_t M
    root_rot = rot.quat_mul(q_template[:, 0], _M_QUAT)  # R_root M
    local_rot[:, 0] = rot.quat_identity()
    root_pos = np.asarray(trans, dtype=np.float64) + PELVIS_J0_TEMPLATE
    return root_pos, rot.quat_normalize(root_rot), rot.quat_normalize(local_rot)


def model_to_amass(
    root_pos: np.ndarray, root_rot: np.ndarray, local_rot: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of ``amass_to_model``: (root_orient (T, 3), body_pose (T, 63), trans (T, 3)); hands are dropped."""
    root_template = rot.quat_mul(root_rot, UPRIGHT_QUAT)  # R_root = Q_root M^T
    local_template = rot.quat_mul(rot.quat_mul(_M_QUAT, local_rot), UPRIGHT_QUAT)  # R_t = M R_model M^T
    smpl_q = local_template[:, SMPL_TO_BODY]  # skeleton order -> SMPL order
    smpl_q[:, 0] = root_template
    aa = rot.quat_to_axis_angle(smpl_q)
    num_frames = aa.shape[0]
    body_pose = aa[:, 1:NUM_AMASS_BODY_JOINTS].reshape(num_frames, 3 * (NUM_AMASS_BODY_JOINTS - 1))
    return aa[:, 0], body_pose, np.asarray(root_pos, dtype=np.float64) - PELVIS_J0_TEMPLATE


def dof_positions(local_rot: np.ndarray) -> np.ndarray:
    """Hinge angles (T, 69): intrinsic x-y-z Euler angles of the 23 non-root local rotations, in [-pi, pi).

    Each rotation has two Euler solutions; this takes the one nearest the rest pose (smaller angle norm), which is
    what a PD target wants (a 2 rad knee bend is (0, 2, 0), not (pi, pi - 2, pi)). The choice only flips where both
    are equally far from rest, which needs rotations far beyond a human joint's range.
    """
    first, second = rot.euler_xyz_candidates(local_rot[:, 1:])  # (T, 23, 3) each
    use_second = np.sum(second**2, -1) < np.sum(first**2, -1)
    out = np.where(use_second[..., None], second, first)
    return out.reshape(local_rot.shape[0], NUM_DOFS)


def dof_velocities(dof_pos: np.ndarray, fps: float) -> np.ndarray:
    """Hinge angle rates (T, 69) by central differences (one-sided at the ends) of the wrapped angle increments."""
    unwrapped = dof_pos[:1] + np.concatenate(
        [np.zeros_like(dof_pos[:1]), np.cumsum(rot.wrap_angle(np.diff(dof_pos, axis=0)), axis=0)]
    )
    return _time_derivative(unwrapped, fps)


def linear_velocities(body_pos: np.ndarray, fps: float) -> np.ndarray:
    """World linear velocities (T, 24, 3) by central differences (one-sided at the ends)."""
    return _time_derivative(body_pos, fps)


def angular_velocities(body_rot: np.ndarray, fps: float) -> np.ndarray:
    """World angular velocities (T, 24, 3): rotation from frame t-1 to t+1 over 2/fps (one-sided at the ends)."""
    num_frames = body_rot.shape[0]
    if num_frames < 2:
        return np.zeros((*body_rot.shape[:-1], 3))
    out = np.empty((*body_rot.shape[:-1], 3))
    out[1:-1] = rot.angular_velocity(body_rot[:-2], body_rot[2:], 2.0 / fps)
    out[0] = rot.angular_velocity(body_rot[0], body_rot[1], 1.0 / fps)
    out[-1] = rot.angular_velocity(body_rot[-2], body_rot[-1], 1.0 / fps)
    return out


def _time_derivative(x: np.ndarray, fps: float) -> np.ndarray:
    if x.shape[0] < 2:
        return np.zeros_like(x)
    return np.gradient(x, 1.0 / fps, axis=0)
