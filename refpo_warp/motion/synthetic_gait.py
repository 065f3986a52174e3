"""Walking (straight or turning) by foot placement and leg inverse kinematics.

The pelvis follows a straight or circular path at the clip's speed. Each foot alternates a stance phase on a
footprint placed beside the pelvis at mid-stance (landing toe-up and rolling down about the heel, flat, then
lifting the heel and rolling about the toe joint) and a swing phase that carries it to the next footprint along a
raised arc. Hips and knees are solved analytically to reach the ankle targets; ankles set the foot's heading and
pitch; arms and spine swing against the legs. The pelvis height is the highest that keeps every foot on the
ground within reach, smoothed over time from below (which gives the vertical bob of a walk); a swinging foot rises
where that height would pull its leg straight.
"""

from __future__ import annotations

import numpy as np

from refpo_warp.motion import rotations as rot
from refpo_warp.motion.skeleton import BODY_NAMES, FOOT_BODIES, FOOT_SOLE_DEPTH, HEEL_BEHIND_ANKLE, REST_OFFSETS

SWING_FRACTION = 0.4  # of each gait cycle per foot; the rest is stance (two double-support phases of 0.1)
SWING_CLEARANCE = 0.06  # m, peak ankle lift above its stance height (scaled up with speed)
REACH_MARGIN = 0.985  # fraction of the full leg length a hip-ankle distance may use
HEIGHT_SMOOTHING_S = 0.04  # s, Gaussian width of the pelvis height smoothing
_LEGS = (("L", 0.0), ("R", 0.5))  # side, gait phase offset (cycles)
STRIKE_END, PUSH_START = 0.15, 0.7  # stance progress: heel roll until STRIKE_END, heel lift from PUSH_START


def _idx(name: str) -> int:
    return BODY_NAMES.index(name)


def _rest_ankle_offset(side: str) -> np.ndarray:
    return REST_OFFSETS[[_idx(f"{side}_Hip"), _idx(f"{side}_Knee"), _idx(f"{side}_Ankle")]].sum(axis=0)


ANKLE_SOLE_DEPTH = {side: FOOT_SOLE_DEPTH[FOOT_BODIES.index(f"{side}_Ankle")] for side in "LR"}
# Standing pelvis height with straight legs and flat feet (the lower of the two sides).
STANDING_PELVIS_HEIGHT = min(-_rest_ankle_offset(s)[2] + ANKLE_SOLE_DEPTH[s] for s in "LR")


def _yaw_quat(yaw: np.ndarray) -> np.ndarray:
    return rot.quat_from_axis_angle(np.asarray(yaw)[..., None] * np.array([0.0, 0.0, 1.0]))


def _pitch_quat(pitch: np.ndarray) -> np.ndarray:
    return rot.quat_from_axis_angle(np.asarray(pitch)[..., None] * np.array([0.0, 1.0, 0.0]))


def _path(times: np.ndarray, speed: float, heading: float, turn_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Pelvis xy (T, 2) and heading (T,) on a straight line or a circle through the origin."""
    yaw = heading + turn_rate * times
    if abs(turn_rate) < 1e-9:
        xy = speed * times[:, None] * np.array([np.cos(heading), np.sin(heading)])
    else:
        r = speed / turn_rate
        xy = np.stack([r * (np.sin(yaw) - np.sin(heading)), -r * (np.cos(yaw) - np.cos(heading))], axis=1)
    return xy, yaw


def _smooth(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _pivot_pose(side: str, footprint: np.ndarray, yaw: np.ndarray, sigma: np.ndarray, speed: float):
    """Ankle position and foot pitch at stance progress sigma in [0, 1] on a footprint (flat ankle position):
    the foot lands toe-up and rolls down about the heel, stays flat, then lifts the heel rolling about the toe
    joint."""
    strike_pitch, push_pitch = -(0.15 + 0.1 * speed), 0.3 + 0.3 * speed  # about y: > 0 lifts the heel
    striking = sigma < STRIKE_END
    pitch = np.where(
        striking,
        strike_pitch * (1.0 - _smooth(sigma / STRIKE_END)),
        push_pitch * _smooth((sigma - PUSH_START) / (1.0 - PUSH_START)),
    )
    pivot = np.where(striking[:, None], _heel_point(side), _toe_joint(side))
    pitch_rot = _pitch_quat(pitch)
    # The pivot stays where it is on the flat foot; the ankle swings around it.
    ankle = footprint + rot.quat_rotate(_yaw_quat(yaw), pivot - rot.quat_rotate(pitch_rot, pivot))
    return ankle, pitch


def _heel_point(side: str) -> np.ndarray:
    return np.array([HEEL_BEHIND_ANKLE, 0.0, -ANKLE_SOLE_DEPTH[side]])


def _toe_joint(side: str) -> np.ndarray:
    # The foot rolls about the toe joint while the toe segment stays flat on the ground.
    return REST_OFFSETS[_idx(f"{side}_Toe")]


def _feet(t: np.ndarray, spec, side: str, offset: float) -> tuple[np.ndarray, ...]:
    """Ankle targets (T, 3), foot headings (T,), foot pitch (T,) and toe flexion (T,) of one leg."""
    cycles = spec.gait_freq * t + spec.phase / (2.0 * np.pi) + offset
    n = np.floor(cycles)
    u = cycles - n

    def footprint(cycle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # The stance of cycle n spans u in [SWING_FRACTION, 1); the pelvis passes over the foot at mid-stance.
        t_mid = (cycle + 0.5 * (1.0 + SWING_FRACTION) - spec.phase / (2.0 * np.pi) - offset) / spec.gait_freq
        xy, yaw = _path(t_mid, spec.speed, spec.heading, spec.turn_rate)
        ankle = np.concatenate([xy, np.full((xy.shape[0], 1), ANKLE_SOLE_DEPTH[side])], axis=1)
        return ankle + rot.quat_rotate(_yaw_quat(yaw), _rest_ankle_offset(side) * np.array([1.0, 1.0, 0.0])), yaw

    # Stance on footprint n; swing (u < SWING_FRACTION) from the end of stance n-1 to the start of stance n.
    print_now, yaw_now = footprint(n)
    print_prev, yaw_prev = footprint(n - 1)
    stance = u >= SWING_FRACTION
    sigma = (u - SWING_FRACTION) / (1.0 - SWING_FRACTION)
    stance_ankle, stance_pitch = _pivot_pose(side, print_now, yaw_now, sigma, spec.speed)
    lift_off, off_pitch = _pivot_pose(side, print_prev, yaw_prev, np.ones_like(u), spec.speed)
    touch_down, on_pitch = _pivot_pose(side, print_now, yaw_now, np.zeros_like(u), spec.speed)
    s = _smooth(u / SWING_FRACTION)
    lift = np.sin(np.pi * np.clip(u / SWING_FRACTION, 0.0, 1.0)) ** 2 * SWING_CLEARANCE * (0.6 + 0.4 * spec.speed)
    swing_ankle = lift_off + s[:, None] * (touch_down - lift_off) + lift[:, None] * np.array([0.0, 0.0, 1.0])
    ankle = np.where(stance[:, None], stance_ankle, swing_ankle)
    yaw = np.where(stance, yaw_now, yaw_prev + s * rot.wrap_angle(yaw_now - yaw_prev))
    pitch = np.where(stance, stance_pitch, off_pitch + s * (on_pitch - off_pitch))
    # The toes stay flat while the heel is up, then straighten during the swing.
    toe = np.where(stance, -np.maximum(stance_pitch, 0.0), -off_pitch * (1.0 - s))
    return ankle, yaw, pitch, toe


def _knee_angle(side: str, distance: np.ndarray) -> np.ndarray:
    """Knee flexion about y that puts the ankle ``distance`` from the hip (straight where out of reach)."""
    k_off, a_off = REST_OFFSETS[_idx(f"{side}_Knee")], REST_OFFSETS[_idx(f"{side}_Ankle")]
    # |k + Ry(q) a|^2 = |k|^2 + |a|^2 + 2 (k_y a_y + P cos q + Q sin q)
    p = k_off[0] * a_off[0] + k_off[2] * a_off[2]
    q = k_off[0] * a_off[2] - k_off[2] * a_off[0]
    amp, delta = np.hypot(p, q), np.arctan2(q, p)
    c = (distance**2 - k_off @ k_off - a_off @ a_off - 2.0 * k_off[1] * a_off[1]) / (2.0 * amp)
    return delta + np.arccos(np.clip(c, -1.0, 1.0))


def _leg_reach(side: str) -> float:
    return float(np.linalg.norm(REST_OFFSETS[_idx(f"{side}_Knee")] + REST_OFFSETS[_idx(f"{side}_Ankle")]))


def _root_rotation(t: np.ndarray, spec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pelvis world rotation, its yaw, and how far forward the left leg is (~ cos of the gait phase)."""
    _, heading = _path(t, spec.speed, spec.heading, spec.turn_rate)
    # Left leg forward of the pelvis ~ cos(2 pi (u_L - 0.4)); arms and pelvis yaw follow that rhythm.
    left_forward = np.cos(2.0 * np.pi * (spec.gait_freq * t - SWING_FRACTION) + spec.phase)
    yaw = heading + 0.06 * spec.speed * left_forward  # the pelvis turns with the swinging leg
    lean = rot.quat_from_axis_angle(np.array([0.0, 0.04 * spec.speed, 0.0]))  # lean into the walk
    return rot.quat_mul(_yaw_quat(yaw), lean), yaw, left_forward


def _stance_limit(t: np.ndarray, spec) -> np.ndarray:
    """Highest pelvis height (T,) at which every foot on the ground stays within the leg's reach (and not above
    the standing height)."""
    pelvis_xy, _ = _path(t, spec.speed, spec.heading, spec.turn_rate)
    root_rot, _, _ = _root_rotation(t, spec)
    limit = np.full(t.size, STANDING_PELVIS_HEIGHT - 0.01)
    for side, offset in _LEGS:
        u = np.mod(spec.gait_freq * t + spec.phase / (2.0 * np.pi) + offset, 1.0)
        hip = rot.quat_rotate(root_rot, REST_OFFSETS[_idx(f"{side}_Hip")])
        ankle = _feet(t, spec, side, offset)[0]
        horizontal = np.linalg.norm(ankle[:, :2] - (pelvis_xy + hip[:, :2]), axis=1)
        reach = REACH_MARGIN * _leg_reach(side)
        leg_limit = ankle[:, 2] + np.sqrt(np.maximum(reach**2 - horizontal**2, 0.0)) - hip[:, 2]
        limit = np.where(u >= SWING_FRACTION, np.minimum(limit, leg_limit), limit)
    return limit


def _pelvis_height(t: np.ndarray, spec) -> np.ndarray:
    """A smooth pelvis height below the stance limit: the limit's running minimum over +-3 sigma, then a
    Gaussian average over the same window (each average is of values at most the limit at its centre). Computed
    on a fixed fine time grid so the motion does not depend on the frame rate it is sampled at."""
    dt, reach = 1.0 / 600.0, 3.0 * HEIGHT_SMOOTHING_S
    fine = np.arange(t[0] - 2 * reach, t[-1] + 2 * reach + dt, dt)
    limit = _stance_limit(fine, spec)
    half = int(np.ceil(reach / dt))
    padded = np.pad(limit, half, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)
    eroded = windows.min(axis=1)
    kernel = np.exp(-0.5 * ((np.arange(-half, half + 1) * dt) / HEIGHT_SMOOTHING_S) ** 2)
    smooth = np.convolve(np.pad(eroded, half, mode="edge"), kernel / kernel.sum(), mode="valid")
    return np.interp(t, fine, smooth)


def walk_motion(t: np.ndarray, spec, euler: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(root_pos, root_rot, local_rot) of a walk; ``euler`` (T, 24, 3) holds the upper-body angles to use."""
    pelvis_xy, _ = _path(t, spec.speed, spec.heading, spec.turn_rate)
    root_rot, pelvis_yaw, left_forward = _root_rotation(t, spec)
    for side, sign in (("L", 1.0), ("R", -1.0)):
        # In the T-pose frame a horizontal swing is about z (applied before the arm is lowered about x); a
        # positive angle moves the left arm back and the right arm forward, i.e. against the left leg.
        euler[:, _idx(f"{side}_Shoulder"), 2] += 0.35 * spec.speed * left_forward
        euler[:, _idx(f"{side}_Elbow"), 2] += -sign * 0.1 * spec.speed * (1.0 - sign * left_forward)
    euler[:, _idx("Spine"), 2] += -0.05 * spec.speed * left_forward  # shoulders counter-rotate the pelvis
    local_rot = rot.quat_from_euler_xyz(euler)
    local_rot[:, 0] = rot.quat_identity()
    root_pos = np.concatenate([pelvis_xy, _pelvis_height(t, spec)[:, None]], axis=1)

    for side, offset in _LEGS:
        ankle, foot_yaw, foot_pitch, toe_flex = _feet(t, spec, side, offset)
        hip_pos = root_pos + rot.quat_rotate(root_rot, REST_OFFSETS[_idx(f"{side}_Hip")])
        # A swinging foot rises where the pelvis would otherwise pull its leg straight (a smooth maximum).
        u = np.mod(spec.gait_freq * t + spec.phase / (2.0 * np.pi) + offset, 1.0)
        swinging = np.minimum(_smooth(u / 0.05), _smooth((SWING_FRACTION - u) / 0.05)) * (u < SWING_FRACTION)
        horizontal = np.linalg.norm(ankle[:, :2] - hip_pos[:, :2], axis=1)
        reach = REACH_MARGIN * _leg_reach(side) - 0.01
        lowest = hip_pos[:, 2] - np.sqrt(np.maximum(reach**2 - horizontal**2, 0.0))
        raised = 0.005 * np.logaddexp(ankle[:, 2] / 0.005, lowest / 0.005)
        ankle[:, 2] += swinging * (raised - ankle[:, 2])

        to_ankle = rot.quat_rotate(rot.quat_conjugate(root_rot), ankle - hip_pos)  # pelvis frame
        knee = _knee_angle(side, np.linalg.norm(to_ankle, axis=1))
        knee_rot = rot.quat_from_axis_angle(knee[:, None] * np.array([0.0, 1.0, 0.0]))
        leg = REST_OFFSETS[_idx(f"{side}_Knee")] + rot.quat_rotate(knee_rot, REST_OFFSETS[_idx(f"{side}_Ankle")])
        hip_rot = _rotation_between(leg, to_ankle)
        # Twist the leg about its (upward) axis so the knee points where the foot does.
        axis = -to_ankle / np.linalg.norm(to_ankle, axis=1, keepdims=True)
        hip_rot = rot.quat_mul(rot.quat_from_axis_angle(axis * rot.wrap_angle(foot_yaw - pelvis_yaw)[:, None]), hip_rot)
        shin_world = rot.quat_mul(rot.quat_mul(root_rot, hip_rot), knee_rot)
        foot_world = rot.quat_mul(_yaw_quat(foot_yaw), _pitch_quat(foot_pitch))
        local_rot[:, _idx(f"{side}_Hip")] = hip_rot
        local_rot[:, _idx(f"{side}_Knee")] = knee_rot
        local_rot[:, _idx(f"{side}_Ankle")] = rot.quat_mul(rot.quat_conjugate(shin_world), foot_world)
        local_rot[:, _idx(f"{side}_Toe")] = _pitch_quat(toe_flex)
    return root_pos, root_rot, local_rot


def _rotation_between(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Shortest rotation taking the directions of u to those of w (not antiparallel here: legs stay below hips)."""
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    w = w / np.linalg.norm(w, axis=-1, keepdims=True)
    q = np.concatenate([np.cross(u, w), 1.0 + np.sum(u * w, axis=-1, keepdims=True)], axis=-1)
    return rot.quat_normalize(q)
