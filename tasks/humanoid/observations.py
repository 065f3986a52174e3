"""Observation kernel of the tracking env: the 934-dim self + task observation (layout: ``obs_layout.py``).

One thread per (env, body) writes that body's entries of every block, in the heading frame of the simulated root.
The critic group gets the full observation, the policy group the same values times the conditioning mask.
"""

from __future__ import annotations

from refpo_warp.motion.motion_library import MotionFrames
from refpo_warp.tasks.humanoid.obs_layout import OFFSET
from refpo_warp.tasks.humanoid.rotation_funcs import heading_inverse, normal, origin_velocity, tangent
from refpo_warp.utils.warp_setup import wp

O_BODY_POS = wp.constant(OFFSET["body_pos"])
O_BODY_ROT = wp.constant(OFFSET["body_rot"])
O_BODY_VEL = wp.constant(OFFSET["body_vel"])
O_BODY_ANGVEL = wp.constant(OFFSET["body_angvel"])
O_DIFF_POS = wp.constant(OFFSET["diff_pos"])
O_DIFF_ROT = wp.constant(OFFSET["diff_rot"])
O_DIFF_VEL = wp.constant(OFFSET["diff_vel"])
O_DIFF_ANGVEL = wp.constant(OFFSET["diff_angvel"])
O_REF_POS = wp.constant(OFFSET["ref_pos"])
O_REF_ROT = wp.constant(OFFSET["ref_rot"])


@wp.func
def put(
    critic: wp.array2d(dtype=float),
    policy: wp.array2d(dtype=float),
    mask: wp.array(dtype=float),
    i: int,
    k: int,
    value: float,
):
    critic[i, k] = value
    policy[i, k] = value * mask[k]


@wp.func
def put3(
    critic: wp.array2d(dtype=float),
    policy: wp.array2d(dtype=float),
    mask: wp.array(dtype=float),
    i: int,
    k: int,
    v: wp.vec3,
):
    for a in range(3):
        put(critic, policy, mask, i, k + a, v[a])


@wp.func
def put6(
    critic: wp.array2d(dtype=float),
    policy: wp.array2d(dtype=float),
    mask: wp.array(dtype=float),
    i: int,
    k: int,
    q: wp.quat,
):
    put3(critic, policy, mask, i, k, tangent(q))
    put3(critic, policy, mask, i, k + 3, normal(q))


@wp.kernel
def observation_kernel(
    body_q: wp.array2d(dtype=wp.transform),
    body_qd: wp.array2d(dtype=wp.spatial_vector),
    body_com: wp.array(dtype=wp.vec3),
    ref: MotionFrames,
    mask: wp.array(dtype=float),
    critic: wp.array2d(dtype=float),
    policy: wp.array2d(dtype=float),
):
    i, b = wp.tid()
    root_pos = wp.transform_get_translation(body_q[i, 0])
    hinv = heading_inverse(wp.transform_get_rotation(body_q[i, 0]))
    heading = wp.quat_inverse(hinv)

    pos = wp.transform_get_translation(body_q[i, b])
    rot = wp.transform_get_rotation(body_q[i, b])
    vel = origin_velocity(body_q[i, b], body_qd[i, b], body_com[b])
    angvel = wp.spatial_bottom(body_qd[i, b])

    # Self observation.
    if b == 0:
        put(critic, policy, mask, i, 0, root_pos[2])
    else:
        put3(critic, policy, mask, i, O_BODY_POS + 3 * (b - 1), wp.quat_rotate(hinv, pos - root_pos))
    put6(critic, policy, mask, i, O_BODY_ROT + 6 * b, hinv * rot)
    put3(critic, policy, mask, i, O_BODY_VEL + 3 * b, wp.quat_rotate(hinv, vel))
    put3(critic, policy, mask, i, O_BODY_ANGVEL + 3 * b, wp.quat_rotate(hinv, angvel))

    # Task observation against the reference one control step ahead.
    rp = ref.body_pos[i, b]
    rr = ref.body_rot[i, b]
    put3(critic, policy, mask, i, O_DIFF_POS + 3 * b, wp.quat_rotate(hinv, rp - pos))
    put6(critic, policy, mask, i, O_DIFF_ROT + 6 * b, hinv * (rr * wp.quat_inverse(rot)) * heading)
    put3(critic, policy, mask, i, O_DIFF_VEL + 3 * b, wp.quat_rotate(hinv, ref.body_vel[i, b] - vel))
    put3(critic, policy, mask, i, O_DIFF_ANGVEL + 3 * b, wp.quat_rotate(hinv, ref.body_angvel[i, b] - angvel))
    put3(critic, policy, mask, i, O_REF_POS + 3 * b, wp.quat_rotate(hinv, rp - root_pos))
    put6(critic, policy, mask, i, O_REF_ROT + 6 * b, hinv * rr)
