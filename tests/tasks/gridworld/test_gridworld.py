"""The Warp GridWorld against the independent numpy/gymnasium implementation, resets and the VecEnv contract."""

import numpy as np
import pytest
import torch

from refpo_warp import make_env
from refpo_warp.tasks.gridworld.cfg import GridWorldCfg
from refpo_warp.tasks.gridworld.env import GridWorldEnv
from refpo_warp.tasks.gridworld.gym_env import GridWorldGymEnv

NUM_ENVS = 32


@pytest.fixture(scope="module")
def env():
    return make_env("gridworld", num_envs=NUM_ENVS, device="cpu", seed=3)


def test_matches_numpy_reference_on_random_actions(env):
    rng = np.random.default_rng(0)
    refs = [GridWorldGymEnv() for _ in range(NUM_ENVS)]
    env.reset()
    for i, ref in enumerate(refs):
        ref.reset(options={"start": env.positions[i].tolist()})
    compared_dones = 0
    for _ in range(400):
        # Include exact ties at +-0.5 (numpy rounds them to 0) and out-of-range values (clipped).
        actions = rng.choice([-1.7, -1.0, -0.5, -0.3, 0.0, 0.49, 0.5, 0.51, 1.0, 2.0], size=(NUM_ENVS, 2))
        obs, rew, done, extras = env.step(torch.tensor(actions, dtype=torch.float32))
        for i, ref in enumerate(refs):
            r_obs, r_rew, r_term, r_trunc, r_info = ref.step(actions[i])
            assert rew[i].item() == r_rew
            assert bool(done[i]) == (r_term or r_trunc)
            assert bool(extras["time_outs"][i]) == r_trunc
            if r_term or r_trunc:
                compared_dones += 1
                assert env.episode_metric_buffers["success"][i].item() == float(r_term)
                assert env.episode_metric_buffers["reached_top"][i].item() == float(r_info["reached_top"])
                ref.reset(options={"start": env.positions[i].tolist()})  # follow the env's auto-reset
                r_obs = ref._obs()
            np.testing.assert_allclose(obs["policy"][i].numpy(), r_obs, atol=1e-7)
    assert compared_dones > 50


def test_time_out_at_max_episode_length():
    env = make_env("gridworld", num_envs=4, device="cpu", max_episode_length=7)
    env.reset_to(torch.tensor([[12, 12]] * 4))
    for t in range(7):
        _, rew, done, extras = env.step(torch.zeros(4, 2))  # stay put: never reaches a goal
        assert bool(done.all()) == (t == 6)
    assert extras["time_outs"].all() and (rew == 0).all()
    assert (env.episode_length_buf == 0).all()


def test_resets_are_uniform_over_non_goal_cells():
    env = make_env("gridworld", num_envs=4096, device="cpu", seed=11)
    pos = env.positions.clone()
    assert pos[:, 0].min() == 0 and pos[:, 0].max() == 24
    assert pos[:, 1].min() == 2 and pos[:, 1].max() == 22  # never on a goal row
    counts = torch.bincount(pos[:, 1].long(), minlength=25)[2:23].float()
    assert (counts / counts.mean() - 1).abs().max() < 0.35  # 21 rows, ~195 draws each


def test_masked_reset_touches_only_masked_envs(env):
    env.reset()
    for _ in range(3):
        env.step(torch.ones(NUM_ENVS, 2))
    before_pos = env.positions.clone()
    before_len = env.episode_length_buf.clone()
    mask = torch.zeros(NUM_ENVS, dtype=torch.bool)
    mask[::3] = True
    env.reset_envs(mask)
    assert torch.equal(env.positions[~mask], before_pos[~mask])
    assert torch.equal(env.episode_length_buf[~mask], before_len[~mask])
    assert (env.episode_length_buf[mask] == 0).all()


def test_observations_are_fresh_tensors_and_episode_length_is_assignable(env):
    first = env.step(torch.zeros(NUM_ENVS, 2))[0]["policy"].clone()
    held = env.step(torch.ones(NUM_ENVS, 2))[0]
    snapshot = held["policy"].clone()
    env.step(-torch.ones(NUM_ENVS, 2))
    assert torch.equal(held["policy"], snapshot), "a returned observation must not change on the next step"
    env.episode_length_buf = torch.full((NUM_ENVS,), 5)
    assert (env.episode_length_buf == 5).all() and first.shape == (NUM_ENVS, 2)
    env.episode_length_buf = torch.full((NUM_ENVS,), 199)  # as rsl_rl's random initial lengths: the kernels see it
    _, _, dones, extras = env.step(torch.zeros(NUM_ENVS, 2))  # standing still: the 200-step time-out, no goal
    assert dones.all() and extras["time_outs"].all()


def test_graph_replay_matches_eager_stepping():
    actions = torch.tensor(np.random.default_rng(1).uniform(-1, 1, size=(50, 16, 2)), dtype=torch.float32)
    runs = []
    for capture in (True, False):
        env = make_env("gridworld", num_envs=16, device="cpu", seed=5, graph_capture=capture)
        runs.append(torch.stack([env.step(a)[0]["policy"] for a in actions]))
        assert (env._graph is not None) == capture
    assert torch.equal(runs[0], runs[1])


def test_a_fused_step_cannot_skip_the_base_s_reward_term_or_truncation_kernels():
    class WithTerms(GridWorldEnv):  # GridWorld's one kernel applies the episode rule itself (step_finishes_episode)
        reward_terms = ("goal",)

    with pytest.raises(TypeError, match="step_finishes_episode cannot be combined with reward_terms"):
        WithTerms(GridWorldCfg(), num_envs=2, device="cpu")
