"""The humanoid's MuJoCo C twin (the benchmark's anchor) is the simulator's model: same options and PD actuators, and
one control step from the same states agrees with MuJoCo Warp to float32 rounding."""

import numpy as np
import pytest
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.motion import skeleton as sk
from refpo_warp.tasks.humanoid import mujoco_c


def qpos_qvel(model, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``qpos`` and ``qvel`` out of full-physics states (..., nstate): the state starts with time, qpos, qvel."""
    return states[..., 1 : 1 + model.nq], states[..., 1 + model.nq : 1 + model.nq + model.nv]


@pytest.fixture(scope="module")
def env():
    return make_env("humanoid_all", num_envs=4, device="cpu", seed=3)


def test_c_model_has_the_simulators_settings(env):
    sim = env.sim
    model = mujoco_c.c_model(sim)
    settings = mujoco_c.solver_settings(model)
    assert settings["timestep"] == pytest.approx(1.0 / 120.0) and sim.substeps == 4
    assert settings["integrator"] == "mjINT_IMPLICITFAST" and settings["solver"] == "mjSOL_NEWTON"
    assert settings["iterations"] == sim.options.iterations
    assert settings["ls_iterations"] == sim.options.ls_iterations
    assert settings["cone"] == "mjCONE_PYRAMIDAL"
    assert (model.nq, model.nv, model.nu) == (76, 75, 69)
    kp, kd = np.repeat(sk.PD_GAINS[1:], 3, axis=0).T
    np.testing.assert_allclose(model.actuator_gainprm[:, 0], kp)
    np.testing.assert_allclose(model.actuator_biasprm[:, 1:3], np.stack([-kp, -kd], 1))
    np.testing.assert_allclose(model.jnt_actfrcrange[1:], [[-500.0, 500.0]] * 69)


def _one_step_difference(env, actions):
    """Max |qpos| and |qvel| difference between our control step and MuJoCo C's from the same state."""
    sim = env.sim
    model = mujoco_c.c_model(sim)
    states = mujoco_c.c_states(model, sim)
    env.step(actions)
    assert not (env._terminated | env._truncated).any()  # every world still holds the stepped state
    out = mujoco_c.rollout(model, states, sim.joint_target.numpy()[:, None, 7:], sim.substeps)
    qpos, qvel = qpos_qvel(model, out[:, -1])
    ours = mujoco_c.newton_to_mujoco(sim.joint_q.numpy(), sim.joint_qd.numpy(), sim.body_com.numpy()[0])
    # Quaternion entries compare directly: both start from the same sign and move by less than a degree.
    return np.abs(qpos - ours[0]).max(), np.abs(qvel - ours[1]).max(), np.abs(ours[1]).max()


def test_one_control_step_matches_mujoco_c(env):
    """PD targets at the reference's next pose, then uniform random targets: MuJoCo Warp (float32) and MuJoCo C
    (float64) end the 4 substeps (ground contacts, PD actuators, joint limits) in the same state."""
    env.reset()
    scale = torch.tensor(sk.ACTION_SCALE, dtype=torch.float32)
    ref = env.reference_at(torch.from_numpy(env.obs_time.numpy().copy()))
    dq, dqd, speed = _one_step_difference(env, torch.from_numpy(ref.dof_pos.numpy().copy()) / scale)
    assert dq < 1e-5 and dqd < 1e-3, (dq, dqd)  # measured: 3e-7 and 3e-6
    env.reset()
    generator = torch.Generator().manual_seed(0)
    dq, dqd, speed = _one_step_difference(env, torch.rand(4, 69, generator=generator) * 2 - 1)
    assert speed > 5.0  # the random targets really swing the joints
    assert dq < 1e-4 and dqd < 1e-2, (dq, dqd)  # measured: 5e-6 and 2e-4 at 30 rad/s
