"""Generic Newton helpers (refpo_warp/sim): N-world MJCF models, per-world views, substepping, resets, health."""

import math

import numpy as np
import pytest

from refpo_warp.sim import MuJoCoWorlds, mjcf_timestep, world_com_velocity, world_state_finite
from refpo_warp.sim.mjcf_worlds import build_mjcf_worlds
from refpo_warp.tasks.dmc.task import MODELS_DIR
from refpo_warp.utils.warp_setup import wp

PENDULUM = MODELS_DIR / "pendulum.xml"
CHEETAH = MODELS_DIR / "cheetah.xml"


@pytest.fixture(scope="module")
def pendulum():
    return MuJoCoWorlds(PENDULUM, 3, "cpu", substeps=1)


def test_timestep_is_read_from_the_file(tmp_path):
    assert mjcf_timestep(PENDULUM) == pytest.approx(0.01)
    assert mjcf_timestep(MODELS_DIR / "walker.xml") == pytest.approx(0.0025)
    bare = tmp_path / "bare.xml"
    bare.write_text("<mujoco><worldbody/></mujoco>")
    assert mjcf_timestep(bare) == pytest.approx(0.002)  # MuJoCo's default


def test_bad_files_get_clear_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"missing.xml"):
        build_mjcf_worlds(tmp_path / "missing.xml", 2, "cpu")
    wrong = tmp_path / "wrong.xml"
    wrong.write_text("<robot/>")
    with pytest.raises(ValueError, match="expected <mujoco>"):
        mjcf_timestep(wrong)
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><option timestep='fast'/></mujoco>")
    with pytest.raises(ValueError, match="not a number"):
        mjcf_timestep(broken)


def test_views_are_per_world_and_zero_copy(pendulum):
    v = pendulum.views
    assert v.joint_q.shape == (3, 1) and v.joint_qd.shape == (3, 1) and v.ctrl.shape == (3, 1)
    assert v.body_q.shape == (3, 1) and v.body_mass.shape == (3, 1)
    np.testing.assert_allclose(v.body_mass.numpy(), 1.0)  # the 1 kg bob (pole and base are massless)
    wp.to_torch(v.joint_q)[1, 0] = 0.7
    assert pendulum.state.joint_q.numpy()[1] == pytest.approx(0.7)  # the view aliases the solver's state
    assert v.body_index("pole") == 0
    with pytest.raises(KeyError, match="pole"):
        v.body_index("no_such_body")


def test_forward_kinematics_follows_joint_coordinates(pendulum):
    q = np.array([[0.0], [math.pi / 2], [math.pi]], np.float32)
    pendulum.views.joint_q.assign(q)
    pendulum.forward_kinematics()
    bob = [wp.transform_point(wp.transform(*pose), wp.vec3(0, 0, 0.5)) for pose in pendulum.views.body_q.numpy()[:, 0]]
    # hinge about +y at z = 0.6: angle a puts the bob at (0.5 sin a, 0, 0.6 + 0.5 cos a)
    np.testing.assert_allclose(np.array(bob), [[0, 0, 1.1], [0.5, 0, 0.6], [0, 0, 0.1]], atol=1e-6)


def test_joint_ref_offset_is_exposed():
    finger = MuJoCoWorlds(MODELS_DIR / "finger_spin.xml", 1, "cpu")
    np.testing.assert_allclose(finger.views.coord_ref.numpy(), [-math.pi / 2, 0.0, 0.0], atol=1e-6)
    # Newton limits are qpos - ref: the proximal range (-110, 110) deg becomes (-20, 200) deg
    np.testing.assert_allclose(np.degrees(finger.views.limit_lower[:2]), [-20.0, -110.0], atol=1e-4)
    np.testing.assert_allclose(np.degrees(finger.views.limit_upper[:2]), [200.0, 110.0], atol=1e-4)


def _swing(substeps, calls, graph=False):
    sim = MuJoCoWorlds(PENDULUM, 2, "cpu", substeps=substeps)
    sim.views.joint_q.assign(np.array([[0.3], [2.0]], np.float32))
    wp.to_torch(sim.views.ctrl)[:] = 0.5
    if graph:
        sim.simulate_many(calls)
    else:
        for _ in range(calls):
            sim.simulate()
    return sim.views.joint_q.numpy().copy(), sim.views.joint_qd.numpy().copy()


def test_odd_and_even_substeps_and_graph_replay_agree():
    one = _swing(1, 6)
    three = _swing(3, 2)  # odd: the result must be copied back into the canonical state
    two = _swing(2, 3)
    replayed = _swing(3, 2, graph=True)  # first call eager, the second replayed from a captured graph
    for other in (three, two, replayed):
        np.testing.assert_allclose(other[0], one[0], atol=1e-6)
        np.testing.assert_allclose(other[1], one[1], atol=1e-6)
    assert abs(one[0][0, 0] - 0.3) > 1e-3  # it moved


def test_after_reset_clears_solver_memory_of_masked_worlds_only(pendulum):
    data = pendulum.solver.mjw_data
    data.qacc_warmstart.fill_(3.0)
    data.qfrc_applied.fill_(2.0)
    pendulum.after_reset(wp.array([True, False, True], dtype=wp.bool, device="cpu"))
    np.testing.assert_array_equal(data.qacc_warmstart.numpy()[:, 0], [0.0, 3.0, 0.0])
    np.testing.assert_array_equal(data.qfrc_applied.numpy()[:, 0], [0.0, 2.0, 0.0])


@wp.kernel
def flag_nonfinite_worlds(
    joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float), nonfinite: wp.array(dtype=wp.bool)
):
    w = wp.tid()
    nonfinite[w] = not world_state_finite(joint_q, joint_qd, w)


def test_nonfinite_worlds_are_flagged():
    q = wp.array(np.array([[0.0, 1.0], [np.nan, 0.0], [0.0, 0.0]], np.float32), dtype=float, device="cpu")
    qd = wp.array(np.array([[0.0], [0.0], [np.inf]], np.float32), dtype=float, device="cpu")
    flags = wp.zeros(3, dtype=wp.bool, device="cpu")
    wp.launch(flag_nonfinite_worlds, dim=3, inputs=[q, qd, flags], device="cpu")
    np.testing.assert_array_equal(flags.numpy(), [False, True, True])


@wp.kernel
def _com_velocity(
    body_qd: wp.array2d(dtype=wp.spatial_vector), body_mass: wp.array2d(dtype=float), out: wp.array(dtype=wp.vec3)
):
    w = wp.tid()
    out[w] = world_com_velocity(body_qd, body_mass, w)


def test_world_com_velocity_is_the_mass_weighted_mean():
    sim = MuJoCoWorlds(CHEETAH, 2, "cpu")
    rng = np.random.default_rng(0)
    sim.views.joint_qd.assign(rng.normal(size=(2, 9)).astype(np.float32))
    sim.forward_kinematics()
    out = wp.zeros(2, dtype=wp.vec3, device="cpu")
    wp.launch(_com_velocity, dim=2, inputs=[sim.views.body_qd, sim.views.body_mass, out], device="cpu")
    qd, m = sim.views.body_qd.numpy(), sim.views.body_mass.numpy()
    expected = (m[..., None] * qd[..., :3]).sum(1) / m.sum(1, keepdims=True)
    np.testing.assert_allclose(out.numpy(), expected, rtol=1e-5, atol=1e-6)
    assert m[0].sum() == pytest.approx(14.0, rel=1e-5)  # the cheetah's total mass
