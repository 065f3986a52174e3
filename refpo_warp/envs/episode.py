"""The episode rules every environment shares, as Warp kernels over the env index (``WarpVecEnv`` launches them).

After a task's step kernels wrote this step's rewards, terminations (and any truncation of its own, e.g. the end of
a motion clip), ``finish_step`` (and, for a task with named reward terms, ``finish_reward_terms``) decides, for
every env:

- the episode length grows by one (the state just reached is step ``length`` of the episode);
- a time-out is ``length >= max_episode_length``; it and the task's truncation are reported as ``truncated`` (rsl_rl
  bootstraps the value of a truncated episode from ``extras["time_outs"]``), but only when the task did not
  terminate the episode at the same step: a termination takes precedence;
- ``done`` = terminated or truncated: the reset mask the task's reset then runs on;
- the per-episode sums of the task's named reward terms (``finish_reward_terms``), kept for the episode that ended
  (logged as ``Episode_Reward/<term>``); the return itself is summed by rsl_rl's logger and by the evaluation;
- the counters of finished envs restart from zero.
"""

from __future__ import annotations

from refpo_warp.utils.warp_setup import wp


@wp.func
def finish_env_step(
    i: int,
    max_episode_length: int,
    task_truncation: int,
    terminated: wp.array(dtype=wp.bool),
    truncated: wp.array(dtype=wp.bool),
    episode_length: wp.array(dtype=wp.int32),
    done: wp.array(dtype=wp.bool),
) -> bool:
    """The rules above for env ``i``; returns ``done[i]``. Callable from a task's own step kernel (a task that sets
    ``WarpVecEnv.step_finishes_episode`` fuses its whole step into one launch)."""
    length = episode_length[i] + 1
    term = terminated[i]
    # task_truncation: whether the task writes truncated[i] itself (otherwise it holds the last step's verdict)
    trunc = (not term) and (length >= max_episode_length or (task_truncation != 0 and truncated[i]))
    ended = term or trunc
    truncated[i] = trunc
    done[i] = ended
    episode_length[i] = wp.where(ended, 0, length)
    return ended


@wp.kernel
def finish_step(
    max_episode_length: int,
    task_truncation: int,
    terminated: wp.array(dtype=wp.bool),
    truncated: wp.array(dtype=wp.bool),
    episode_length: wp.array(dtype=wp.int32),
    done: wp.array(dtype=wp.bool),
):
    finish_env_step(wp.tid(), max_episode_length, task_truncation, terminated, truncated, episode_length, done)


@wp.kernel
def finish_reward_terms(
    reward_terms: wp.array2d(dtype=float),
    done: wp.array(dtype=wp.bool),
    term_sums: wp.array2d(dtype=float),
    ended_term_sums: wp.array2d(dtype=float),
):
    """Per (env, reward term), after ``finish_step``: the term's sum over the episode, kept for the episode that
    ended (``ended_term_sums``) and restarted from zero; launched only for envs that declare reward terms."""
    i, k = wp.tid()
    total = term_sums[i, k] + reward_terms[i, k]
    if done[i]:
        ended_term_sums[i, k] = total
        term_sums[i, k] = 0.0
    else:
        term_sums[i, k] = total


@wp.kernel
def restart_episodes(
    mask: wp.array(dtype=wp.bool),
    num_terms: int,
    episode_length: wp.array(dtype=wp.int32),
    term_sums: wp.array2d(dtype=float),
    terminated: wp.array(dtype=wp.bool),
    truncated: wp.array(dtype=wp.bool),
    done: wp.array(dtype=wp.bool),
):
    """Counters and end flags of the envs in ``mask`` as at the start of an episode (an explicit reset)."""
    i = wp.tid()
    if mask[i]:
        episode_length[i] = 0
        for k in range(num_terms):
            term_sums[i, k] = 0.0
        terminated[i] = False
        truncated[i] = False
        done[i] = False
