"""The same GridWorld as a plain single-env gymnasium ``Env`` in numpy.

It is the independent reference the Warp kernel is tested against, and the baseline of ``refpo bench
gridworld`` (run inside gymnasium's ``SyncVectorEnv``). Written from the task definition, not from the kernel.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np


class GridWorldGymEnv(gym.Env):
    """25x25 grid, goal rows {0, 1, size-2, size-1} (+20, terminal), 200-step time-out, (pos - c) / c obs."""

    metadata = {"render_modes": []}

    def __init__(self, size: int = 25, goal_reward: float = 20.0, max_episode_length: int = 200) -> None:
        self.size = size
        self.goal_reward = goal_reward
        self.max_episode_length = max_episode_length
        self.center = (size - 1) / 2
        self.observation_space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.pos = np.zeros(2, dtype=np.int64)
        self.steps = 0

    def _obs(self) -> np.ndarray:
        return ((self.pos - self.center) / self.center).astype(np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if options and "start" in options:
            self.pos = np.asarray(options["start"], dtype=np.int64).copy()
        else:
            self.pos = np.array([self.np_random.integers(0, self.size), self.np_random.integers(2, self.size - 2)])
        self.steps = 0
        return self._obs(), {}

    def step(self, action):
        move = np.round(np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)).astype(np.int64)
        self.pos = np.clip(self.pos + move, 0, self.size - 1)
        self.steps += 1
        y = self.pos[1]
        terminated = bool(y <= 1 or y >= self.size - 2)
        truncated = (not terminated) and self.steps >= self.max_episode_length
        reward = self.goal_reward if terminated else 0.0
        return self._obs(), reward, terminated, truncated, {"reached_top": bool(terminated and y >= self.size - 2)}
