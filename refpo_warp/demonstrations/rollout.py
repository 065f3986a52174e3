"""Roll a policy out on a vectorised env and keep whole episodes, as a demonstration dataset stores them.

Every env steps at once; each env writes its step into a step-major buffer at its own episode position (one indexed
write per step for all envs). Only when episodes end does Python touch single envs: it copies each finished env's
rows out (observations, actions, rewards, terminations, truncations, and the observation the episode ended in,
before the env's auto-reset). Each env keeps at most ``ceil(episodes / num_envs)`` episodes, so short episodes do not
crowd out long ones; episodes still running when enough are kept are dropped, never written as parts.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable

import torch
from tensordict import TensorDict

from refpo_warp.demonstrations.dataset_file import Episode


def flat_obs(obs: TensorDict | dict, groups: list[str]) -> torch.Tensor:
    """The actor's observation: its groups side by side (the dataset's observation vector)."""
    return torch.cat([obs[g] for g in groups], dim=-1)


@torch.inference_mode()
def collect_episodes(
    policy: Callable[[TensorDict], torch.Tensor],
    env,
    episodes: int,
    groups: list[str],
    noise_std: float = 0.0,
    generator: torch.Generator | None = None,
    progress_every_s: float = 10.0,
) -> list[Episode]:
    """``episodes`` whole episodes of ``policy`` (plus Gaussian action noise of std ``noise_std``, drawn from
    ``generator``) on ``env``; the noisy action is the one stepped and stored."""
    n, horizon = env.num_envs, int(env.max_episode_length)
    quota = math.ceil(episodes / n)
    env.enable_final_observations()
    obs = env.reset()
    first = flat_obs(obs, groups)
    obs_dim, action_dim = first.shape[-1], env.num_actions
    obs_buf = torch.zeros(horizon + 1, n, obs_dim)
    act_buf = torch.zeros(horizon, n, action_dim)
    rew_buf = torch.zeros(horizon, n)
    term_buf = torch.zeros(horizon, n, dtype=torch.bool)
    trunc_buf = torch.zeros(horizon, n, dtype=torch.bool)
    length = torch.zeros(n, dtype=torch.long)
    kept = torch.zeros(n, dtype=torch.long)
    rows = torch.arange(n)
    out: list[Episode] = []
    started, shown = time.monotonic(), time.monotonic()
    while len(out) < episodes:
        actions = policy(obs)
        if noise_std > 0:
            actions = actions + noise_std * torch.randn(actions.shape, generator=generator).to(actions.device)
        obs_buf[length, rows] = flat_obs(obs, groups).cpu()
        act_buf[length, rows] = actions.float().cpu()
        obs, rewards, dones, extras = env.step(actions)
        truncated = extras["time_outs"].cpu()
        dones = dones.cpu()
        rew_buf[length, rows] = rewards.float().cpu()
        term_buf[length, rows] = dones & ~truncated
        trunc_buf[length, rows] = truncated
        length += 1
        if bool(dones.any()):
            final = flat_obs(env.final_observations, groups).cpu()
            for i in dones.nonzero().flatten().tolist():  # the finished envs only
                steps = int(length[i])
                if kept[i] < quota and len(out) < episodes:
                    obs_buf[steps, i] = final[i]
                    out.append(
                        Episode(
                            obs_buf[: steps + 1, i].numpy().copy(),
                            act_buf[:steps, i].numpy().copy(),
                            rew_buf[:steps, i].numpy().copy(),
                            term_buf[:steps, i].numpy().copy(),
                            trunc_buf[:steps, i].numpy().copy(),
                        )
                    )
                    kept[i] += 1
            length[dones] = 0
        if time.monotonic() - shown >= progress_every_s:
            shown = time.monotonic()
            print(f"[collect] {len(out)}/{episodes} episodes ({shown - started:.0f} s)", file=sys.stdout, flush=True)
    return out
