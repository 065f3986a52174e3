"""The simulated SMPL humanoid: the MJCF against the skeleton, the Newton model's PD set-up, standing under PD hold,
self-collision at rest, and contact/constraint capacity under random actions."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from refpo_warp.motion import skeleton as sk
from refpo_warp.tasks.humanoid.mjcf_builder import MJCF_PATH, build_mjcf


def _mjcf_bodies():
    """(name, parent name, pos, geom attributes, joint elements) for every body of the shipped MJCF, in file order."""
    root = ET.parse(MJCF_PATH).getroot()
    out = []

    def visit(body, parent):
        out.append(
            (
                body.get("name"),
                parent,
                np.array(body.get("pos").split(), float),
                body.find("geom").attrib,
                body.findall("joint"),
            )
        )
        for child in body.findall("body"):
            visit(child, body.get("name"))

    visit(root.find("worldbody/body"), None)
    return out


def test_shipped_mjcf_is_the_generated_one():
    assert MJCF_PATH.read_text() == build_mjcf(), "regenerate with: python -m refpo_warp.tasks.humanoid.mjcf_builder"


def test_mjcf_matches_skeleton():
    bodies = _mjcf_bodies()
    assert [b[0] for b in bodies] == list(sk.BODY_NAMES)
    for i, (name, parent, pos, geom, joints) in enumerate(bodies):
        expected_parent = None if sk.PARENTS[i] < 0 else sk.BODY_NAMES[sk.PARENTS[i]]
        assert parent == expected_parent, name
        assert float(geom["mass"]) == pytest.approx(sk.BODY_MASSES[i], rel=1e-4), name
        if i == 0:
            assert 0.9 < pos[2] < 0.96  # standing height of the rest pose
            continue
        np.testing.assert_allclose(pos, sk.REST_OFFSETS[i], atol=1e-9, err_msg=name)
        assert [j.get("axis") for j in joints] == ["1 0 0", "0 1 0", "0 0 1"], name  # x, then y, then z
        limit = 720 if name in ("L_Shoulder", "R_Shoulder", "L_Elbow", "R_Elbow") else 180
        assert all(j.get("range") == f"{-limit} {limit}" for j in joints), name
        assert all(j.get("stiffness") is None and j.get("damping") is None for j in joints)  # PD lives in code
    assert sum(float(b[3]["mass"]) for b in bodies) == pytest.approx(sk.BODY_MASSES.sum())


@pytest.fixture(scope="module")
def sim():
    from refpo_warp.tasks.humanoid.model import HumanoidSim

    return HumanoidSim(4, "cpu")


def test_model_pd_gains_are_target_gains_not_springs(sim):
    import newton

    m = sim.model
    per_world = m.joint_dof_count // sim.num_envs
    assert per_world == 75 and m.body_count // sim.num_envs == 24
    ke = m.joint_target_ke.numpy()[:per_world]
    kd = m.joint_target_kd.numpy()[:per_world]
    mode = m.joint_target_mode.numpy()[:per_world]
    np.testing.assert_array_equal(ke[:6], 0.0)  # the free root is unactuated
    np.testing.assert_allclose(ke[6:], np.repeat(sk.PD_GAINS[1:, 0], 3))
    np.testing.assert_allclose(kd[6:], np.repeat(sk.PD_GAINS[1:, 1], 3))
    assert ke[6 + 3 * (sk.body_index("L_Knee") - 1)] == 800.0 and ke[6 + 3 * (sk.body_index("Chest") - 1)] == 1000.0
    assert (mode[6:] == int(newton.JointTargetMode.POSITION)).all()
    np.testing.assert_array_equal(m.joint_target_ke.numpy()[per_world : 2 * per_world], ke)  # every world alike
    assert not m.joint_stiffness.numpy().any()  # no passive springs
    np.testing.assert_allclose(m.joint_armature.numpy()[6:per_world], 0.02)
    masses = m.body_mass.numpy()[:24]
    np.testing.assert_allclose(masses, sk.BODY_MASSES, rtol=1e-5)


def test_rest_pose_body_positions_follow_rest_offsets(sim):
    body_q = sim.body_q.numpy()[0]
    root = body_q[0, :3]
    for b in range(1, sk.NUM_BODIES):
        chain, p = b, np.zeros(3)
        while chain > 0:
            p += sk.REST_OFFSETS[chain]
            chain = int(sk.PARENTS[chain])
        np.testing.assert_allclose(body_q[b, :3] - root, p, atol=1e-6, err_msg=sk.BODY_NAMES[b])


def test_pd_hold_keeps_the_standing_pose_and_nothing_touches_itself(sim):
    """Zero PD targets (the rest pose) held for 3 s on the ground: it stays upright, joints barely move."""
    sim.joint_target.zero_()
    start = sim.joint_q.numpy().copy()
    roots = []
    for _ in range(90):  # 3 s of 30 Hz control steps
        sim.simulate()
        roots.append(sim.joint_q.numpy()[:, :3].copy())
    q = sim.joint_q.numpy()
    assert np.isfinite(q).all()
    roots = np.array(roots)
    assert np.abs(roots[..., 2] - start[:, 2]).max() < 0.015  # the pelvis neither sinks nor tips over
    # The PD joints give a little under gravity (a static forward lean of ~3 cm), then the pose is still.
    assert np.abs(roots[..., :2] - start[:, :2]).max() < 0.05
    assert np.abs(roots[-30:] - roots[-1]).max() < 0.02  # no drift over the last second (a slight sway)
    assert np.abs(q[:, 7:]).max() < 0.05  # joint angles within 3 degrees of the targets
    assert np.abs(sim.joint_qd.numpy()).max() < 0.1
    # Standing at rest, only the four foot boxes touch anything (the ground): no self-contact.
    data = sim.solver.mjw_data
    nacon = int(data.nacon.numpy()[0])
    geoms = data.contact.geom.numpy()[:nacon]
    ground = [i for i in range(sim.solver.mj_model.ngeom) if sim.solver.mj_model.geom_bodyid[i] == 0]
    assert nacon > 0 and all(np.isin(pair, ground).any() for pair in geoms)


def test_random_targets_stay_within_contact_and_constraint_capacity():
    """Flailing under random PD targets (with ground and self contacts) must not overflow the per-world buffers."""
    from refpo_warp.tasks.humanoid.model import HumanoidSim, SimOptions

    sim = HumanoidSim(4, "cpu", SimOptions())
    rng = np.random.default_rng(0)
    scale = np.concatenate([np.zeros(7), sk.ACTION_SCALE]).astype(np.float32)
    peak_rows = peak_contacts = 0
    for _ in range(20):
        sim.joint_target.assign(scale * np.clip(rng.normal(size=(4, 76)), -1, 1).astype(np.float32))
        sim.simulate()
        rows, contacts = sim.constraint_usage()
        peak_rows, peak_contacts = max(peak_rows, rows), max(peak_contacts, contacts)
    assert np.isfinite(sim.joint_q.numpy()).all()
    assert 0 < peak_rows < sim.options.njmax
    assert 0 < peak_contacts < sim.options.nconmax * sim.num_envs
