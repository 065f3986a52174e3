"""env.reset_group_size (Flow-GRPO's groups): the members of a group start every episode from the same initial state,
different groups (and successive episodes) from different ones, in every task family."""

import pytest
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.utils.warp_setup import wp

GROUP, GROUPS = 2, 4


def initial_state(env, family: str) -> torch.Tensor:
    """What a reset draws at random, per env."""
    if family == "gridworld":
        return env.positions.float().clone()
    if family == "dmc":
        return torch.cat([env.joint_q, env.joint_qd], dim=-1).clone()
    return torch.stack([wp.to_torch(env.clip_id).float(), wp.to_torch(env.start_time)], dim=-1).clone()


def assert_grouped(states: torch.Tensor) -> None:
    grouped = states.reshape(GROUPS, GROUP, -1)
    assert torch.equal(grouped, grouped[:, :1].expand_as(grouped)), "members of a group differ"
    first = grouped[:, 0]
    for i in range(GROUPS):
        for j in range(i):
            assert not torch.equal(first[i], first[j]), f"groups {i} and {j} start from the same state"


@pytest.mark.parametrize(
    "task, family, length",
    [("gridworld", "gridworld", 6), ("dmc_cartpole_swingup", "dmc", 6), ("humanoid_root", "humanoid", 4)],
)
def test_group_members_share_initial_states_at_resets_and_auto_resets(task, family, length):
    env = make_env(
        task, num_envs=GROUP * GROUPS, device="cpu", seed=5, reset_group_size=GROUP, max_episode_length=length
    )
    env.reset()
    first = initial_state(env, family)
    assert_grouped(first)
    zeros = torch.zeros(env.num_envs, env.num_actions)
    for _step in range(length):  # identical states and actions: every member's episode ends at the same step
        _, _, dones, _ = env.step(zeros)
    assert dones.all()
    second = initial_state(env, family)  # the auto-reset inside the last step drew the second episodes
    assert_grouped(second)
    assert not torch.equal(first, second)


def test_the_kth_episode_of_every_member_starts_from_the_same_state():
    env = make_env("gridworld", num_envs=GROUP * GROUPS, device="cpu", seed=5, reset_group_size=GROUP)
    env.reset()
    first = initial_state(env, "gridworld")
    solo = torch.zeros(env.num_envs, dtype=torch.bool)
    solo[0] = True
    env.reset_envs(solo)  # env 0 alone starts its second episode
    second_of_env0 = initial_state(env, "gridworld")[0]
    assert not torch.equal(second_of_env0, first[0])
    env.reset()  # env 1 (same group) starts its second episode, env 0 its third
    assert torch.equal(initial_state(env, "gridworld")[1], second_of_env0)


def test_without_groups_every_env_draws_its_own_state_and_bad_sizes_are_refused():
    env = make_env("dmc_cartpole_swingup", num_envs=GROUP * GROUPS, device="cpu", seed=5)
    states = initial_state(env, "dmc")
    assert len({tuple(s.tolist()) for s in states}) == env.num_envs
    with pytest.raises(ValueError, match="reset_group_size"):
        make_env("gridworld", num_envs=6, device="cpu", reset_group_size=4)
