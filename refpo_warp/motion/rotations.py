"""Vectorised numpy rotation helpers. Quaternions are xyzw (the Warp/Newton order); every function broadcasts over
leading axes, so ``q`` may be (4,), (T, 4), (T, J, 4), ...
"""

from __future__ import annotations

import numpy as np

_EPS = 1e-12


def quat_identity(shape: tuple[int, ...] = ()) -> np.ndarray:
    q = np.zeros((*shape, 4))
    q[..., 3] = 1.0
    return q


def quat_normalize(q: np.ndarray) -> np.ndarray:
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    return np.concatenate([-q[..., :3], q[..., 3:]], axis=-1)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b (apply b first, then a)."""
    av, aw = a[..., :3], a[..., 3:]
    bv, bw = b[..., :3], b[..., 3:]
    xyz = aw * bv + bw * av + np.cross(av, bv)
    w = aw * bw - np.sum(av * bv, axis=-1, keepdims=True)
    return np.concatenate([xyz, np.broadcast_to(w, (*xyz.shape[:-1], 1))], axis=-1)


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4)."""
    qv, qw = q[..., :3], q[..., 3:]
    t = 2.0 * np.cross(qv, v)
    return v + qw * t + np.cross(qv, t)


def quat_from_axis_angle(aa: np.ndarray) -> np.ndarray:
    """Axis-angle vectors (..., 3) (direction = axis, norm = angle in radians) to unit quaternions."""
    aa = np.asarray(aa, dtype=np.float64)
    angle = np.linalg.norm(aa, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(half)/angle -> 1/2 as angle -> 0; the Taylor form keeps tiny angles exact.
    small = angle < 1e-8
    scale = np.where(small, 0.5 - angle**2 / 48.0, np.sin(half) / np.where(small, 1.0, angle))
    return np.concatenate([aa * scale, np.cos(half)], axis=-1)


def quat_to_axis_angle(q: np.ndarray) -> np.ndarray:
    """Unit quaternions to axis-angle vectors with angle in [0, pi] (the shorter of q and -q)."""
    q = np.where(q[..., 3:] < 0.0, -q, q)
    sin_half = np.linalg.norm(q[..., :3], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(sin_half, q[..., 3:])
    small = sin_half < 1e-8
    scale = np.where(small, 2.0 / np.maximum(q[..., 3:], _EPS), angle / np.where(small, 1.0, sin_half))
    return q[..., :3] * scale


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    x, y, z, w = (q[..., i] for i in range(4))
    m = np.empty((*q.shape[:-1], 3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - z * w)
    m[..., 0, 2] = 2 * (x * z + y * w)
    m[..., 1, 0] = 2 * (x * y + z * w)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - x * w)
    m[..., 2, 0] = 2 * (x * z - y * w)
    m[..., 2, 1] = 2 * (y * z + x * w)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m


def quat_from_matrix(m: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) to unit quaternions with w >= 0 (Shepperd's method, branch per element)."""
    m = np.asarray(m, dtype=np.float64)
    trace = m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2]
    # Four candidate solutions; use the one whose pivot (largest of 1+trace, 1+2*m_ii-trace) is biggest.
    cands = np.stack(
        [
            np.stack([m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1],
                      1 + trace], -1),
            np.stack([1 + 2 * m[..., 0, 0] - trace, m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0],
                      m[..., 2, 1] - m[..., 1, 2]], -1),
            np.stack([m[..., 0, 1] + m[..., 1, 0], 1 + 2 * m[..., 1, 1] - trace, m[..., 1, 2] + m[..., 2, 1],
                      m[..., 0, 2] - m[..., 2, 0]], -1),
            np.stack([m[..., 0, 2] + m[..., 2, 0], m[..., 1, 2] + m[..., 2, 1], 1 + 2 * m[..., 2, 2] - trace,
                      m[..., 1, 0] - m[..., 0, 1]], -1),
        ],
        axis=-2,
    )  # fmt: skip  # one row per matrix row
    pivots = np.stack(
        [1 + trace, 1 + 2 * m[..., 0, 0] - trace, 1 + 2 * m[..., 1, 1] - trace, 1 + 2 * m[..., 2, 2] - trace], -1
    )
    best = np.argmax(pivots, axis=-1)
    q = np.take_along_axis(cands, best[..., None, None], axis=-2)[..., 0, :]
    q = quat_normalize(q)
    return np.where(q[..., 3:] < 0.0, -q, q)


def quat_from_euler_xyz(angles: np.ndarray) -> np.ndarray:
    """Intrinsic x-y-z Euler angles (..., 3) to quaternions: R = Rx(a0) * Ry(a1) * Rz(a2)."""
    angles = np.asarray(angles, dtype=np.float64)
    axes = np.eye(3)
    qs = [quat_from_axis_angle(angles[..., i : i + 1] * axes[i]) for i in range(3)]
    return quat_mul(quat_mul(qs[0], qs[1]), qs[2])


def euler_xyz_candidates(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both intrinsic x-y-z Euler solutions (..., 3) of the rotations q, each angle in [-pi, pi].

    R = Rx(a) Ry(b) Rz(c) has R02 = sin b, R12 = -sin a cos b, R22 = cos a cos b, R01 = -cos b sin c,
    R00 = cos b cos c; the second solution is (a + pi, pi - b, c + pi). At b = +-pi/2 only a -+ c is defined;
    c is then set to 0.
    """
    m = quat_to_matrix(q)
    sin_b = np.clip(m[..., 0, 2], -1.0, 1.0)
    cos_b = np.sqrt(np.maximum(0.0, 1.0 - sin_b**2))
    locked = cos_b < 1e-9
    a = np.where(locked, np.arctan2(m[..., 2, 1], m[..., 1, 1]), np.arctan2(-m[..., 1, 2], m[..., 2, 2]))
    b = np.arctan2(sin_b, cos_b)
    c = np.where(locked, 0.0, np.arctan2(-m[..., 0, 1], m[..., 0, 0]))
    first = np.stack([a, b, c], axis=-1)
    second = wrap_angle(np.stack([a + np.pi, np.pi - b, c + np.pi], axis=-1))
    return first, second


def wrap_angle(x: np.ndarray) -> np.ndarray:
    """Wrap angles to [-pi, pi)."""
    return (np.asarray(x) + np.pi) % (2.0 * np.pi) - np.pi


def quat_make_continuous(q: np.ndarray, axis: int = 0) -> np.ndarray:
    """Flip signs along ``axis`` (time) so consecutive quaternions lie in the same hemisphere (q and -q are the
    same rotation; interpolation needs neighbours with a positive dot product)."""
    q = np.moveaxis(np.asarray(q, dtype=np.float64), axis, 0)
    # Frame t keeps its sign iff an even number of sign changes happened between frames 0..t.
    changes = np.sum(q[1:] * q[:-1], axis=-1, keepdims=True) < 0.0
    parity = np.concatenate([np.zeros_like(changes[:1]), np.cumsum(changes, axis=0) % 2 == 1])
    return np.moveaxis(np.where(parity, -q, q), 0, axis)


def quat_slerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation along the shorter arc; t broadcasts as (..., 1) or scalar."""
    t = np.asarray(t, dtype=np.float64)
    if t.ndim == q0.ndim - 1:
        t = t[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0.0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-6  # nearly identical rotations: linear interpolation is exact to first order
    safe = np.where(near, 1.0, sin_theta)
    w0 = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / safe)
    w1 = np.where(near, t, np.sin(t * theta) / safe)
    return quat_normalize(w0 * q0 + w1 * q1)


def angular_velocity(q_from: np.ndarray, q_to: np.ndarray, dt: float | np.ndarray) -> np.ndarray:
    """World-frame angular velocity that turns q_from into q_to in dt seconds (constant rate, shorter arc)."""
    return quat_to_axis_angle(quat_mul(q_to, quat_conjugate(q_from))) / dt
