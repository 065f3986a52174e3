"""One motion clip at the library's frame rate, and the pipeline that builds it from a root pose and per-body local
rotations at any source rate: resample by time, forward kinematics, ground-height fix, velocities, hinge angles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refpo_warp.motion import kinematics as kin
from refpo_warp.motion import rotations as rot
from refpo_warp.motion.limits import resampled_frame_count
from refpo_warp.motion.skeleton import BODY_NAMES, FOOT_BODIES, FOOT_SOLE_DEPTH

FOOT_INDICES = np.array([BODY_NAMES.index(n) for n in FOOT_BODIES])
HEIGHT_FIX_WINDOW_S = 1.0  # ground the clip on its first second: later frames may climb stairs or jump


@dataclass
class MotionClip:
    """Reference states of one clip at ``fps`` (arrays over T frames, bodies in skeleton order, world z-up frame)."""

    name: str
    fps: float
    body_pos: np.ndarray  # (T, 24, 3)
    body_rot: np.ndarray  # (T, 24, 4) xyzw
    body_vel: np.ndarray  # (T, 24, 3)
    body_angvel: np.ndarray  # (T, 24, 3)
    dof_pos: np.ndarray  # (T, 69)
    dof_vel: np.ndarray  # (T, 69)

    @property
    def num_frames(self) -> int:
        return self.body_pos.shape[0]


def resample(
    root_pos: np.ndarray, root_rot: np.ndarray, local_rot: np.ndarray, src_fps: float, fps: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Resample a pose sequence by time to ``fps``: frame k is at k / fps seconds, up to the source duration.

    Positions are interpolated linearly, rotations (root and local) by slerp between the two source frames that
    bracket each time.
    """
    num_src = root_pos.shape[0]
    num_out = resampled_frame_count(num_src, src_fps, fps)
    src_index = np.minimum(np.arange(num_out) * (src_fps / fps), num_src - 1)
    i0 = np.floor(src_index).astype(np.int64)
    i1 = np.minimum(i0 + 1, num_src - 1)
    alpha = src_index - i0
    pos = (1.0 - alpha)[:, None] * root_pos[i0] + alpha[:, None] * root_pos[i1]
    root = rot.quat_slerp(root_rot[i0], root_rot[i1], alpha)
    local = rot.quat_slerp(local_rot[i0], local_rot[i1], alpha[:, None])
    return pos, root, local


def sole_heights(body_pos: np.ndarray) -> np.ndarray:
    """Height (T,) of the lowest foot sole point: min over ankle/toe joints of z minus the joint's sole depth."""
    return np.min(body_pos[:, FOOT_INDICES, 2] - FOOT_SOLE_DEPTH, axis=1)


def ground_offset(body_pos: np.ndarray, fps: float) -> float:
    """Vertical shift that puts the lowest sole point of the clip's first second on the ground (z = 0)."""
    window = min(body_pos.shape[0], int(round(HEIGHT_FIX_WINDOW_S * fps)) + 1)
    return -float(np.min(sole_heights(body_pos[:window])))


def build_clip(
    name: str,
    root_pos: np.ndarray,
    root_rot: np.ndarray,
    local_rot: np.ndarray,
    src_fps: float,
    fps: float,
) -> MotionClip:
    """Full pipeline for one clip given in the model frame (see ``kinematics.amass_to_model``)."""
    root_rot = rot.quat_make_continuous(rot.quat_normalize(root_rot))
    local_rot = rot.quat_make_continuous(rot.quat_normalize(local_rot))
    root_pos, root_rot, local_rot = resample(root_pos, root_rot, local_rot, src_fps, fps)
    body_pos, body_rot = kin.forward_kinematics(root_pos, root_rot, local_rot)
    body_pos[..., 2] += ground_offset(body_pos, fps)
    body_rot = rot.quat_make_continuous(body_rot)
    dof_pos = kin.dof_positions(local_rot)
    return MotionClip(
        name=name,
        fps=float(fps),
        body_pos=body_pos,
        body_rot=body_rot,
        body_vel=kin.linear_velocities(body_pos, fps),
        body_angvel=kin.angular_velocities(body_rot, fps),
        dof_pos=dof_pos,
        dof_vel=kin.dof_velocities(dof_pos, fps),
    )
