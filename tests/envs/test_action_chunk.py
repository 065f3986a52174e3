"""env.action_chunk (ReinFlow's horizon): one policy action runs H env steps open-loop; rewards add up to the episode's
end, an episode that ends inside a chunk restarts from a reset state, lengths and metrics are per episode."""

import pytest
import torch

from refpo_warp.envs.action_chunk import ActionChunkWrapper
from refpo_warp.envs.registry import make_env
from refpo_warp.evaluation.episodes import run_episodes


def test_a_chunk_is_h_env_steps_of_the_wrapped_env():
    chunked = make_env("dmc_cartpole_swingup", num_envs=4, device="cpu", seed=3, action_chunk=3)
    plain = make_env("dmc_cartpole_swingup", num_envs=4, device="cpu", seed=3)
    assert isinstance(chunked, ActionChunkWrapper) and chunked.num_actions == 3 * plain.num_actions
    assert chunked.max_episode_length == 334 and chunked.step_dt == pytest.approx(3 * plain.step_dt)
    actions = torch.linspace(-1, 1, 4 * 6).reshape(4, 2, 3)  # (envs, chunks, sub-steps), one actuator
    for c in range(2):
        obs, rewards, dones, _ = chunked.step(actions[:, c])
        expected = torch.zeros(4)
        for h in range(3):
            plain_obs, r, _, _ = plain.step(actions[:, c, h : h + 1])
            expected += r
        torch.testing.assert_close(rewards, expected)
        torch.testing.assert_close(obs["policy"], plain_obs["policy"])
        assert not dones.any()


def goal_world(chunk: int, **cfg):
    env = make_env("gridworld", num_envs=2, device="cpu", seed=1, action_chunk=chunk, **cfg)
    env.reset_to(torch.tensor([[5, 3], [5, 12]]))  # env 0 two moves down from the bottom goal rows, env 1 in the middle
    return env


def test_an_episode_ending_inside_a_chunk_counts_its_rewards_once_and_restarts_fresh():
    env = goal_world(3)
    down = torch.tensor([0.0, -1.0]).repeat(2, 3)  # three moves down
    obs, rewards, dones, extras = env.step(down)
    # env 0: y 3 -> 2 -> 1 (goal, +20, done at sub-step 1); the third move ran in a new episode and is discarded
    assert rewards.tolist() == [20.0, 0.0] and dones.tolist() == [True, False]
    assert extras["time_outs"].tolist() == [False, False]
    assert extras["log"]["Episode/success"].tolist() == [1.0] and env.episode_metric_buffers["success"][0] == 1.0
    assert env.unwrapped.episode_length_buf.tolist() == [0, 3]  # env 0 starts a fresh episode, env 1 moved 3 times
    assert env.positions[1].tolist() == [5, 9]
    start = env.positions[0].clone()
    assert 2 <= start[1] <= 22 and torch.equal(obs["policy"][0], (start.float() - 12) / 12)


def test_time_outs_fall_on_chunk_boundaries_and_lengths_count_env_steps():
    env = goal_world(3, max_episode_length=7)
    assert env.max_episode_length == 3
    env.episode_length_buf = torch.tensor([1, 2])  # rsl_rl's random initial lengths, in chunks
    assert env.unwrapped.episode_length_buf.tolist() == [3, 6]
    still = torch.zeros(2, 6)
    _, _, dones, extras = env.step(still)  # env 1 times out at its 7th env step, the chunk's first sub-step
    assert dones.tolist() == [False, True] and extras["time_outs"].tolist() == [False, True]
    assert env.unwrapped.episode_length_buf.tolist() == [6, 0]
    episodes = run_episodes(lambda obs: still, goal_world(3, max_episode_length=7))
    assert episodes["length"].tolist() == [9.0, 9.0]  # 3 chunks of 3 env steps (the 7-step episode, rounded up)


def test_training_counts_env_steps_of_a_chunked_env(tmp_path):
    """Each policy step of an action-chunk env is ``action_chunk`` env steps: in the iteration budget, in
    ``progress.jsonl`` and in the checkpoint's count (8 envs x 4 policy steps x chunk 3 = 96 env steps/iteration)."""
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.runner.build import num_iterations
    from refpo_warp.runner.checkpoints import checkpoint_progress, read_checkpoint
    from refpo_warp.runner.progress import read_rows
    from refpo_warp.training import train

    args = [
        "task=gridworld",
        "algo=reinflow",
        "num_envs=8",
        "runner.num_steps_per_env=4",
        "env.action_chunk=3",
        "device=cpu",
        "eval.at_end=false",
        "eval.interval=0",
        "runner.save_interval=100",
    ]
    assert num_iterations(resolve_config(args + ["total_env_steps=200"])) == 3  # ceil(200 / 96)
    train(args + ["max_iterations=2", f"run_dir={tmp_path}"])
    assert [r["env_steps"] for r in read_rows(tmp_path)] == [96, 192]
    assert checkpoint_progress(read_checkpoint(tmp_path / "model_1.pt"))[0] == 192
