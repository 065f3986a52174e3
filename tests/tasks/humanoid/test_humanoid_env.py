"""The humanoid tracking env: kinematic replay (zero error, maximal reward), observations and reward against an
independent numpy implementation, heading invariance, termination, eval mode and its episode metrics."""

import numpy as np
import pytest
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.motion import skeleton as sk
from refpo_warp.motion.rotations import quat_conjugate, quat_mul, quat_rotate, quat_to_axis_angle
from refpo_warp.utils.warp_setup import wp

DT = 1.0 / 30.0


@pytest.fixture(scope="module")
def env():
    return make_env("humanoid_all", num_envs=3, device="cpu", seed=3)


# ------------------------------------------------------------------------------------------- numpy references
def sim_bodies(env):
    """World positions, xyzw rotations, origin velocities and angular velocities of the simulated bodies."""
    bq = env.sim.body_q.numpy().astype(np.float64)
    bqd = env.sim.body_qd.numpy().astype(np.float64)
    rot = bq[..., 3:]
    omega = bqd[..., 3:]
    vel = bqd[..., :3] - np.cross(omega, quat_rotate(rot, env.sim.body_com.numpy().astype(np.float64)[None]))
    return bq[..., :3], rot, vel, omega


def frames(ref):
    keys = ("body_pos", "body_rot", "body_vel", "body_angvel")
    return [np.asarray(getattr(ref, k).numpy(), np.float64) for k in keys]


def heading_inverse(q):
    fwd = quat_rotate(q, np.array([1.0, 0.0, 0.0]))
    yaw = np.arctan2(fwd[..., 1], fwd[..., 0])
    return np.stack([np.zeros_like(yaw), np.zeros_like(yaw), np.sin(-yaw / 2), np.cos(-yaw / 2)], -1)


def tan_norm(q):
    return np.concatenate([quat_rotate(q, np.array([1.0, 0, 0])), quat_rotate(q, np.array([0, 0, 1.0]))], -1)


def numpy_observation(pos, rot, vel, omega, rpos, rrot, rvel, romega):
    """The reference implementation's self + task observation for one env (arrays (24, .))."""
    h = np.broadcast_to(heading_inverse(rot[0]), (24, 4))
    hq = quat_conjugate(h)
    self_obs = [
        pos[0, 2:3],
        quat_rotate(h[1:], pos[1:] - pos[0]).ravel(),
        tan_norm(quat_mul(h, rot)).ravel(),
        quat_rotate(h, vel).ravel(),
        quat_rotate(h, omega).ravel(),
    ]
    diff_rot = quat_mul(quat_mul(h, quat_mul(rrot, quat_conjugate(rot))), hq)
    task = [
        quat_rotate(h, rpos - pos).ravel(),
        tan_norm(diff_rot).ravel(),
        quat_rotate(h, rvel - vel).ravel(),
        quat_rotate(h, romega - omega).ravel(),
        quat_rotate(h, rpos - pos[0]).ravel(),
        tan_norm(quat_mul(h, rrot)).ravel(),
    ]
    return np.concatenate(self_obs + task)


def numpy_imitation_reward(pos, rot, vel, omega, rpos, rrot, rvel, romega):
    angle = np.linalg.norm(quat_to_axis_angle(quat_mul(rrot, quat_conjugate(rot))), axis=-1)
    return (
        0.5 * np.exp(-100 * np.mean((rpos - pos) ** 2))
        + 0.3 * np.exp(-10 * np.mean(angle**2))
        + 0.1 * np.exp(-0.1 * np.mean((rvel - vel) ** 2))
        + 0.1 * np.exp(-0.1 * np.mean((romega - omega) ** 2))
    )


def set_sim_to_reference(env, ref):
    """Write the reference state into every world's joint coordinates and run forward kinematics (replay)."""
    import newton

    from refpo_warp.tasks.humanoid.tracking_kernels import write_reference_state_kernel

    s = env.sim
    all_envs = wp.array(np.ones(env.num_envs, bool), dtype=wp.bool, device="cpu")
    wp.launch(
        write_reference_state_kernel,
        dim=env.num_envs,
        inputs=[all_envs, ref, s.root_com],
        outputs=[s.joint_q, s.joint_qd],
        device="cpu",
    )
    newton.eval_fk(s.model, s.state.joint_q, s.state.joint_qd, s.state)


# ------------------------------------------------------------------------------------------- tests
def test_spaces(env):
    obs = env.get_observations()
    assert env.num_actions == 69
    assert obs["policy"].shape == (3, 934) and obs["critic"].shape == (3, 934)
    torch.testing.assert_close(obs["policy"], obs["critic"])  # "all" conditioning hides nothing


def test_kinematic_replay_gives_zero_error_and_maximal_reward(env):
    """Sim joint coordinates set to the reference's dof_pos/root pose each step: FK reproduces every body pose."""
    import dataclasses

    from refpo_warp.tasks.humanoid.reward_terms import reward_params
    from refpo_warp.tasks.humanoid.tracking_kernels import reward_and_termination_kernel

    no_power = reward_params(dataclasses.replace(env.cfg, power_coef=0.0))
    env.reset()
    # Whole frames: between frames the library interpolates body poses and joint angles separately (~1 mm apart).
    start = torch.from_numpy(np.floor(env.ref_time.numpy() * 30.0) / 30.0).float()
    rewards = []
    for k in range(0, 45, 3):
        ref = env.reference_at(start + k * DT)
        set_sim_to_reference(env, ref)
        pos, rot, vel, omega = sim_bodies(env)
        rpos, rrot, rvel, romega = frames(ref)
        assert np.abs(pos - rpos).max() < 2e-6
        assert np.abs(np.abs(np.sum(rot * rrot, -1)) - 1).max() < 1e-6
        # Joint-rate velocities vs the library's finite differences of body poses agree to about 1e-3 on average.
        assert np.abs(vel - rvel).mean() < 5e-3 and np.abs(omega - romega).mean() < 1e-2
        b, s, c = env.buffers, env.sim, env.cfg
        env._episode_length.fill_(5)  # past the power-free steps
        s.joint_target.assign(s.joint_q.numpy())  # targets at the current pose; the power term uses them
        wp.launch(
            reward_and_termination_kernel,
            dim=env.num_envs,
            inputs=[
                s.body_q,
                s.body_qd,
                s.body_com,
                s.joint_q,
                s.joint_qd,
                s.joint_target,
                env.kp,
                env.kd,
                500.0,
                ref,
                env.eval_body,
                env.clip_id,
                env.ref_time,
                env.motion.clip_duration_device,
                b.episode_length,
                0,
                c.termination_distance,
                c.eval_termination_distance,
                c.max_joint_speed,
                no_power,
                env.mpjpe_sum,
            ],
            outputs=[
                b.rewards,
                b.terminated,
                b.truncated,
                b.metrics["success"],
                b.metrics["mpjpe_mm"],
                b.metrics["alive_steps"],
                b.reward_terms,
            ],
            device="cpu",
        )
        rewards.append(env._rewards.clone())
        assert not env._terminated.any()
        assert float(env._metrics["mpjpe_mm"].max()) < 1e-2  # micrometres
    rewards = torch.stack(rewards)
    assert float(rewards.min()) > 0.999 and float(rewards.max()) <= 1.0 + 1e-6
    env.reset()


def test_observation_matches_numpy_reference(env):
    generator = torch.Generator().manual_seed(0)
    for _ in range(2):
        obs, _, _done, _ = env.step(0.3 * (torch.rand(3, 69, generator=generator) * 2 - 1))
    ref = env.reference_at(torch.from_numpy(env.obs_time.numpy().copy()))
    sim = sim_bodies(env)
    expected = np.stack([numpy_observation(*[a[i] for a in sim], *[a[i] for a in frames(ref)]) for i in range(3)])
    np.testing.assert_allclose(obs["critic"].numpy(), expected, atol=2e-4)
    # The reference is one control step ahead of the simulator's clock.
    np.testing.assert_allclose(env.obs_time.numpy(), env.ref_time.numpy() + DT, atol=1e-6)


def test_reward_matches_numpy_reference(env):
    """Reward of steps that follow the reference joint angles as PD targets (episodes long enough for the power
    term to switch on) against numpy."""
    env.reset()
    scale = torch.tensor(sk.ACTION_SCALE, dtype=torch.float32)
    gains = np.repeat(sk.PD_GAINS[1:], 3, axis=0)
    checked_power = 0
    for _ in range(6):
        ref_next = env.reference_at(torch.from_numpy(env.obs_time.numpy().copy()))
        _, rewards, done, _ = env.step(torch.from_numpy(ref_next.dof_pos.numpy().copy()) / scale)
        keep = ~done.numpy()  # a finished env was re-initialised; its state no longer matches its reward
        pos, rot, vel, omega = sim_bodies(env)
        ref = frames(env.reference_at())
        imitation = np.array(
            [numpy_imitation_reward(pos[i], rot[i], vel[i], omega[i], *[a[i] for a in ref]) for i in range(3)]
        )
        q, qd = env.sim.joint_q.numpy()[:, 7:], env.sim.joint_qd.numpy()[:, 6:]
        target = env.sim.joint_target.numpy()[:, 7:]
        tau = np.clip(gains[:, 0] * (target - q) - gains[:, 1] * qd, -500, 500)
        power_on = env._episode_length.numpy() > 3  # off for an episode's first 3 steps
        power = np.where(power_on, np.abs(tau * qd).sum(1), 0.0)
        checked_power += int((power_on & keep).sum())
        np.testing.assert_allclose(rewards.numpy()[keep], (imitation - 0.0005 * power)[keep], rtol=1e-4, atol=1e-4)
    assert checked_power > 0


def test_actions_map_to_pd_targets(env):
    """PD target = scale * clip(a, -1, 1): pi per hinge, 5 for the knees' y hinge, 0 for frozen hands and toes."""
    env.reset()
    actions = torch.full((3, 69), 0.2)
    actions[1] = 3.0  # clipped to 1
    env.step(actions)
    target = env.sim.joint_target.numpy()[:, 7:]
    knee_y = 3 * (sk.body_index("L_Knee") - 1) + 1
    assert target[0, knee_y] == pytest.approx(1.0) and target[1, knee_y] == pytest.approx(5.0)
    assert target[0, 0] == pytest.approx(0.2 * np.pi) and target[1, 0] == pytest.approx(np.pi)
    for name in sk.FROZEN_HAND_TOE:
        body = sk.body_index(name)
        assert not target[:, 3 * (body - 1) : 3 * body].any(), name
    assert np.count_nonzero(target[0]) == 69 - 12


def test_observation_is_heading_invariant(env):
    """Turning the whole scene (simulator and reference) about the vertical and shifting it gives the same obs."""
    from refpo_warp.motion.motion_library import MotionFrames
    from refpo_warp.tasks.humanoid.observations import observation_kernel

    env.step(0.3 * torch.ones(3, 69))
    s = env.sim
    ref = env.reference_at(torch.from_numpy(env.obs_time.numpy().copy()))
    angle, shift = 1.1, np.array([0.7, -2.0, 0.0])
    turn = np.array([0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)])

    def moved(points):
        return quat_rotate(turn, points) + shift

    bq, bqd = s.body_q.numpy(), s.body_qd.numpy()
    bq2 = np.concatenate([moved(bq[..., :3]), quat_mul(turn, bq[..., 3:])], -1)
    bqd2 = np.concatenate([quat_rotate(turn, bqd[..., :3]), quat_rotate(turn, bqd[..., 3:])], -1)
    rpos, rrot, rvel, romega = frames(ref)
    ref2 = MotionFrames()  # the body arrays: the observation reads no joint angles or rates
    ref2.body_pos = wp.array(moved(rpos).astype(np.float32), dtype=wp.vec3)
    ref2.body_rot = wp.array(quat_mul(turn, rrot).astype(np.float32), dtype=wp.quat)
    ref2.body_vel = wp.array(quat_rotate(turn, rvel).astype(np.float32), dtype=wp.vec3)
    ref2.body_angvel = wp.array(quat_rotate(turn, romega).astype(np.float32), dtype=wp.vec3)
    arrays = [
        wp.array(bq2.astype(np.float32), dtype=wp.transform),
        wp.array(bqd2.astype(np.float32), dtype=wp.spatial_vector),
        s.body_com,
        ref2,
        env.mask,
    ]
    critic, policy = wp.zeros((3, 934), dtype=float), wp.zeros((3, 934), dtype=float)
    wp.launch(observation_kernel, dim=(3, 24), inputs=arrays, outputs=[critic, policy])
    np.testing.assert_allclose(critic.numpy(), env._obs["critic"].numpy(), atol=2e-4)


def test_a_body_off_the_reference_terminates_the_episode(env):
    # Start from the fixture's fresh state (seed 3, the reset at construction), so the new episode's random start
    # does not depend on which tests ran before in this process: between frames the library interpolates body
    # positions and joint angles separately (up to ~5e-5 m apart), and some start times miss the 1e-5 m check below.
    env.reseed(3)
    env.reset()
    env.reset()
    env.step(torch.zeros(3, 69))
    # Push world 1's whole body 0.3 m sideways: every body is now more than 0.25 m from the reference.
    q = env.sim.joint_q.numpy()
    q[1, 1] += 0.3
    env.sim.joint_q.assign(q)
    _, _rewards, _done, extras = env.step(torch.zeros(3, 69))
    assert env._terminated[1] and not extras["time_outs"][1]
    assert float(env._metrics["success"][1]) == 0.0 and float(env._metrics["alive_steps"][1]) == 2.0
    assert float(env._metrics["mpjpe_mm"][1]) > 100.0  # the second frame was 0.3 m off
    assert int(env._episode_length[1]) == 0  # re-initialised from the reference
    pos, _, _, _ = sim_bodies(env)
    np.testing.assert_allclose(pos[1], frames(env.reference_at())[0][1], atol=1e-5)


@pytest.fixture(scope="module")
def eval_env():
    return make_env("humanoid_root", num_envs=3, device="cpu", seed=0, eval_mode=True)


def test_eval_mode_plays_clip_i_from_its_start(eval_env):
    env = eval_env
    env.reset()
    np.testing.assert_array_equal(env.clip_id.numpy(), [0, 1, 2])
    np.testing.assert_array_equal(env.ref_time.numpy(), 0.0)
    steps = np.floor(env.motion.clip_duration / DT + 1e-6).astype(int)
    assert env.max_episode_length == steps.max() + 1
    from refpo_warp.envs.warp_vec_env import WarpVecEnv

    assert type(env).eval_num_envs(env.cfg) == env.motion.num_clips and issubclass(type(env), WarpVecEnv)


def test_eval_metrics_for_a_clip_played_to_its_end(eval_env):
    """Clip 0 replayed by the reference joint angles as PD targets: it ends by time-out with success 1."""
    env = eval_env
    env.reset()
    scale = torch.tensor(sk.ACTION_SCALE, dtype=torch.float32)
    steps0 = int(np.floor(env.motion.clip_duration[0] / DT + 1e-6))
    mpjpe = []
    for k in range(1, steps0 + 1):  # noqa: B007  (k, the steps taken, is read after the loop)
        ref = env.reference_at(torch.from_numpy(env.obs_time.numpy().copy()))
        _, _, done, extras = env.step(torch.from_numpy(ref.dof_pos.numpy().copy()) / scale)
        pos, _, _, _ = sim_bodies(env)
        if not done[0]:
            mpjpe.append(np.linalg.norm(pos[0] - frames(env.reference_at())[0][0], axis=-1).mean())
        if done[0]:
            break
    assert k == steps0 and bool(extras["time_outs"][0]) and not env._terminated[0]
    assert float(env._metrics["success"][0]) == 1.0 and float(env._metrics["alive_steps"][0]) == steps0
    # mpjpe_mm averages the per-step mean body error over the episode's steps. The state of the last step was
    # replaced by the next episode's start, so its error is what remains of the total.
    assert len(mpjpe) == steps0 - 1
    last = float(env._metrics["mpjpe_mm"][0]) / 1000 * steps0 - np.sum(mpjpe)
    assert 0.0 <= last < 0.5 and abs(last - mpjpe[-1]) < 0.05
