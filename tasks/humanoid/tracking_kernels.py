"""Per-step kernels of the tracking env: PD targets from actions, imitation reward, termination, episode metrics,
episode starts (reference-state initialisation) and writing a reference state into the simulator.

Reward (reference ``compute_imitation_reward``; means over the 24 bodies, and over x/y/z for vectors):
``0.5 exp(-100 mean dp^2) + 0.3 exp(-10 mean angle^2) + 0.1 exp(-0.1 mean dv^2) + 0.1 exp(-0.1 mean dw^2)
- power_coef * sum_dof |tau * qdot|``, the power term off for an episode's first 3 steps.
"""

from __future__ import annotations

from refpo_warp.device import configure_warp
from refpo_warp.motion import skeleton as sk
from tasks.humanoid.model import FREE_COORDS, FREE_DOFS
from tasks.humanoid.rotation_funcs import com_velocity, origin_velocity, quat_angle

wp = configure_warp()

NB = wp.constant(sk.NUM_BODIES)
NDOF = wp.constant(sk.NUM_DOFS)
QS = wp.constant(FREE_COORDS)  # first hinge coordinate in joint_q
DS = wp.constant(FREE_DOFS)  # first hinge DoF in joint_qd
POWER_FREE_STEPS = wp.constant(3)


@wp.kernel
def apply_actions_kernel(
    actions: wp.array2d(dtype=float),
    scale: wp.array(dtype=float),
    joint_target: wp.array2d(dtype=float),
):
    # PD target = scale * clip(a, -1, 1); scale is 0 for frozen hand/toe DoFs (their targets stay at rest).
    i, d = wp.tid()
    a = actions[i, d]
    if not wp.isfinite(a):
        a = 0.0
    joint_target[i, QS + d] = scale[d] * wp.clamp(a, -1.0, 1.0)


@wp.kernel
def advance_time_kernel(
    start_time: wp.array(dtype=float),
    episode_length: wp.array(dtype=wp.int32),
    dt: float,
    ref_time: wp.array(dtype=float),
):
    i = wp.tid()
    length = episode_length[i] + 1
    episode_length[i] = length
    ref_time[i] = start_time[i] + float(length) * dt


@wp.func
def choose_start(rng: wp.array(dtype=wp.uint32), i: int, num_clips: int, clip_duration: wp.array(dtype=float),
                 dt: float, eval_mode: int, clip_id: wp.array(dtype=int),
                 start_time: wp.array(dtype=float)):  # fmt: skip
    """Eval: env i plays clip i from its start. Train: a uniformly random clip at a uniformly random time that
    leaves at least one control step."""
    if eval_mode != 0:
        clip_id[i] = i % num_clips
        start_time[i] = 0.0
    else:
        state = rng[i]
        clip = wp.randi(state, 0, num_clips)
        start_time[i] = wp.randf(state) * wp.max(clip_duration[clip] - dt, 0.0)
        rng[i] = state
        clip_id[i] = clip


@wp.kernel
def start_episodes_kernel(
    mask: wp.array(dtype=wp.bool),
    rng: wp.array(dtype=wp.uint32),
    num_clips: int,
    clip_duration: wp.array(dtype=float),
    dt: float,
    eval_mode: int,
    clip_id: wp.array(dtype=int),
    start_time: wp.array(dtype=float),
    ref_time: wp.array(dtype=float),
    episode_length: wp.array(dtype=wp.int32),
    mpjpe_sum: wp.array(dtype=float),
    reset_mask: wp.array(dtype=wp.bool),
):
    i = wp.tid()
    reset_mask[i] = mask[i]
    if mask[i]:
        choose_start(rng, i, num_clips, clip_duration, dt, eval_mode, clip_id, start_time)
        ref_time[i] = start_time[i]
        episode_length[i] = 0
        mpjpe_sum[i] = 0.0


@wp.kernel
def evaluate_step_kernel(
    body_q: wp.array2d(dtype=wp.transform),
    body_qd: wp.array2d(dtype=wp.spatial_vector),
    body_com: wp.array(dtype=wp.vec3),
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
    joint_target: wp.array2d(dtype=float),
    kp: wp.array(dtype=float),
    kd: wp.array(dtype=float),
    effort_limit: float,
    ref_pos: wp.array2d(dtype=wp.vec3),
    ref_rot: wp.array2d(dtype=wp.quat),
    ref_vel: wp.array2d(dtype=wp.vec3),
    ref_angvel: wp.array2d(dtype=wp.vec3),
    eval_body: wp.array(dtype=float),
    clip_id: wp.array(dtype=int),
    ref_time: wp.array(dtype=float),
    clip_duration: wp.array(dtype=float),
    episode_length: wp.array(dtype=wp.int32),
    max_episode_length: int,
    eval_mode: int,
    termination_distance: float,
    eval_termination_distance: float,
    max_joint_speed: float,
    power_coef: float,
    mpjpe_sum: wp.array(dtype=float),
    rewards: wp.array(dtype=float),
    terminated: wp.array(dtype=wp.bool),
    truncated: wp.array(dtype=wp.bool),
    done_mask: wp.array(dtype=wp.bool),
    success: wp.array(dtype=float),
    mpjpe_mm: wp.array(dtype=float),
    alive_steps: wp.array(dtype=float),
):
    i = wp.tid()
    pos_err = float(0.0)
    rot_err = float(0.0)
    vel_err = float(0.0)
    angvel_err = float(0.0)
    max_dist = float(0.0)
    sum_dist = float(0.0)
    eval_dist = float(0.0)
    eval_count = float(0.0)
    for b in range(NB):
        pos = wp.transform_get_translation(body_q[i, b])
        rot = wp.transform_get_rotation(body_q[i, b])
        dp = ref_pos[i, b] - pos
        dv = ref_vel[i, b] - origin_velocity(body_q[i, b], body_qd[i, b], body_com[b])
        dw = ref_angvel[i, b] - wp.spatial_bottom(body_qd[i, b])
        angle = quat_angle(ref_rot[i, b] * wp.quat_inverse(rot))
        dist = wp.length(dp)
        pos_err += wp.dot(dp, dp)
        rot_err += angle * angle
        vel_err += wp.dot(dv, dv)
        angvel_err += wp.dot(dw, dw)
        max_dist = wp.max(max_dist, dist)
        sum_dist += dist
        eval_dist += eval_body[b] * dist
        eval_count += eval_body[b]
    n = float(NB)
    imitation = (0.5 * wp.exp(-100.0 * pos_err / (3.0 * n)) + 0.3 * wp.exp(-10.0 * rot_err / n)
                 + 0.1 * wp.exp(-0.1 * vel_err / (3.0 * n)) + 0.1 * wp.exp(-0.1 * angvel_err / (3.0 * n)))  # fmt: skip

    power = float(0.0)
    fastest = float(0.0)
    for d in range(NDOF):
        q = joint_q[i, QS + d]
        qd = joint_qd[i, DS + d]
        tau = wp.clamp(kp[d] * (joint_target[i, QS + d] - q) - kd[d] * qd, -effort_limit, effort_limit)
        power += wp.abs(tau * qd)
        fastest = wp.max(fastest, wp.abs(qd))
    length = episode_length[i]
    if length <= POWER_FREE_STEPS:
        power = 0.0
    reward = imitation - power_coef * power
    # A non-finite or runaway state is a numerical failure: end the episode and keep NaN out of the learner.
    broken = not (fastest <= max_joint_speed) or not wp.isfinite(reward) or not wp.isfinite(sum_dist)
    if broken:
        reward = 0.0
        sum_dist = 0.0

    if eval_mode != 0:
        lost = eval_dist / wp.max(eval_count, 1.0) > eval_termination_distance
    else:
        lost = max_dist > termination_distance
    term = broken or (lost and length > 1)
    clip_end = ref_time[i] >= clip_duration[clip_id[i]] - 1.0e-4
    trunc = (not term) and (clip_end or (eval_mode == 0 and length >= max_episode_length))

    total = mpjpe_sum[i] + sum_dist / n
    mpjpe_sum[i] = total
    rewards[i] = reward
    terminated[i] = term
    truncated[i] = trunc
    done_mask[i] = term or trunc
    success[i] = wp.where(term, 0.0, 1.0)
    mpjpe_mm[i] = 1000.0 * total / float(wp.max(length, 1))
    alive_steps[i] = float(length)


@wp.kernel
def write_reference_state_kernel(
    mask: wp.array(dtype=wp.bool),
    ref_pos: wp.array2d(dtype=wp.vec3),
    ref_rot: wp.array2d(dtype=wp.quat),
    ref_vel: wp.array2d(dtype=wp.vec3),
    ref_angvel: wp.array2d(dtype=wp.vec3),
    ref_dof_pos: wp.array2d(dtype=float),
    ref_dof_vel: wp.array2d(dtype=float),
    root_com: wp.vec3,
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
):
    # Root: position and xyzw quaternion; Newton's free-joint velocity is the COM's linear velocity + world omega.
    i = wp.tid()
    if not mask[i]:
        return
    p = ref_pos[i, 0]
    r = ref_rot[i, 0]
    w = ref_angvel[i, 0]
    v = com_velocity(r, ref_vel[i, 0], w, root_com)
    for a in range(3):
        joint_q[i, a] = p[a]
        joint_qd[i, a] = v[a]
        joint_qd[i, 3 + a] = w[a]
    for a in range(4):
        joint_q[i, 3 + a] = r[a]
    for d in range(NDOF):
        joint_q[i, QS + d] = ref_dof_pos[i, d]
        joint_qd[i, DS + d] = ref_dof_vel[i, d]
