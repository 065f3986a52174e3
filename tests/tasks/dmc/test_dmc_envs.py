"""Every DMC task: sizes, rewards at hand-chosen states, reset ranges, time-outs and non-finite resets (CPU)."""

import math

import numpy as np
import pytest
import torch

from refpo_warp.envs.registry import get_task, make_env
from refpo_warp.tasks.dmc import suite
from refpo_warp.utils.warp_setup import wp

N = 4
TASKS = tuple(suite.task_names())  # every module of tasks/dmc/suite/: a new task must be added below too
# Playground observation size, action size and control period (ctrl_dt) of every task.
SPACES = {
    "cartpole_balance": (5, 1, 0.01),
    "cartpole_swingup": (5, 1, 0.01),
    "pendulum_swingup": (3, 1, 0.02),
    "point_mass": (4, 2, 0.02),
    "point_mass_wall": (4, 2, 0.02),
    "ball_in_cup": (8, 2, 0.02),
    "finger_spin": (9, 2, 0.02),
    "reacher_easy": (6, 2, 0.02),
    "acrobot_swingup": (6, 1, 0.01),
    "cheetah_run": (17, 6, 0.01),
    "walker_walk": (24, 6, 0.025),
}
_ENVS = {}


def dmc_env(task):
    """One 4-env instance per task for this module (cheetah with a small bank of settled initial states); actions
    clipped, so hand-worked rewards see the controls as written (tanh squashing has its own test)."""
    if task not in _ENVS:
        extra = {"reset_bank_size": 16} if task == "cheetah_run" else {}
        _ENVS[task] = make_env(f"dmc_{task}", num_envs=N, device="cpu", seed=7, action_transform="clip", **extra)
    return _ENVS[task]


def g(d):
    """Gaussian tolerance with value 0.1 at one margin, at distance d (in margins): exp(-0.5 (d s)^2) = 0.1^(d^2)."""
    return 0.1 ** (d * d)


@pytest.mark.parametrize("task", TASKS)
def test_sizes_and_timing(task):
    env = dmc_env(task)
    num_obs, num_act, ctrl_dt = SPACES[task]
    assert env.num_actions == num_act
    assert env.get_observations()["policy"].shape == (N, num_obs)
    assert env.step_dt == pytest.approx(ctrl_dt)
    assert env.max_episode_length == 1000
    obs, rew, done, _extras = env.step(torch.zeros(N, num_act))
    assert obs["policy"].shape == (N, num_obs) and rew.shape == (N,) and not done.any()
    assert torch.isfinite(obs["policy"]).all() and torch.isfinite(rew).all()
    assert get_task(f"dmc_{task}").cfg_overrides == {"task": task}


# (MuJoCo qpos, qvel, action, hand-worked reward) per task. Derivations in the comments.
HAND_WORKED = {
    "cartpole_balance": [
        # upright (cos .3 + 1)/2, centered (1 + g(.5/2))/2, small_control (4 + 1 - .5^2)/5,
        # small_velocity (1 + g(2/5))/2
        ((0.5, 0.3), (0.1, 2.0), (0.5,), (math.cos(0.3) + 1) / 2 * (1 + g(0.25)) / 2 * 0.95 * (1 + g(0.4)) / 2),
        # an action beyond the range is clipped to 1: small_control (4 + 0)/5
        ((0.5, 0.3), (0.1, 2.0), (2.0,), (math.cos(0.3) + 1) / 2 * (1 + g(0.25)) / 2 * 0.8 * (1 + g(0.4)) / 2),
        ((0.0, 0.0), (0.0, 0.0), (0.0,), 1.0),
    ],
    "cartpole_swingup": [
        # horizontal pole: upright 1/2; centered (1 + g(1/2))/2; small_velocity (1 + g(1/5))/2
        ((-1.0, math.pi / 2), (0.0, -1.0), (0.0,), 0.5 * (1 + g(0.5)) / 2 * (1 + g(0.2)) / 2),
        ((0.0, math.pi), (0.0, 0.0), (0.0,), 0.0),  # hanging down: upright 0
    ],
    "pendulum_swingup": [  # 1 within 8 degrees of upright
        ((0.1,), (0.0,), (0.0,), 1.0),
        ((-0.13,), (3.0,), (1.0,), 1.0),
        ((0.15,), (0.0,), (0.0,), 0.0),
        ((math.pi,), (0.0,), (0.0,), 0.0),
    ],
    "point_mass": [
        ((0.01, 0.0), (0.0, 0.0), (0.5, -0.5), 0.95),  # inside the 0.015 target; control (4 + .75)/5
        ((0.03, 0.0), (0.0, 0.0), (0.0, 0.0), 0.1),  # one margin out: 0.1
        ((0.012, 0.016), (0.0, 0.0), (1.0, 0.0), g(1 / 3) * 0.9),  # dist .02 -> d = 1/3; control (4 + .5)/5
    ],
    "ball_in_cup": [  # ball (x, 0.2 + z) vs target (cup_x, 0.55 + cup_z), inside if |dx|, |dz| < 0.025
        ((0.0, 0.0, 0.01, 0.35), (0,) * 4, (0.0, 0.0), 1.0),
        ((0.1, 0.0, 0.1, 0.33), (0,) * 4, (0.0, 0.0), 1.0),
        ((0.0, 0.0, 0.03, 0.35), (0,) * 4, (0.0, 0.0), 0.0),
        ((0.0, 0.0, 0.0, 0.0), (0,) * 4, (0.0, 0.0), 0.0),
    ],
    "finger_spin": [  # 1 when the spinner turns at <= -15 rad/s
        ((0.0, 0.0, 0.0), (0.0, 0.0, -16.0), (0.0, 0.0), 1.0),
        ((0.0, 0.0, 0.0), (0.0, 0.0, -14.0), (0.0, 0.0), 0.0),
        ((0.0, 0.0, 1.0), (0.0, 0.0, 20.0), (0.0, 0.0), 0.0),
    ],
    "acrobot_swingup": [  # tip = (0,0,2) + (sin s, 0, cos s) + (sin(s+e), 0, cos(s+e)); target (0,0,4), radius .2
        ((0.0, 0.0), (0.0, 0.0), (0.0,), 1.0),
        ((0.0, math.pi / 2), (0.0, 0.0), (0.0,), g(math.sqrt(2) - 0.2)),  # tip (1,0,3): dist sqrt 2, margin 1
        ((math.pi, 0.0), (0.0, 0.0), (0.0,), g(3.8)),
    ],
    "cheetah_run": [  # pure translation: the centre of mass moves at the root x velocity; reward clip(v/10, 0, 1)
        ((0,) * 9, (4.0,) + (0,) * 8, (0,) * 6, 0.4),
        ((0,) * 9, (12.0,) + (0,) * 8, (0,) * 6, 1.0),
        ((0,) * 9, (-2.0,) + (0,) * 8, (0,) * 6, 0.0),
    ],
    "walker_walk": [  # qpos = (rootz, rootx, rooty, legs); torso at height 1.3 + rootz
        ((0,) * 9, (0.0, 0.8) + (0,) * 7, (0,) * 6, (5 * 0.8 + 1) / 6),  # standing, upright; move 1 - .4 * .5
        ((-0.4,) + (0,) * 8, (0.0, 1.5) + (0,) * 7, (0,) * 6, (3 * g(0.5) + 1) / 4),  # torso .9: d = .3/.6
        ((0.0, 0.0, math.pi) + (0,) * 6, (0,) * 9, (0,) * 6, 0.75 / 6),  # upside down: upright 0, move 0
    ],
}


@pytest.mark.parametrize("task", sorted(HAND_WORKED))
def test_rewards_at_hand_chosen_states(task):
    env = dmc_env(task)
    cases = HAND_WORKED[task]
    for start in range(0, len(cases), N):
        batch = cases[start : start + N]
        batch = batch + [batch[-1]] * (N - len(batch))
        qpos, qvel, act, expected = (torch.tensor([c[i] for c in batch], dtype=torch.float32) for i in range(4))
        env.set_state(qpos, qvel)
        np.testing.assert_allclose(env.compute_rewards(act).numpy(), expected.numpy(), rtol=1e-4, atol=1e-5)


def test_reacher_reward_at_hand_chosen_targets():
    env = dmc_env("reacher_easy")
    # shoulder 0, wrist 90 deg: fingertip at (0.12, 0.12); touching needs distance <= 0.05 + 0.01
    env.set_state(torch.tensor([[0.0, math.pi / 2]] * N), torch.zeros(N, 2))
    env.task.target.assign(np.array([[0.12, 0.07], [0.12, 0.05], [0.17, 0.12], [0.0, 0.0]], np.float32))
    np.testing.assert_allclose(env.compute_rewards(torch.zeros(N, 2)).numpy(), [1.0, 0.0, 1.0, 0.0])


def _reset_samples(env, rounds=16):
    qpos, qvel = [], []
    for _ in range(rounds):
        env.reset()
        qpos.append(env.qpos.clone())
        qvel.append(env.joint_qd.clone())
    return torch.cat(qpos).numpy(), torch.cat(qvel).numpy()


def _check_uniform(values, low, high, min_cover=0.6):
    assert values.min() >= low - 1e-5 and values.max() <= high + 1e-5, (values.min(), values.max(), low, high)
    assert values.max() - values.min() >= min_cover * (high - low)  # really randomised over the range


DEG = math.pi / 180
# Uniform reset ranges of the MuJoCo qpos coordinates (Playground reset functions); absent: fixed value given.
RESET_RANGES = {
    "cartpole_balance": {0: (-0.1, 0.1), 1: (-0.034, 0.034)},
    "pendulum_swingup": {0: (0.0, math.pi)},
    "point_mass": {0: (-0.29, 0.29), 1: (-0.29, 0.29)},
    "finger_spin": {0: (-110 * DEG, 110 * DEG), 1: (-110 * DEG, 110 * DEG), 2: (-math.pi, math.pi)},
    "reacher_easy": {0: (-math.pi, math.pi), 1: (-160 * DEG, 160 * DEG)},
    "acrobot_swingup": {0: (-math.pi, math.pi), 1: (-math.pi, math.pi)},
    "walker_walk": {
        2: (-math.pi, math.pi),
        3: (-20 * DEG, 100 * DEG),
        4: (-150 * DEG, 0.0),
        5: (-45 * DEG, 45 * DEG),
        6: (-20 * DEG, 100 * DEG),
        7: (-150 * DEG, 0.0),
        8: (-45 * DEG, 45 * DEG),
    },
}


@pytest.mark.parametrize("task", sorted(RESET_RANGES))
def test_uniform_resets_stay_in_their_ranges(task):
    qpos, qvel = _reset_samples(dmc_env(task))
    ranges = RESET_RANGES[task]
    for j in range(qpos.shape[1]):
        if j in ranges:
            _check_uniform(qpos[:, j], *ranges[j])
        else:
            np.testing.assert_array_equal(qpos[:, j], 0.0)  # e.g. the walker's root x and z
    if task == "cartpole_balance":
        assert np.abs(qvel).max() < 0.06 and qvel.std() > 0.003  # 0.01 N(0, 1)
    else:
        np.testing.assert_array_equal(qvel, 0.0)


def test_swingup_and_fixed_resets():
    qpos, qvel = _reset_samples(dmc_env("cartpole_swingup"))
    assert np.abs(qpos[:, 0]).max() < 0.06 and np.abs(qpos[:, 1] - math.pi).max() < 0.06  # 0.01 N(0, 1) noise
    assert qpos[:, 1].std() > 0.003 and np.abs(qvel).max() < 0.06
    qpos, qvel = _reset_samples(dmc_env("ball_in_cup"), rounds=2)
    np.testing.assert_array_equal(qpos, 0.0)  # Playground starts ball-in-cup at the model's rest pose
    np.testing.assert_array_equal(qvel, 0.0)


def test_reacher_targets_and_cheetah_settled_starts():
    env = dmc_env("reacher_easy")
    targets = []
    for _ in range(16):
        env.reset()
        targets.append(env.task.target.numpy().copy())
    radius = np.linalg.norm(np.concatenate(targets), axis=1)
    _check_uniform(radius, 0.05, 0.2, min_cover=0.5)
    qpos, qvel = _reset_samples(dmc_env("cheetah_run"), rounds=8)
    leg_ranges = np.radians([(-30, 60), (-50, 50), (-230, 50), (-57, 0.4), (-70, 50), (-28, 28)])
    assert (qpos[:, 3:] >= leg_ranges[:, 0] - 0.05).all() and (qpos[:, 3:] <= leg_ranges[:, 1] + 0.05).all()
    assert np.abs(qpos[:, 1]).max() < 0.3  # resting on the ground after settling (torso at 0.7 + rootz)
    assert np.abs(qvel).max() < 1.0 and len(np.unique(qpos[:, 3])) > 1  # settled, and drawn from a varied bank


def test_time_out_truncates_and_restarts():
    env = dmc_env("cartpole_balance")
    env.reset()
    zeros = torch.zeros(N, 1)
    for _ in range(999):
        _, _, done, extras = env.step(zeros)
        assert not done.any()
    obs, _rew, done, extras = env.step(zeros)
    assert done.all() and extras["time_outs"].all()  # truncated: the value is bootstrapped
    assert not env._terminated.any()
    assert (env.episode_length_buf == 0).all()
    assert (obs["policy"][:, 1] > 0.99).all()  # a fresh balance start (pole near upright)
    np.testing.assert_array_equal(extras["log"]["Episode/nonfinite_resets"].numpy(), 0.0)


@pytest.mark.parametrize("task", ["cartpole_balance", "cheetah_run"])
def test_nonfinite_state_resets_that_env(task):
    env = dmc_env(task)
    env.reset()
    zeros = torch.zeros(N, env.num_actions)
    env.step(zeros)
    qpos, qvel = env.qpos.clone(), env.joint_qd.clone()
    qvel[1, 0] = float("nan")
    env.set_state(qpos, qvel)
    obs, rew, done, extras = env.step(zeros)
    assert done.tolist() == [False, True, False, False]
    assert not extras["time_outs"].any()  # terminated, not bootstrapped
    assert rew[1] == 0.0 and torch.isfinite(rew).all()
    assert extras["log"]["Episode/nonfinite_resets"].tolist() == [1.0]
    assert torch.isfinite(obs["policy"]).all() and env.episode_length_buf[1] == 0
    for _ in range(5):  # the reset env keeps simulating normally (solver warm start was cleared)
        obs, rew, done, _ = env.step(zeros)
        assert not done.any() and torch.isfinite(obs["policy"]).all()


def test_unknown_task_name_is_a_clear_error():
    with pytest.raises(ValueError, match="cartpole_balance"):
        make_env("dmc_cartpole_balance", num_envs=1, device="cpu", task="cartpole_balanse")


def test_tanh_squashing_sends_tanh_of_the_stored_action_to_the_env():
    """DMC's default action transform (Playground): the env's controls are tanh(a); the learner's a is untouched."""
    squashed = make_env("dmc_cartpole_balance", num_envs=N, device="cpu", seed=7)
    clipped = dmc_env("cartpole_balance")
    assert squashed.cfg.action_transform == "tanh"
    actions = torch.tensor([[0.3], [-2.0], [5.0], [0.0]])
    stored = actions.clone()
    squashed.step(actions)
    torch.testing.assert_close(actions, stored)  # the caller's (stored, pre-tanh) action is not modified
    torch.testing.assert_close(wp.to_torch(squashed.sim.views.ctrl), torch.tanh(actions))
    qpos, qvel = torch.zeros(N, 2), torch.zeros(N, 2)
    for env in (squashed, clipped):
        env.set_state(qpos, qvel)
    np.testing.assert_allclose(
        squashed.compute_rewards(actions).numpy(), clipped.compute_rewards(torch.tanh(actions)).numpy(), rtol=1e-6
    )
