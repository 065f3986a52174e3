"""Generator of the project's SMPL-topology humanoid MJCF (``smpl_humanoid.xml``) from ``refpo_warp.motion.skeleton``.

The model is the project's own: the SMPL kinematic tree (24 bodies, a free root and 23 joints of three hinges each,
x then y then z, so that the joint coordinates are the intrinsic x-y-z Euler angles of the motion library's
``dof_pos``), the neutral mean shape's rest offsets and body masses, and simple capsule/sphere/box collision
geometry sized here. Every body frame is aligned with the world frame in the rest (T-)pose. The MJCF holds no
actuators and no joint stiffness: the PD gains are set as Newton joint target gains when the model is built
(``tasks/humanoid/model.py``), because Newton would read MJCF joint stiffness as a passive spring.

Regenerate after changing the skeleton or the geometry table: ``python -m refpo_warp.tasks.humanoid.mjcf_builder``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from refpo_warp.motion import skeleton as sk

MJCF_PATH = Path(__file__).resolve().parent / "smpl_humanoid.xml"

ARMATURE = 0.02
HINGE_RANGE_DEG = 180.0
WIDE_RANGE_DEG = 720.0  # shoulders and elbows (as in the reference model)
WIDE_RANGE_BODIES = ("L_Shoulder", "R_Shoulder", "L_Elbow", "R_Elbow")
FRICTION = "1 0.005 0.0001"

# Foot geometry (metres, model frame): the sole lies SOLE_BELOW_TOE below the toe joint, the heel HEEL_BEHIND
# behind the ankle joint; the toe box reaches TOE_LENGTH in front of the toe joint.
SOLE_BELOW_TOE = sk.TOE_SOLE_DEPTH
HEEL_BEHIND = -sk.HEEL_BEHIND_ANKLE
FOOT_HALF_WIDTH = 0.045
FOOT_HALF_HEIGHT = 0.04
TOE_LENGTH = 0.05
TOE_HALF_HEIGHT = 0.02

# Limb capsules run from the joint towards the child joint over the fraction [start, end] of the bone, with a radius.
_CAPSULES = {
    "Hip": (0.05, 0.9, 0.06), "Knee": (0.05, 0.9, 0.05),
    "Torso": (0.0, 1.0, 0.09), "Spine": (0.0, 1.0, 0.09), "Chest": (0.0, 0.55, 0.1), "Neck": (0.0, 0.8, 0.045),
    "Thorax": (0.35, 0.8, 0.045), "Shoulder": (0.1, 0.9, 0.045), "Elbow": (0.1, 0.9, 0.04),
    "Wrist": (0.2, 0.9, 0.035),
}  # fmt: skip  # one row per body region
PELVIS_RADIUS = 0.09
HEAD_RADIUS = 0.1
HEAD_CENTER = (0.02, 0.0, 0.09)
HAND_LENGTH = 0.08  # fingers continue along the wrist->hand bone
HAND_RADIUS = 0.025
# Non-adjacent body pairs kept out of self-collision (MuJoCo already skips parent-child pairs): the trunk's three
# short segments overlap in every pose, so Torso and Chest would push each other apart all the time.
EXCLUDED_PAIRS = (("Torso", "Chest"),)


def _children(body: int) -> list[int]:
    return [c for c in range(sk.NUM_BODIES) if sk.PARENTS[c] == body]


def _fmt(values) -> str:
    return " ".join(f"{float(v):.5g}" for v in values)


def _bone(body: int) -> np.ndarray:
    """Offset of the body's (first) child joint: the bone the body's geometry covers."""
    return sk.REST_OFFSETS[_children(body)[0]]


def _geom(body: int) -> str:
    """One collision geom per body, carrying the body's mass (MuJoCo derives the inertia from the shape)."""
    name = sk.BODY_NAMES[body]
    kind = name.split("_")[-1]
    mass = f'mass="{sk.BODY_MASSES[body]:.5g}"'
    if name == "Pelvis":
        return f'<geom name="{name}" type="sphere" size="{PELVIS_RADIUS}" {mass}/>'
    if name == "Head":
        return f'<geom name="{name}" type="sphere" size="{HEAD_RADIUS}" pos="{_fmt(HEAD_CENTER)}" {mass}/>'
    if kind == "Ankle":
        toe = _bone(body)
        x0, x1 = -HEEL_BEHIND, toe[0]
        z0 = toe[2] - SOLE_BELOW_TOE
        center = ((x0 + x1) / 2, toe[1] / 2, z0 + FOOT_HALF_HEIGHT)
        size = ((x1 - x0) / 2, FOOT_HALF_WIDTH, FOOT_HALF_HEIGHT)
        return f'<geom name="{name}" type="box" pos="{_fmt(center)}" size="{_fmt(size)}" {mass}/>'
    if kind == "Toe":
        center = (TOE_LENGTH / 2, 0.0, -SOLE_BELOW_TOE + TOE_HALF_HEIGHT)
        size = (TOE_LENGTH / 2, FOOT_HALF_WIDTH, TOE_HALF_HEIGHT)
        return f'<geom name="{name}" type="box" pos="{_fmt(center)}" size="{_fmt(size)}" {mass}/>'
    if kind == "Hand":
        bone = sk.REST_OFFSETS[body]
        direction = bone / np.linalg.norm(bone)
        ends = np.concatenate([0.2 * HAND_LENGTH * direction, HAND_LENGTH * direction])
        return f'<geom name="{name}" type="capsule" fromto="{_fmt(ends)}" size="{HAND_RADIUS}" {mass}/>'
    start, end, radius = _CAPSULES[kind]
    bone = _bone(body)
    ends = np.concatenate([start * bone, end * bone])
    return f'<geom name="{name}" type="capsule" fromto="{_fmt(ends)}" size="{radius}" {mass}/>'


def standing_height() -> float:
    """Pelvis height at which the rest pose's soles touch the ground (plus 2 mm)."""
    lowest = 0.0
    for body in range(sk.NUM_BODIES):
        if sk.BODY_NAMES[body].endswith("Toe"):
            z, b = -SOLE_BELOW_TOE, body
            while b > 0:
                z += sk.REST_OFFSETS[b][2]
                b = int(sk.PARENTS[b])
            lowest = min(lowest, z)
    return round(-lowest + 0.002, 4)


def _body_xml(body: int, depth: int) -> list[str]:
    name = sk.BODY_NAMES[body]
    pad = "  " * depth
    pos = (0.0, 0.0, standing_height()) if body == 0 else sk.REST_OFFSETS[body]
    lines = [f'{pad}<body name="{name}" pos="{_fmt(pos)}">']
    if body == 0:
        lines.append(f'{pad}  <freejoint name="{name}"/>')
    else:
        limit = WIDE_RANGE_DEG if name in WIDE_RANGE_BODIES else HINGE_RANGE_DEG
        for axis, vec in (("x", "1 0 0"), ("y", "0 1 0"), ("z", "0 0 1")):
            lines.append(f'{pad}  <joint name="{name}_{axis}" type="hinge" axis="{vec}" range="{-limit:g} {limit:g}"/>')
    lines.append(f"{pad}  {_geom(body)}")
    for child in _children(body):
        lines += _body_xml(child, depth + 1)
    lines.append(f"{pad}</body>")
    return lines


def build_mjcf() -> str:
    """The MJCF text of the humanoid (deterministic; the shipped file must equal it)."""
    header = [
        "<!-- Generated by tasks/humanoid/mjcf_builder.py from refpo_warp/motion/skeleton.py; do not edit. -->",
        '<mujoco model="smpl_humanoid">',
        '  <compiler angle="degree" inertiafromgeom="true"/>',
        "  <default>",
        f'    <joint armature="{ARMATURE}" limited="true"/>',
        f'    <geom condim="3" friction="{FRICTION}" contype="1" conaffinity="1"/>',
        "  </default>",
        "  <worldbody>",
    ]
    excludes = [f'    <exclude body1="{a}" body2="{b}"/>' for a, b in EXCLUDED_PAIRS]
    contact = ["  <contact>", *excludes, "  </contact>"]
    return "\n".join(header + _body_xml(0, 2) + ["  </worldbody>"] + contact + ["</mujoco>", ""])


def main() -> None:
    MJCF_PATH.write_text(build_mjcf())
    print(f"wrote {MJCF_PATH}")


if __name__ == "__main__":
    main()
