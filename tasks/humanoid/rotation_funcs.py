"""Warp rotation helpers of the tracking observations and reward (quaternions xyzw, z up).

Heading: the yaw of a body's forward (+x) axis projected on the ground plane; observations are expressed in the
frame that undoes the root's heading, so they do not change when the whole scene turns about the vertical axis.
Tangent-normal ("tan-norm") 6D: a rotation written as its images of the x axis and of the z axis.
"""

from __future__ import annotations

from refpo_warp.utils.warp_setup import wp


@wp.func
def heading_angle(q: wp.quat) -> float:
    forward = wp.quat_rotate(q, wp.vec3(1.0, 0.0, 0.0))
    return wp.atan2(forward[1], forward[0])


@wp.func
def heading_inverse(q: wp.quat) -> wp.quat:
    """The rotation about +z that cancels the heading of ``q``."""
    return wp.quat_from_axis_angle(wp.vec3(0.0, 0.0, 1.0), -heading_angle(q))


@wp.func
def quat_angle(q: wp.quat) -> float:
    """Rotation angle of ``q`` in [0, pi] (q and -q are the same rotation)."""
    v = wp.vec3(q[0], q[1], q[2])
    return 2.0 * wp.atan2(wp.length(v), wp.abs(q[3]))


@wp.func
def tangent(q: wp.quat) -> wp.vec3:
    """First half of the tan-norm 6D encoding: the rotated x axis."""
    return wp.quat_rotate(q, wp.vec3(1.0, 0.0, 0.0))


@wp.func
def normal(q: wp.quat) -> wp.vec3:
    """Second half of the tan-norm 6D encoding: the rotated z axis."""
    return wp.quat_rotate(q, wp.vec3(0.0, 0.0, 1.0))


@wp.func
def origin_velocity(body_q: wp.transform, body_qd: wp.spatial_vector, com_local: wp.vec3) -> wp.vec3:
    """Linear velocity of a body frame's origin from Newton's body twist (COM linear velocity, angular velocity)."""
    omega = wp.spatial_bottom(body_qd)
    com_offset = wp.quat_rotate(wp.transform_get_rotation(body_q), com_local)
    return wp.spatial_top(body_qd) - wp.cross(omega, com_offset)


@wp.func
def com_velocity(rot: wp.quat, origin_vel: wp.vec3, omega: wp.vec3, com_local: wp.vec3) -> wp.vec3:
    """Inverse of ``origin_velocity``: the COM linear velocity of a body moving with its origin's velocity."""
    return origin_vel + wp.cross(omega, wp.quat_rotate(rot, com_local))
