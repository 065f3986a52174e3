"""gymnasium vector adapter on real Warp envs: gymnasium's default autoreset mode (NEXT_STEP) and the env's own
(SAME_STEP) against hand-worked GridWorld steps, final observations against an env that did not reset (DMC
cartpole), fresh arrays, `_key` masks, and gymnasium's own wrappers (RecordEpisodeStatistics, NormalizeObservation,
DtypeObservation, DictInfoToList)."""

from itertools import combinations

import numpy as np
import pytest
import torch
from gymnasium.utils.passive_env_checker import data_shares_objects
from gymnasium.vector import AutoresetMode
from gymnasium.wrappers.vector import DictInfoToList, DtypeObservation, NormalizeObservation, RecordEpisodeStatistics

from refpo_warp import make_env
from refpo_warp.envs.gym_adapter import GymVectorEnv
from refpo_warp.utils.paths import REPO_ROOT

SAME, NEXT = AutoresetMode.SAME_STEP, AutoresetMode.NEXT_STEP
C = 12.0  # GridWorld 25x25: obs = (cell - 12) / 12
DOWN = np.tile(np.array([0.0, -1.0], dtype=np.float32), (8, 1))
STAY = np.zeros((8, 2), dtype=np.float32)


def grid(mode, **cfg):
    warp_env = make_env("gridworld", num_envs=8, device="cpu", seed=4, **cfg)
    return warp_env, GymVectorEnv(warp_env, autoreset_mode=mode)


def cells(obs):
    return np.rint(np.asarray(obs) * C + C).astype(int)


def start_four_above_the_bottom_goal(warp_env, vec):
    """Envs 0-3 at row 2 (one step above the bottom goal rows), envs 4-7 at row 12."""
    vec.reset(seed=9)
    warp_env.reset_to(torch.tensor([[i, 2] for i in range(4)] + [[i, 12] for i in range(4)]))


def test_same_step_returns_the_next_start_and_the_final_observation_in_infos():
    warp_env, vec = grid(SAME)
    start_four_above_the_bottom_goal(warp_env, vec)
    obs, rew, term, trunc, infos = vec.step(DOWN)
    done = np.array([True] * 4 + [False] * 4)
    assert obs.dtype == np.float32 and vec.observation_space.contains(obs)
    assert rew.dtype == np.float64 and term.dtype == np.bool_ and trunc.dtype == np.bool_
    np.testing.assert_array_equal(term, done)
    assert not trunc.any() and list(rew) == [20.0] * 4 + [0.0] * 4
    # finished envs already start their next episode (off the goal rows); the others moved down one row
    assert ((cells(obs[:4, 1]) >= 2) & (cells(obs[:4, 1]) <= 22)).all()
    np.testing.assert_array_equal(cells(obs[4:]), [[i, 11] for i in range(4)])
    np.testing.assert_array_equal(infos["_final_obs"], done)
    np.testing.assert_array_equal(infos["_final_info"], done)
    assert infos["final_obs"].dtype == object and all(infos["final_obs"][i] is None for i in range(4, 8))
    np.testing.assert_array_equal(cells(np.stack(infos["final_obs"][:4])), [[i, 1] for i in range(4)])
    final_info = infos["final_info"]
    np.testing.assert_array_equal(final_info["_success"], done)
    assert list(final_info["success"][:4]) == [1.0] * 4 and list(final_info["reached_top"][:4]) == [0.0] * 4
    # gymnasium's own reading of the masks: per-env dicts hold the keys of the envs they are valid for
    per_env = DictInfoToList(vec).step(STAY)[4]
    assert per_env == [{}] * 8


def test_next_step_returns_the_final_observation_then_resets_on_the_next_step():
    warp_env, vec = grid(NEXT)
    start_four_above_the_bottom_goal(warp_env, vec)
    obs, rew, term, trunc, infos = vec.step(DOWN)
    np.testing.assert_array_equal(cells(obs), [[i, 1] for i in range(4)] + [[i, 11] for i in range(4)])
    assert list(term) == [True] * 4 + [False] * 4 and list(rew) == [20.0] * 4 + [0.0] * 4
    assert "final_obs" not in infos and list(infos["_success"]) == [True] * 4 + [False] * 4
    assert list(infos["success"][:4]) == [1.0] * 4

    obs, rew, term, trunc, infos = vec.step(DOWN)  # envs 0-3 reset (their action is ignored)
    starts = cells(obs[:4])
    assert ((starts[:, 1] >= 2) & (starts[:, 1] <= 22)).all()
    np.testing.assert_array_equal(starts, warp_env.positions[:4].numpy())  # the env holds exactly that start
    assert not (term | trunc).any() and (rew == 0).all() and infos == {}
    np.testing.assert_array_equal(cells(obs[4:]), [[i, 10] for i in range(4)])

    obs, *_ = vec.step(DOWN)  # the first action of the new episodes moves them down from their start
    np.testing.assert_array_equal(cells(obs[:4]), starts - [0, 1])


def test_final_observation_equals_the_state_an_unreset_env_reaches():
    """DMC cartpole: an env that times out after 3 steps reports, as final observation, exactly the observation
    that an identically seeded env with long episodes returns at step 3 (same physics, same actions)."""
    short = make_env("dmc_cartpole_balance", num_envs=4, device="cpu", seed=3, max_episode_length=3)
    long = make_env("dmc_cartpole_balance", num_envs=4, device="cpu", seed=3)
    vec = GymVectorEnv(short, autoreset_mode=SAME)
    actions = np.random.default_rng(0).uniform(-1, 1, size=(6, 4, 1)).astype(np.float32)
    for t in range(6):
        obs, rew, term, trunc, infos = vec.step(actions[t])
        ref_obs, ref_rew, _, _ = long.step(torch.from_numpy(actions[t]))
        if t < 3:
            np.testing.assert_allclose(rew, ref_rew.numpy(), rtol=1e-6)
        if t == 2:
            assert trunc.all() and not term.any()
            np.testing.assert_array_equal(np.stack(infos["final_obs"]), ref_obs["policy"].numpy())
            assert not np.allclose(obs, ref_obs["policy"].numpy())  # the returned obs starts a new episode
        elif t == 5:  # the second episode times out too
            assert trunc.all() and "final_obs" in infos
        else:
            assert "final_obs" not in infos and not (term | trunc).any()


@pytest.mark.parametrize("mode", [SAME, NEXT])
def test_every_call_returns_new_arrays(mode):
    warp_env, vec = grid(mode, max_episode_length=2)
    calls = [vec.reset(seed=1)]
    for _ in range(4):
        obs, _rew, _term, _trunc, infos = vec.step(DOWN)
        calls.append((obs, infos))
    for a, b in combinations(calls, 2):
        assert not data_shares_objects(a, b)
    kept = calls[1][0].copy()
    vec.step(DOWN)
    vec.step(DOWN)
    np.testing.assert_array_equal(calls[1][0], kept)  # later steps do not overwrite what a caller holds
    for buffer in [*warp_env._obs.values(), *warp_env._final_obs.values(), *warp_env._metrics.values()]:
        assert not np.shares_memory(calls[-1][0], buffer.numpy())


@pytest.mark.parametrize("mode, lengths_at", [(SAME, (6, 12, 18)), (NEXT, (6, 13, 20))])
def test_record_episode_statistics_counts_episodes_in_both_modes(mode, lengths_at):
    """Standing still times out every 6 steps; with NEXT_STEP the reset step in between is not an episode step."""
    _, vec = grid(mode, max_episode_length=6)
    env = RecordEpisodeStatistics(vec)
    env.reset(seed=2)
    for step in range(1, 21):
        _, _, term, trunc, infos = env.step(STAY)
        assert ("episode" in infos) == (step in lengths_at)
        if step in lengths_at:
            assert trunc.all() and not term.any()
            assert list(infos["episode"]["l"]) == [6] * 8 and list(infos["episode"]["r"]) == [0.0] * 8


def test_record_episode_statistics_return_of_a_goal_episode():
    warp_env, vec = grid(SAME)
    env = RecordEpisodeStatistics(vec)
    start_four_above_the_bottom_goal(warp_env, vec)
    env.step(STAY)
    *_, infos = env.step(DOWN)
    np.testing.assert_array_equal(infos["_episode"], [True] * 4 + [False] * 4)
    assert list(infos["episode"]["r"][:4]) == [20.0] * 4 and list(infos["episode"]["l"][:4]) == [2] * 4


def test_observation_wrappers_need_next_step_autoreset():
    # gymnasium 1.x observation wrappers refuse SAME_STEP (their transform would miss infos["final_obs"]) ...
    for wrapper in (NormalizeObservation, lambda e: DtypeObservation(e, np.float64)):
        with pytest.raises(ValueError, match="NEXT_STEP"):
            wrapper(grid(SAME)[1])
    # ... and work on NEXT_STEP, the default, where every observation, final ones included, is a returned observation.
    warp_env = make_env("gridworld", num_envs=8, device="cpu", seed=4, max_episode_length=3)
    env = DtypeObservation(NormalizeObservation(GymVectorEnv(warp_env)), np.float64)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(10):
        obs, *_ = env.step(rng.uniform(-1, 1, size=(8, 2)).astype(np.float32))
    assert obs.dtype == np.float64 and np.isfinite(obs).all()
    assert env.env.obs_rms.count == pytest.approx(8 * 11, abs=1)  # reset + 10 steps of 8 envs (+ its 1e-4 prior)


def test_the_default_autoreset_mode_is_gymnasiums():
    """gymnasium's own vector envs default to NEXT_STEP; so does the adapter (SAME_STEP stays an option)."""
    import gymnasium as gym

    reference = gym.vector.SyncVectorEnv([lambda: gym.make("CartPole-v1")])
    vec = GymVectorEnv(make_env("gridworld", num_envs=2, device="cpu"))
    assert vec.autoreset_mode == reference.metadata["autoreset_mode"] == NEXT
    assert vec.metadata["autoreset_mode"] == NEXT


def test_action_space_follows_the_env_action_transform():
    assert GymVectorEnv(make_env("gridworld", num_envs=2, device="cpu")).single_action_space.high.tolist() == [1, 1]
    squashing = make_env("gridworld", num_envs=2, device="cpu", action_transform="tanh")
    assert np.isinf(GymVectorEnv(squashing).single_action_space.high).all()


def test_bad_arguments_are_named():
    warp_env = make_env("gridworld", num_envs=2, device="cpu", seed=0)
    with pytest.raises(ValueError, match="obs_group 'critic'"):
        GymVectorEnv(warp_env, obs_group="critic")
    with pytest.raises(ValueError, match="autoreset_mode"):
        GymVectorEnv(warp_env, autoreset_mode=AutoresetMode.DISABLED)
    with pytest.raises(ValueError, match=r"shape \(2, 2\)"):
        GymVectorEnv(warp_env).step(np.zeros((3, 2), dtype=np.float32))


def test_gymnasium_example_improves_the_return():
    """examples/gymnasium_ppo.py (PPO on the gymnasium API only) learns GridWorld within a few seconds."""
    import importlib.util

    path = REPO_ROOT / "examples" / "gymnasium_ppo.py"
    spec = importlib.util.spec_from_file_location("gymnasium_ppo", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    history = example.train(iterations=12, quiet=True)
    # 30-step episodes: a random policy reaches a goal row in about a third of them (return 20 each)
    assert history[0] < 12 and np.mean(history[-3:]) > history[0] + 6, history
