"""Procedural AMASS-format clips (walk, turn, stand with sway, arm waves), so the project needs no mocap data.

Everything is written in the model frame (x forward, y left, z up) and converted to AMASS's template-frame
axis-angle at the end. Walks and turns place footprints along a straight or circular path and solve the legs by
inverse kinematics (``synthetic_gait``). Standing clips are smooth periodic joint angles (sway through hips,
ankles and spine; a raised arm whose elbow waves); their root translation is not scripted: each frame the lowest
foot sole point stays fixed horizontally and sits on the ground, so the feet do not slide.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TypedDict

import numpy as np

from refpo_warp.motion import kinematics as kin
from refpo_warp.motion import rotations as rot
from refpo_warp.motion.clip import FOOT_INDICES
from refpo_warp.motion.skeleton import BODY_NAMES, FOOT_SOLE_DEPTH, NUM_BODIES
from refpo_warp.motion.synthetic_gait import walk_motion

KINDS = ("walk", "turn", "stand", "wave")
ARM_DOWN = 1.25  # rad below the T-pose (about the forward axis)


@dataclass(frozen=True)
class ClipSpec:
    """Parameters of one synthetic clip; unused fields are ignored by a kind (e.g. gait fields by ``wave``)."""

    name: str
    kind: str  # one of KINDS
    duration: float = 4.0  # seconds
    fps: float = 30.0
    heading: float = 0.0  # initial facing direction, rad about z (0 faces +x)
    speed: float = 1.0  # m/s along the path (walk, turn)
    gait_freq: float = 0.9  # strides (two steps) per second (walk, turn)
    turn_rate: float = 0.0  # rad/s (turn)
    sway_freq: float = 0.3  # Hz (stand, wave)
    sway_amp: float = 0.06  # rad (stand, wave)
    wave_arm: str = "right"  # "left", "right" or "both" (wave)
    wave_freq: float = 1.5  # Hz (wave)
    phase: float = 0.0  # rad, shifts every oscillation


# The shipped default set: 12 clips, 2.5-5 s, four frame rates, several speeds and headings.
DEFAULT_CLIP_SPECS: tuple[ClipSpec, ...] = (
    ClipSpec("walk_slow", "walk", 4.0, 30, heading=0.0, speed=0.6, gait_freq=0.7),
    ClipSpec("walk_normal", "walk", 4.0, 60, heading=1.0, speed=1.1, gait_freq=0.9, phase=0.5),
    ClipSpec("walk_fast", "walk", 3.0, 120, heading=-2.0, speed=1.4, gait_freq=1.1, phase=1.0),
    ClipSpec("walk_back_heading", "walk", 5.0, 100, heading=np.pi, speed=1.0, gait_freq=0.85, phase=2.0),
    ClipSpec("turn_left", "turn", 4.0, 60, heading=0.3, speed=0.9, gait_freq=0.85, turn_rate=0.6),
    ClipSpec("turn_right", "turn", 4.0, 100, heading=2.5, speed=1.1, gait_freq=0.9, turn_rate=-0.6, phase=1.5),
    ClipSpec("turn_sharp_left", "turn", 3.0, 30, heading=-1.2, speed=0.7, gait_freq=0.8, turn_rate=1.0),
    ClipSpec("stand_sway", "stand", 5.0, 30, heading=0.8, sway_freq=0.3, sway_amp=0.06),
    ClipSpec("stand_sway_quick", "stand", 3.0, 120, heading=-0.5, sway_freq=0.5, sway_amp=0.05, phase=1.0),
    ClipSpec("wave_right", "wave", 3.0, 60, heading=0.0, wave_arm="right", wave_freq=1.5),
    ClipSpec("wave_left", "wave", 3.0, 100, heading=1.7, wave_arm="left", wave_freq=1.2, phase=0.7),
    ClipSpec("wave_both", "wave", 2.5, 120, heading=-2.6, wave_arm="both", wave_freq=1.8, phase=2.1),
)


def random_clip_specs(count: int, seed: int = 0) -> list[ClipSpec]:
    """``count`` clips of random kinds, speeds, headings, turn rates and frame rates (reproducible by seed)."""
    rng = np.random.default_rng(seed)
    specs = []
    for i in range(count):
        kind = KINDS[int(rng.integers(len(KINDS)))]
        specs.append(
            ClipSpec(
                name=f"{kind}_{i:03d}",
                kind=kind,
                duration=float(rng.uniform(2.0, 5.0)),
                fps=float(rng.choice([30, 60, 100, 120])),
                heading=float(rng.uniform(-np.pi, np.pi)),
                speed=float(rng.uniform(0.5, 1.5)),
                gait_freq=float(rng.uniform(0.7, 1.05)),
                turn_rate=float(rng.uniform(0.3, 1.0) * rng.choice([-1, 1])),
                sway_freq=float(rng.uniform(0.2, 0.5)),
                sway_amp=float(rng.uniform(0.03, 0.08)),
                wave_arm=str(rng.choice(["left", "right", "both"])),
                wave_freq=float(rng.uniform(1.0, 2.0)),
                phase=float(rng.uniform(0, 2 * np.pi)),
            )
        )
    return specs


def generate_motion(spec: ClipSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Model-frame motion at ``spec.fps``: (root_pos (T, 3), root_rot (T, 4), local_rot (T, 24, 4))."""
    if spec.kind not in KINDS:
        raise ValueError(f"Unknown synthetic clip kind '{spec.kind}' in clip '{spec.name}': expected one of {KINDS}")
    if spec.duration <= 0 or spec.fps <= 0:
        raise ValueError(f"Clip '{spec.name}': duration and fps must be positive, got {spec.duration}, {spec.fps}")
    t = np.arange(int(np.floor(spec.duration * spec.fps + 1e-6)) + 1) / spec.fps
    euler = np.zeros((t.size, NUM_BODIES, 3))  # per-body local (x, y, z) angles, composed as Rx Ry Rz; 0 = root
    if spec.kind in ("walk", "turn"):
        _walk_upper_body(euler)
        return walk_motion(t, replace(spec, turn_rate=spec.turn_rate if spec.kind == "turn" else 0.0), euler)
    _stand_angles(euler, t, spec)
    if spec.kind == "wave":
        _wave_angles(euler, t, spec)
    local_rot = rot.quat_from_euler_xyz(euler)
    local_rot[:, 0] = rot.quat_identity()
    root_rot = np.repeat(rot.quat_from_axis_angle(np.array([0.0, 0.0, spec.heading]))[None], t.size, axis=0)
    return _anchor_root(root_rot, local_rot), root_rot, local_rot


class AmassClip(TypedDict):
    """``generate_amass``'s clip: the arguments ``write_amass`` takes after the path."""

    root_orient: np.ndarray
    body_pose: np.ndarray
    trans: np.ndarray
    fps: float


def generate_amass(spec: ClipSpec) -> AmassClip:
    """The clip as AMASS quantities: root_orient (T, 3), body_pose (T, 63), trans (T, 3), fps."""
    root_pos, root_rot, local_rot = generate_motion(spec)
    root_orient, body_pose, trans = kin.model_to_amass(root_pos, root_rot, local_rot)
    return {"root_orient": root_orient, "body_pose": body_pose, "trans": trans, "fps": float(spec.fps)}


def _set(euler: np.ndarray, body: str, axis: int, value) -> None:
    euler[:, BODY_NAMES.index(body), axis] += value


def _walk_upper_body(euler: np.ndarray) -> None:
    """Resting upper-body pose of a walk (``synthetic_gait`` adds the swing)."""
    for side, sign in (("L", 1.0), ("R", -1.0)):
        _set(euler, f"{side}_Shoulder", 0, -sign * ARM_DOWN)
        _set(euler, f"{side}_Elbow", 2, -sign * 0.3)
    _set(euler, "Head", 1, -0.05)  # look ahead against the forward lean


def _stand_angles(euler: np.ndarray, t: np.ndarray, spec: ClipSpec) -> None:
    phase = 2.0 * np.pi * spec.sway_freq * t + spec.phase
    side_sway = spec.sway_amp * np.sin(phase)
    for side, sign in (("L", 1.0), ("R", -1.0)):
        # Both legs tilt sideways together (a parallelogram), so the pelvis sways while the feet stay flat.
        _set(euler, f"{side}_Hip", 0, side_sway)
        _set(euler, f"{side}_Ankle", 0, -side_sway)
        _set(euler, f"{side}_Knee", 1, 0.05)
        _set(euler, f"{side}_Hip", 1, -0.025)
        _set(euler, f"{side}_Ankle", 1, -0.025)
        _set(euler, f"{side}_Shoulder", 0, -sign * ARM_DOWN)
        _set(euler, f"{side}_Elbow", 2, -sign * 0.2)
    _set(euler, "Spine", 0, -0.6 * side_sway)  # the torso leans back over the feet
    _set(euler, "Chest", 1, 0.5 * spec.sway_amp * np.sin(0.7 * phase + 1.0))
    _set(euler, "Neck", 2, 1.5 * spec.sway_amp * np.sin(0.5 * phase))


def _wave_angles(euler: np.ndarray, t: np.ndarray, spec: ClipSpec) -> None:
    wave = np.sin(2.0 * np.pi * spec.wave_freq * t + spec.phase)
    raise_in = np.clip(t / 0.5, 0.0, 1.0)  # lift the arm during the first half second
    raise_in = raise_in * raise_in * (3.0 - 2.0 * raise_in)
    if spec.wave_arm not in ("left", "right", "both"):
        raise ValueError(f"Clip '{spec.name}': wave_arm must be 'left', 'right' or 'both', got '{spec.wave_arm}'")
    arms = ("L", "R") if spec.wave_arm == "both" else (spec.wave_arm[0].upper(),)
    for side in arms:
        sign = 1.0 if side == "L" else -1.0
        euler[:, BODY_NAMES.index(f"{side}_Shoulder"), 0] = sign * (-ARM_DOWN + raise_in * (ARM_DOWN + 0.3))
        euler[:, BODY_NAMES.index(f"{side}_Elbow"), 2] = 0.0
        euler[:, BODY_NAMES.index(f"{side}_Elbow"), 0] = sign * raise_in * (1.3 + 0.35 * wave)


def _anchor_root(root_rot: np.ndarray, local_rot: np.ndarray) -> np.ndarray:
    """Pelvis positions that keep the lowest sole point of each frame on the ground and fixed horizontally."""
    rel_pos, _ = kin.forward_kinematics(np.zeros((root_rot.shape[0], 3)), root_rot, local_rot)
    soles = rel_pos[:, FOOT_INDICES].copy()
    soles[..., 2] -= FOOT_SOLE_DEPTH
    stance = np.argmin(soles[..., 2], axis=1)
    frames = np.arange(soles.shape[0])
    # Between frames t-1 and t the pelvis moves opposite to frame t's stance point (relative to the pelvis).
    step = soles[frames[:-1], stance[1:], :2] - soles[frames[1:], stance[1:], :2]
    root_pos = np.zeros((soles.shape[0], 3))
    root_pos[1:, :2] = np.cumsum(step, axis=0)
    root_pos[:, 2] = -soles[frames, stance, 2]
    return root_pos


def with_fps(spec: ClipSpec, fps: float) -> ClipSpec:
    """The same motion sampled at another frame rate."""
    return replace(spec, fps=float(fps))
