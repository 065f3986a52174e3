"""Expose a refpo_warp environment through gymnasium's vector-env API (numpy in, numpy out).

The Warp env resets finished episodes inside the step kernel, so the adapter declares gymnasium's same-step
autoreset mode: the observation returned for a finished env already starts its next episode.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector import AutoresetMode


class GymVectorEnv(gym.vector.VectorEnv):
    """gymnasium ``VectorEnv`` view of a ``WarpVecEnv`` (one observation group, Box spaces in [-inf, inf])."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, env, obs_group: str = "policy", action_bound: float = 1.0) -> None:
        self.env = env
        self.obs_group = obs_group
        self.num_envs = env.num_envs
        obs_dim = env.get_observations()[obs_group].shape[-1]
        self.single_observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(obs_dim,), dtype=np.float32)
        self.single_action_space = gym.spaces.Box(-action_bound, action_bound, shape=(env.num_actions,),
                                                  dtype=np.float32)  # fmt: skip
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, self.num_envs)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            self.env.reseed(int(seed))
        obs = self.env.reset()
        return obs[self.obs_group].cpu().numpy(), {}

    def step(self, actions):
        actions = torch.as_tensor(np.asarray(actions, dtype=np.float32), device=self.env.device)
        obs, rewards, dones, extras = self.env.step(actions)
        truncated = extras["time_outs"]
        terminated = dones & ~truncated
        infos = {name: buf.cpu().numpy() for name, buf in self.env.episode_metric_buffers.items()}
        return (obs[self.obs_group].cpu().numpy(), rewards.cpu().numpy(), terminated.cpu().numpy(),
                truncated.cpu().numpy(), infos)  # fmt: skip
