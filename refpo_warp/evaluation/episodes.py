"""Policy evaluation on a vectorised env: every env plays a fixed number of episodes; per-episode results come back.

Returns, lengths and the env's ``episode_metrics`` (success, MPJPE, ...) are recorded at each env's episode ends;
episodes beyond ``episodes_per_env`` are ignored, so every env contributes the same number of episodes.
"""

from __future__ import annotations

from collections.abc import Callable

import torch
from tensordict import TensorDict


@torch.inference_mode()
def run_episodes(
    policy: Callable[[TensorDict], torch.Tensor],
    env,
    episodes_per_env: int = 1,
    max_steps: int | None = None,
    reset: bool = True,
    record_obs: int = 0,
) -> dict[str, torch.Tensor]:
    """Roll ``policy`` in ``env`` until every env finished ``episodes_per_env`` episodes (or ``max_steps`` passed).

    Args:
        policy: Maps the observation TensorDict to actions (e.g. a FlowActor with a fixed number of flow steps).
        env: A ``WarpVecEnv``.
        episodes_per_env: Episodes recorded per env.
        max_steps: Step cap (default: ``episodes_per_env * env.max_episode_length``); unfinished episodes are
            dropped from the result and counted in ``"unfinished"``.
        reset: Reset all envs first so every recorded episode starts from a fresh initial state.
        record_obs: Keep about this many of the observations the policy acted on, evenly spread over the steps
            (returned as ``"observations"``, a TensorDict), for on-policy diagnostics.

    Returns:
        Flat tensors over recorded episodes: ``return``, ``length`` (in env steps; whole chunks through an
        action-chunk wrapper) and one entry per env episode metric, plus the scalar count ``unfinished``.
    """
    n = env.num_envs
    obs = env.reset() if reset else env.get_observations()
    max_steps = max_steps or episodes_per_env * int(env.max_episode_length)
    running_return = torch.zeros(n, device=env.device)
    running_length = torch.zeros(n, device=env.device)
    env_steps_per_step = getattr(env, "env_steps_per_step", 1)  # an ActionChunkWrapper step is H env steps
    finished = torch.zeros(n, dtype=torch.long, device=env.device)
    records: dict[str, list[torch.Tensor]] = {"return": [], "length": []}
    metric_names = list(env.episode_metric_buffers)
    for name in metric_names:
        records[name] = []
    every = max(1, (max_steps * n) // record_obs) if record_obs else 0  # steps between recorded observations
    visited = []

    for step in range(max_steps):
        if every and step % every == 0:
            visited.append(obs.clone())
        actions = policy(obs)
        obs, rewards, dones, _ = env.step(actions)
        running_return += rewards
        running_length += env_steps_per_step
        keep = dones & (finished < episodes_per_env)
        if keep.any():  # boolean indexing copies, so the records survive the in-place resets below
            records["return"].append(running_return[keep])
            records["length"].append(running_length[keep])
            for name in metric_names:
                records[name].append(env.episode_metric_buffers[name][keep])
        finished += dones.long()
        running_return[dones] = 0.0
        running_length[dones] = 0.0
        if bool((finished >= episodes_per_env).all()):
            break

    out = {k: torch.cat(v) if v else torch.zeros(0, device=env.device) for k, v in records.items()}
    out["unfinished"] = torch.tensor(int((episodes_per_env - finished.clamp(max=episodes_per_env)).sum()))
    if visited:
        out["observations"] = torch.cat(visited)[:record_obs]
    return out


def summarize(episodes: dict[str, torch.Tensor]) -> dict[str, float]:
    """Means (and the return's std) of a ``run_episodes`` result, as plain floats for JSON."""
    out: dict[str, float] = {"episodes": int(episodes["return"].numel())}
    for key, values in episodes.items():
        if key == "observations":
            continue
        if key == "unfinished":
            out[key] = int(values)
        elif values.numel():
            out[f"{key}_mean"] = float(values.float().mean())
    if episodes["return"].numel() > 1:
        out["return_std"] = float(episodes["return"].float().std())
    return out
