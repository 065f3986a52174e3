"""Forward kinematics, AMASS pose conversion and hinge angles against independent references: hand-worked
numbers, MuJoCo's own kinematics of an MJCF built from the skeleton, and the SMPL template-frame chain computed
with 3x3 matrices."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from refpo_warp.motion import kinematics as kin
from refpo_warp.motion import rotations as rot
from refpo_warp.motion.skeleton import (
    BODY_NAMES,
    MODEL_TO_TEMPLATE,
    NUM_BODIES,
    PARENTS,
    PELVIS_J0_TEMPLATE,
    REST_OFFSETS,
    SMPL_NAMES,
    SMPL_PARENTS,
)


def local_from_world(body_rot: np.ndarray) -> np.ndarray:
    """Per-body local rotations (T, 24, 4) from world rotations; entry 0 is the identity (the inverse of the
    forward kinematics the library runs)."""
    local = rot.quat_mul(rot.quat_conjugate(body_rot[:, PARENTS[1:]]), body_rot[:, 1:])
    return np.concatenate([rot.quat_identity((body_rot.shape[0], 1)), local], axis=1)


def skeleton_mjcf() -> str:
    """A bare MJCF of the skeleton: free root, three hinges (x, y, z in that order) per joint, rest offsets."""

    def body(b: int, depth: int) -> str:
        pad = "  " * depth
        name = BODY_NAMES[b]
        hinges = zip("xyz", ("1 0 0", "0 1 0", "0 0 1"))
        joints = (
            '<freejoint name="root"/>'
            if b == 0
            else "".join(f'<joint name="{name}_{a}" type="hinge" axis="{v}"/>' for a, v in hinges)
        )
        kids = "".join(body(c, depth + 1) for c in range(NUM_BODIES) if PARENTS[c] == b)
        pos = " ".join(f"{x:.6f}" for x in REST_OFFSETS[b])
        return f'{pad}<body name="{name}" pos="{pos}">{joints}<geom type="sphere" size="0.01"/>\n{kids}{pad}</body>\n'

    return f"<mujoco><worldbody>\n{body(0, 1)}</worldbody></mujoco>"


@pytest.fixture(scope="module")
def mj():
    model = mujoco.MjModel.from_xml_string(skeleton_mjcf())
    assert model.nq == 7 + 69 and model.nv == 6 + 69
    return model, mujoco.MjData(model)


def mujoco_fk(mj, root_pos, root_rot_xyzw, dof_pos):
    model, data = mj
    data.qpos[:3] = root_pos
    data.qpos[3:7] = np.roll(root_rot_xyzw, 1)  # MuJoCo stores wxyz
    data.qpos[7:] = dof_pos
    mujoco.mj_kinematics(model, data)
    body_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in BODY_NAMES]
    return data.xpos[body_ids].copy(), np.roll(data.xquat[body_ids], -1, axis=1)


def same_rotation(q0, q1, atol):
    return np.all(np.abs(np.abs(np.sum(q0 * q1, axis=-1)) - 1.0) < atol)


def test_fk_hand_worked_left_knee_bent_root_turned():
    # Root at (1, 2, 0.9) turned 90 deg about z; left knee bent 90 deg about its y axis; everything else at rest.
    root_rot = rot.quat_from_axis_angle(np.array([0.0, 0.0, np.pi / 2]))
    local = rot.quat_identity((1, NUM_BODIES))
    local[0, BODY_NAMES.index("L_Knee")] = rot.quat_from_axis_angle(np.array([0.0, np.pi / 2, 0.0]))
    pos, _ = kin.forward_kinematics(np.array([[1.0, 2.0, 0.9]]), root_rot[None], local)
    # Rz(90): (x, y, z) -> (-y, x, z). Ry(90): (x, y, z) -> (z, y, -x).
    # hip (-.0068, .0695, -.0914) -> (-.0695, -.0068, -.0914); knee (-.0045, .0343, -.3752) -> (-.0343, -.0045, -.3752)
    # ankle (-.0437, -.0136, -.3980) -Ry-> (-.3980, -.0136, .0437) -Rz-> (.0136, -.3980, .0437)
    expected_knee = np.array([1 - 0.0695 - 0.0343, 2 - 0.0068 - 0.0045, 0.9 - 0.0914 - 0.3752])
    expected_ankle = expected_knee + np.array([0.0136, -0.3980, 0.0437])
    np.testing.assert_allclose(pos[0, BODY_NAMES.index("L_Knee")], expected_knee, atol=1e-12)
    np.testing.assert_allclose(pos[0, BODY_NAMES.index("L_Ankle")], expected_ankle, atol=1e-12)
    # The right leg is untouched: its ankle hangs straight below its hip offsets, turned by the root.
    r_sum = REST_OFFSETS[[5, 6, 7]].sum(axis=0)
    np.testing.assert_allclose(pos[0, 7], [1 - r_sum[1], 2 + r_sum[0], 0.9 + r_sum[2]], atol=1e-12)


def test_fk_and_euler_dofs_match_mujoco_hinges(mj):
    rng = np.random.default_rng(0)
    for _ in range(5):
        dof = rng.uniform(-1.2, 1.2, size=69)
        root_pos = rng.normal(size=3)
        root_rot = rot.quat_normalize(rng.normal(size=4))
        local = np.concatenate([rot.quat_identity((1,)), rot.quat_from_euler_xyz(dof.reshape(23, 3))])[None]
        pos, quat = kin.forward_kinematics(root_pos[None], root_rot[None], local)
        mj_pos, mj_quat = mujoco_fk(mj, root_pos, root_rot, dof)
        np.testing.assert_allclose(pos[0], mj_pos, atol=1e-12)
        assert same_rotation(quat[0], mj_quat, 1e-12)
        # Hinge angles recovered from the local rotations reproduce the same pose in MuJoCo.
        back = kin.dof_positions(local_from_world(quat))[0]
        mj_pos2, mj_quat2 = mujoco_fk(mj, root_pos, root_rot, back)
        np.testing.assert_allclose(mj_pos2, pos[0], atol=1e-10)
        assert same_rotation(mj_quat2, quat[0], 1e-10)


def test_dof_positions_pick_the_solution_nearest_rest():
    angles = np.array([[0.3, -0.4, 0.5], [0.0, 2.0, 0.0], [0.1, -1.9, -0.2], [-2.5, 0.2, 0.1]])
    q = rot.quat_from_euler_xyz(angles)
    local = np.concatenate([rot.quat_identity((4, 1)), np.repeat(q[:, None], 23, axis=1)], axis=1)
    dof = kin.dof_positions(local).reshape(4, 23, 3)[:, 0]
    # Each input is already the smaller-norm solution (a knee bent 2 rad stays (0, 2, 0), not (pi, pi-2, pi)).
    np.testing.assert_allclose(dof, angles, atol=1e-9)


def rodrigues(aa: np.ndarray) -> np.ndarray:
    """Axis-angle (3,) to a rotation matrix, written out independently of the quaternion helpers."""
    theta = np.linalg.norm(aa)
    if theta < 1e-12:
        return np.eye(3)
    k = aa / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx


def test_amass_conversion_matches_template_frame_chain():
    """SMPL's own recipe in the y-up template frame: joint = parent + R_parent_global @ template offset, with world
    position trans + J0 at the pelvis; compare with conversion to the model frame followed by FK."""
    rng = np.random.default_rng(1)
    num_frames = 3
    root_orient = rng.normal(scale=0.8, size=(num_frames, 3))
    body_pose = rng.normal(scale=0.4, size=(num_frames, 63))
    trans = rng.normal(size=(num_frames, 3))
    root_pos, root_rot, local = kin.amass_to_model(root_orient, body_pose, trans)
    pos, quat = kin.forward_kinematics(root_pos, root_rot, local)

    template_offsets = {n: MODEL_TO_TEMPLATE @ REST_OFFSETS[BODY_NAMES.index(n)] for n in SMPL_NAMES}
    for t in range(num_frames):
        aa = np.concatenate([root_orient[t], body_pose[t], np.zeros(6)]).reshape(24, 3)
        glob, jpos = [None] * 24, [None] * 24
        for j, name in enumerate(SMPL_NAMES):
            p = SMPL_PARENTS[j]
            if p < 0:
                glob[j], jpos[j] = rodrigues(aa[0]), trans[t] + PELVIS_J0_TEMPLATE
            else:
                glob[j] = glob[p] @ rodrigues(aa[j])
                jpos[j] = jpos[p] + glob[p] @ template_offsets[name]
            b = BODY_NAMES.index(name)
            np.testing.assert_allclose(pos[t, b], jpos[j], atol=1e-12)
            # Model-frame body rotation = template global rotation followed by the template->model axis change.
            expected = rot.quat_from_matrix(glob[j] @ MODEL_TO_TEMPLATE)
            assert same_rotation(quat[t, b], expected, 1e-10)


def test_upright_root_orient_stands_the_rest_pose_up_facing_x():
    # root_orient = 120 deg about (1,1,1)/sqrt(3): the T-pose stands on z, faces +x, left arm along +y.
    root_orient = np.full((1, 3), 2 * np.pi / 3 / np.sqrt(3))
    root_pos, root_rot, local = kin.amass_to_model(root_orient, np.zeros((1, 63)), np.zeros((1, 3)))
    np.testing.assert_allclose(rot.quat_to_matrix(root_rot[0]), np.eye(3), atol=1e-12)
    np.testing.assert_allclose(root_pos[0], PELVIS_J0_TEMPLATE)
    pos, _ = kin.forward_kinematics(root_pos, root_rot, local)
    assert pos[0, BODY_NAMES.index("Head"), 2] > pos[0, 0, 2] + 0.4
    assert pos[0, BODY_NAMES.index("L_Hand"), 1] > pos[0, 0, 1] + 0.6
    assert pos[0, BODY_NAMES.index("L_Toe"), 0] > pos[0, BODY_NAMES.index("L_Ankle"), 0] + 0.1


def test_model_to_amass_inverts_amass_to_model():
    rng = np.random.default_rng(2)
    # Axis-angle vectors are unique for angles below pi: draw random axes with angles up to 3 rad.
    axes = rng.normal(size=(4, 22, 3))
    aa = axes / np.linalg.norm(axes, axis=-1, keepdims=True) * rng.uniform(0.0, 3.0, size=(4, 22, 1))
    root_orient, body_pose, trans = aa[:, 0], aa[:, 1:].reshape(4, 63), rng.normal(size=(4, 3))
    back = kin.model_to_amass(*kin.amass_to_model(root_orient, body_pose, trans))
    for got, want in zip(back, (root_orient, body_pose, trans)):
        np.testing.assert_allclose(got, want, atol=1e-10)


def test_velocities_of_a_rigid_spin_and_drift():
    """The rest pose spinning at w about z while drifting at v: body velocity = v + w x (p - root),
    angular velocity = (0, 0, w) for every body; hinge rates of a linear angle ramp are the slope."""
    fps, w, v = 30.0, 1.3, np.array([0.4, -0.2, 0.05])
    t = np.arange(40) / fps
    root_pos = np.array([0.0, 0.0, 1.0]) + t[:, None] * v
    root_rot = rot.quat_from_axis_angle(np.outer(w * t, [0.0, 0.0, 1.0]))
    local = rot.quat_identity((t.size, NUM_BODIES))
    pos, quat = kin.forward_kinematics(root_pos, root_rot, local)
    lin = kin.linear_velocities(pos, fps)
    ang = kin.angular_velocities(quat, fps)
    # Central differences over +-h of a circular motion shrink its speed by exactly sin(wh)/(wh).
    h = 1.0 / fps
    expected = v + np.sin(w * h) / (w * h) * np.cross(np.array([0.0, 0.0, w]), pos - root_pos[:, None])
    np.testing.assert_allclose(lin[1:-1], expected[1:-1], atol=1e-12)
    np.testing.assert_allclose(ang, np.broadcast_to([0.0, 0.0, w], ang.shape), atol=1e-9)
    ramp = np.outer(t, np.linspace(-2.0, 2.0, 69)) + 3.0  # crosses +-pi: rates must ignore the wrap
    rates = kin.dof_velocities(rot.wrap_angle(ramp), fps)
    np.testing.assert_allclose(rates, np.broadcast_to(np.linspace(-2.0, 2.0, 69), ramp.shape), atol=1e-9)
