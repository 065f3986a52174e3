"""Per-step kernels of the tracking env: PD targets from actions, imitation reward, termination, the clip-end
truncation, episode metrics, episode starts (reference-state initialisation) and writing a reference state into the
simulator. The episode rules themselves (length, time-out, done, episode sums) are the base env's
(``refpo_warp/envs/episode.py``); here ``episode_length`` is read only, and it still holds the count before the step.

Reward: the named terms of ``reward_terms.py`` (weights and scales from the cfg), the power term off for an
episode's first 3 steps.
"""

from __future__ import annotations

from refpo_warp.motion import skeleton as sk
from refpo_warp.motion.motion_library import MotionFrames
from refpo_warp.tasks.humanoid.model import FREE_COORDS, FREE_DOFS
from refpo_warp.tasks.humanoid.reward_terms import RewardParams, imitation_term, term_vector, write_terms
from refpo_warp.tasks.humanoid.rotation_funcs import com_velocity, origin_velocity, quat_angle
from refpo_warp.utils.warp_setup import wp

NB = wp.constant(sk.NUM_BODIES)
NDOF = wp.constant(sk.NUM_DOFS)
QS = wp.constant(FREE_COORDS)  # first hinge coordinate in joint_q
DS = wp.constant(FREE_DOFS)  # first hinge DoF in joint_qd
POWER_FREE_STEPS = wp.constant(3)
HALF_PI = wp.constant(0.5 * 3.141592653589793)


@wp.kernel
def apply_actions_kernel(
    actions: wp.array2d(dtype=float),
    scale: wp.array(dtype=float),
    frozen: wp.array(dtype=wp.bool),
    residual: int,
    ref: MotionFrames,
    joint_q: wp.array2d(dtype=float),
    joint_target: wp.array2d(dtype=float),
):
    # Absolute: PD target = scale * clip(a, -1, 1). Residual (the reference's res_action): the reference joint angle
    # of the observed frame + scale * clip(a, -1, 1), kept within pi/2 of the current angle. Frozen hand/toe DoFs
    # get target 0 either way.
    i, d = wp.tid()
    a = actions[i, d]
    if not wp.isfinite(a):
        a = 0.0
    target = scale[d] * wp.clamp(a, -1.0, 1.0)
    if residual != 0:
        q = joint_q[i, QS + d]
        target = wp.clamp(ref.dof_pos[i, d] + target, q - HALF_PI, q + HALF_PI)
    if frozen[d]:
        target = 0.0
    joint_target[i, QS + d] = target


@wp.kernel
def advance_time_kernel(
    start_time: wp.array(dtype=float),
    episode_length: wp.array(dtype=wp.int32),
    dt: float,
    ref_time: wp.array(dtype=float),
):
    i = wp.tid()
    ref_time[i] = start_time[i] + float(episode_length[i] + 1) * dt  # the time of the state this step reaches


@wp.func
def choose_start(
    rng: wp.array(dtype=wp.uint32),
    i: int,
    num_clips: int,
    clip_duration: wp.array(dtype=float),
    dt: float,
    eval_mode: int,
    clip_id: wp.array(dtype=int),
    start_time: wp.array(dtype=float),
):
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
    mpjpe_sum: wp.array(dtype=float),
    reset_mask: wp.array(dtype=wp.bool),
):
    i = wp.tid()
    reset_mask[i] = mask[i]
    if mask[i]:
        choose_start(rng, i, num_clips, clip_duration, dt, eval_mode, clip_id, start_time)
        ref_time[i] = start_time[i]
        mpjpe_sum[i] = 0.0


@wp.kernel
def reward_and_termination_kernel(
    body_q: wp.array2d(dtype=wp.transform),
    body_qd: wp.array2d(dtype=wp.spatial_vector),
    body_com: wp.array(dtype=wp.vec3),
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
    joint_target: wp.array2d(dtype=float),
    kp: wp.array(dtype=float),
    kd: wp.array(dtype=float),
    effort_limit: float,
    ref: MotionFrames,
    eval_body: wp.array(dtype=float),
    clip_id: wp.array(dtype=int),
    ref_time: wp.array(dtype=float),
    clip_duration: wp.array(dtype=float),
    episode_length: wp.array(dtype=wp.int32),
    eval_mode: int,
    termination_distance: float,
    eval_termination_distance: float,
    max_joint_speed: float,
    reward: RewardParams,
    mpjpe_sum: wp.array(dtype=float),
    rewards: wp.array(dtype=float),
    terminated: wp.array(dtype=wp.bool),
    clip_end: wp.array(dtype=wp.bool),
    success: wp.array(dtype=float),
    mpjpe_mm: wp.array(dtype=float),
    alive_steps: wp.array(dtype=float),
    reward_terms: wp.array2d(dtype=float),
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
        dp = ref.body_pos[i, b] - pos
        dv = ref.body_vel[i, b] - origin_velocity(body_q[i, b], body_qd[i, b], body_com[b])
        dw = ref.body_angvel[i, b] - wp.spatial_bottom(body_qd[i, b])
        angle = quat_angle(ref.body_rot[i, b] * wp.quat_inverse(rot))
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
    w = reward.weights
    k = reward.scales
    terms = term_vector()
    terms[0] = imitation_term(w[0], k[0], pos_err, 3.0 * n)
    terms[1] = imitation_term(w[1], k[1], rot_err, n)
    terms[2] = imitation_term(w[2], k[2], vel_err, 3.0 * n)
    terms[3] = imitation_term(w[3], k[3], angvel_err, 3.0 * n)

    power = float(0.0)
    fastest = float(0.0)
    for d in range(NDOF):
        q = joint_q[i, QS + d]
        qd = joint_qd[i, DS + d]
        tau = wp.clamp(kp[d] * (joint_target[i, QS + d] - q) - kd[d] * qd, -effort_limit, effort_limit)
        power += wp.abs(tau * qd)
        fastest = wp.max(fastest, wp.abs(qd))
    length = episode_length[i] + 1  # the state just reached is step `length` of the episode
    if length <= POWER_FREE_STEPS:
        power = 0.0
    terms[4] = -reward.power_coef * power
    reward_sum = terms[0] + terms[1] + terms[2] + terms[3] + terms[4]
    # A non-finite or runaway state is a numerical failure: end the episode and keep NaN out of the learner.
    broken = not (fastest <= max_joint_speed) or not wp.isfinite(reward_sum) or not wp.isfinite(sum_dist)
    if broken:
        reward_sum = 0.0
        sum_dist = 0.0
        terms = term_vector()
    write_terms(i, terms, reward_terms)

    if eval_mode != 0:
        lost = eval_dist / wp.max(eval_count, 1.0) > eval_termination_distance
    else:
        lost = max_dist > termination_distance
    term = broken or (lost and length > 1)
    # The end of the clip truncates the episode (the base env's finish_step lets a termination take precedence and
    # adds the time-out; in eval mode max_episode_length is past every clip's end, so only clip ends truncate).
    clip_end[i] = ref_time[i] >= clip_duration[clip_id[i]] - 1.0e-4

    total = mpjpe_sum[i] + sum_dist / n
    mpjpe_sum[i] = total
    rewards[i] = reward_sum
    terminated[i] = term
    success[i] = wp.where(term, 0.0, 1.0)
    mpjpe_mm[i] = 1000.0 * total / float(wp.max(length, 1))
    alive_steps[i] = float(length)


@wp.kernel
def write_reference_state_kernel(
    mask: wp.array(dtype=wp.bool),
    ref: MotionFrames,
    root_com: wp.vec3,
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
):
    # Root: position and xyzw quaternion; Newton's free-joint velocity is the COM's linear velocity + world omega.
    i = wp.tid()
    if not mask[i]:
        return
    p = ref.body_pos[i, 0]
    r = ref.body_rot[i, 0]
    w = ref.body_angvel[i, 0]
    v = com_velocity(r, ref.body_vel[i, 0], w, root_com)
    for a in range(3):
        joint_q[i, a] = p[a]
        joint_qd[i, a] = v[a]
        joint_qd[i, 3 + a] = w[a]
    for a in range(4):
        joint_q[i, 3 + a] = r[a]
    for d in range(NDOF):
        joint_q[i, QS + d] = ref.dof_pos[i, d]
        joint_qd[i, DS + d] = ref.dof_vel[i, d]
