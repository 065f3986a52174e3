"""The SMPL-topology skeleton shared by the motion library and the simulated humanoid.

Bodies are listed in MuJoCo depth-first order (the order of the humanoid MJCF and of every per-body array in the
project). Rest offsets are the neutral mean shape's joint offsets in the z-up model frame (x forward, y left, z up),
in metres, relative to the parent joint. AMASS stores rotations in SMPL's y-up template frame and in SMPL joint
order; ``SMPL_TO_BODY`` maps between the two orders.
"""

from __future__ import annotations

import numpy as np

BODY_NAMES: tuple[str, ...] = (
    "Pelvis",
    "L_Hip", "L_Knee", "L_Ankle", "L_Toe",
    "R_Hip", "R_Knee", "R_Ankle", "R_Toe",
    "Torso", "Spine", "Chest", "Neck", "Head",
    "L_Thorax", "L_Shoulder", "L_Elbow", "L_Wrist", "L_Hand",
    "R_Thorax", "R_Shoulder", "R_Elbow", "R_Wrist", "R_Hand",
)  # fmt: skip  # one row per limb
NUM_BODIES = len(BODY_NAMES)  # 24
NUM_JOINTS = NUM_BODIES - 1  # 23 ball joints (three hinges each) below the free root
NUM_DOFS = 3 * NUM_JOINTS  # 69 actuated DoF

# SMPL / AMASS joint order (the order of the axis-angle triplets in ``poses``).
SMPL_NAMES: tuple[str, ...] = (
    "Pelvis", "L_Hip", "R_Hip", "Torso", "L_Knee", "R_Knee", "Spine", "L_Ankle", "R_Ankle", "Chest",
    "L_Toe", "R_Toe", "Neck", "L_Thorax", "R_Thorax", "Head", "L_Shoulder", "R_Shoulder", "L_Elbow",
    "R_Elbow", "L_Wrist", "R_Wrist", "L_Hand", "R_Hand",
)  # fmt: skip  # rows of ten, in SMPL order
SMPL_PARENTS = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21)

# SMPL_TO_BODY[i] is the index in BODY_NAMES of SMPL joint i; BODY_TO_SMPL is its inverse.
SMPL_TO_BODY = np.array([BODY_NAMES.index(n) for n in SMPL_NAMES], dtype=np.int64)
BODY_TO_SMPL = np.array([SMPL_NAMES.index(n) for n in BODY_NAMES], dtype=np.int64)

# Parent of each body in BODY_NAMES order (-1 for the root).
PARENTS = np.array(
    [-1 if SMPL_PARENTS[s] < 0 else int(SMPL_TO_BODY[SMPL_PARENTS[s]]) for s in BODY_TO_SMPL], dtype=np.int64
)

# Rest offset of each joint from its parent joint, model frame (x forward, y left, z up), metres.
_OFFSETS = {
    "Pelvis": (0.0, 0.0, 0.0),
    "L_Hip": (-0.0068, 0.0695, -0.0914), "R_Hip": (-0.0043, -0.0677, -0.0905),
    "Torso": (-0.0267, -0.0025, 0.1090),
    "L_Knee": (-0.0045, 0.0343, -0.3752), "R_Knee": (-0.0089, -0.0383, -0.3826),
    "Spine": (0.0011, 0.0055, 0.1352),
    "L_Ankle": (-0.0437, -0.0136, -0.3980), "R_Ankle": (-0.0423, 0.0158, -0.3984),
    "Chest": (0.0254, 0.0015, 0.0529),
    "L_Toe": (0.1193, 0.0264, -0.0558), "R_Toe": (0.1233, -0.0254, -0.0481),
    "Neck": (-0.0429, -0.0028, 0.2139),
    "L_Thorax": (-0.0341, 0.0788, 0.1217), "R_Thorax": (-0.0386, -0.0818, 0.1188),
    "Head": (0.0513, 0.0052, 0.0650),
    "L_Shoulder": (-0.0089, 0.0910, 0.0305), "R_Shoulder": (-0.0091, -0.0960, 0.0326),
    "L_Elbow": (-0.0275, 0.2596, -0.0128), "R_Elbow": (-0.0214, -0.2537, -0.0133),
    "L_Wrist": (-0.0012, 0.2492, 0.0090), "R_Wrist": (-0.0056, -0.2553, 0.0078),
    "L_Hand": (-0.0149, 0.0840, -0.0082), "R_Hand": (-0.0103, -0.0846, -0.0061),
}  # fmt: skip  # left and right of a joint on one row
REST_OFFSETS = np.array([_OFFSETS[n] for n in BODY_NAMES], dtype=np.float64)  # (24, 3)

# Pelvis joint position J0 in SMPL's y-up template frame (x left, y up, z forward). AMASS ``trans`` + J0 is
# the pelvis position, because SMPL rotates the body about J0.
PELVIS_J0_TEMPLATE = np.array([-0.0018, -0.2233, 0.0282], dtype=np.float64)

# Axis permutation from the model frame (x fwd, y left, z up) to the template frame (x left, y up, z fwd):
# template = MODEL_TO_TEMPLATE @ model.
MODEL_TO_TEMPLATE = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])

# Body masses of the neutral mean shape, kg (total about 74 kg).
_MASSES = {
    "Pelvis": 16.2, "L_Hip": 7.4, "R_Hip": 7.4, "L_Knee": 3.5, "R_Knee": 3.5, "L_Ankle": 1.55, "R_Ankle": 1.58,
    "L_Toe": 0.4, "R_Toe": 0.4, "Torso": 4.4, "Spine": 3.9, "Chest": 9.6, "Neck": 0.65, "Head": 4.3,
    "L_Thorax": 1.1, "R_Thorax": 1.1, "L_Shoulder": 1.95, "R_Shoulder": 1.98, "L_Elbow": 1.05, "R_Elbow": 1.09,
    "L_Wrist": 0.3, "R_Wrist": 0.3, "L_Hand": 0.16, "R_Hand": 0.16,
}  # fmt: skip  # rows of seven, in SMPL order
BODY_MASSES = np.array([_MASSES[n] for n in BODY_NAMES], dtype=np.float64)

# Joint PD gains (stiffness N·m/rad, damping N·m·s/rad) per body's joint, from the reference tracking setup.
_GAINS = {
    "Hip": (800.0, 80.0), "Knee": (800.0, 80.0), "Ankle": (800.0, 80.0), "Toe": (500.0, 50.0),
    "Torso": (1000.0, 100.0), "Spine": (1000.0, 100.0), "Chest": (1000.0, 100.0),
    "Neck": (500.0, 50.0), "Head": (500.0, 50.0), "Thorax": (500.0, 50.0), "Shoulder": (500.0, 50.0),
    "Elbow": (500.0, 50.0), "Wrist": (300.0, 30.0), "Hand": (300.0, 30.0),
}  # fmt: skip  # one row per gain group
PD_GAINS = np.array([(0.0, 0.0)] + [_GAINS[n.split("_")[-1]] for n in BODY_NAMES[1:]], dtype=np.float64)  # (24, 2)

# Policy action a in [-1, 1] maps to a PD target offset + scale * a per DoF (x, y, z hinge of each joint).
ACTION_SCALE: np.ndarray = np.full((NUM_JOINTS, 3), np.pi)
for _knee in ("L_Knee", "R_Knee"):
    ACTION_SCALE[BODY_NAMES.index(_knee) - 1, 1] = 5.0  # knee flexion (y hinge) uses the reference's wider scale
ACTION_SCALE = ACTION_SCALE.reshape(-1)

# Bodies whose PD targets are held at zero when hands/toes are frozen.
FROZEN_HAND_TOE = ("L_Toe", "R_Toe", "L_Hand", "R_Hand")
# Bodies used by the evaluation termination (mean distance over non-hand/toe bodies).
EVAL_TERMINATION_BODIES = tuple(n for n in BODY_NAMES if n not in FROZEN_HAND_TOE)
# Goal-conditioned bodies per regime (the task observation keeps only these bodies' position targets).
CONDITIONED_BODIES = {
    "all": BODY_NAMES,
    "root_hands": ("Pelvis", "L_Wrist", "R_Wrist"),
    "root": ("Pelvis",),
}


def body_index(name: str) -> int:
    """Index of a body in BODY_NAMES order."""
    return BODY_NAMES.index(name)


# Foot joints and the height of each joint centre above a flat sole in the rest pose. The sole is TOE_SOLE_DEPTH
# below the toe joint (the reference model's foot boxes; ProtoMotions' 0.015 m toe offset); the ankle is higher by
# its rest offset to the toe. Motion clips are grounded so the lowest sole point at the clip start is at z = 0.
TOE_SOLE_DEPTH = 0.015
HEEL_BEHIND_ANKLE = -0.05  # m along the foot: the heel (back of the sole) relative to the ankle joint
FOOT_BODIES: tuple[str, ...] = ("L_Ankle", "L_Toe", "R_Ankle", "R_Toe")
FOOT_SOLE_DEPTH = np.array(
    [TOE_SOLE_DEPTH + (0.0 if name.endswith("Toe") else -REST_OFFSETS[BODY_NAMES.index(name[0] + "_Toe"), 2])
     for name in FOOT_BODIES]
)  # fmt: skip  # the sole depth of each foot joint in one expression
