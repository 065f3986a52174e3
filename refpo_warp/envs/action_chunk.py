"""Action chunks: one policy action = H env actions executed open-loop (ReinFlow's ``horizon_steps``).

``ActionChunkWrapper(env, H)`` is an rsl_rl ``VecEnv`` with ``num_actions = H * env.num_actions``: ``step`` splits
the action into H env actions (row-major: the first ``env.num_actions`` entries are the first env step) and steps the
wrapped env H times. The reward is the sum of the sub-step rewards up to the end of the env's episode, ``done`` is
set if any sub-step ended the episode, and ``time_outs`` says whether that end was a time-out (as ReinFlow's
``MultiStep`` wrapper, which stops at the first done).

Auto-reset inside a chunk: the wrapped env resets a finished env inside its step, so the chunk's remaining
sub-steps run in the new episode. Those sub-steps are discarded (their rewards are not counted, their episode ends
are not reported) and the env is reset once more after the chunk, so the next chunk starts a fresh episode from a
reset state, as ReinFlow's ``MultiStep(reset_within_step=True)`` does. Episode metrics are the values at the
sub-step that ended the episode.

Episode lengths seen through the wrapper count chunks: ``max_episode_length`` is ceil(L / H), and setting
``episode_length_buf`` (rsl_rl's random initial lengths) sets the env's to H times the value, so time-outs fall on
chunk boundaries. ``env_steps_per_step`` (= H) converts policy steps to env steps.
"""

from __future__ import annotations

import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict


class ActionChunkWrapper(VecEnv):
    """Run H env steps per policy step (see the module docstring)."""

    def __init__(self, env, chunk: int) -> None:
        if int(chunk) < 1:
            raise ValueError(f"env.action_chunk must be >= 1, got {chunk}")
        self.env = env
        self.chunk = int(chunk)
        self.env_steps_per_step = self.chunk
        self.num_envs = env.num_envs
        self.num_actions = env.num_actions * self.chunk
        self.max_episode_length = -(-int(env.max_episode_length) // self.chunk)
        self.device = env.device
        self.cfg = env.cfg
        n = self.num_envs
        self._metrics = {name: torch.zeros_like(buf) for name, buf in env.episode_metric_buffers.items()}
        self._rewards = torch.zeros(n, device=self.device)
        self._done = torch.zeros(n, dtype=torch.bool, device=self.device)
        self._time_out = torch.zeros(n, dtype=torch.bool, device=self.device)
        # rsl_rl keeps the observation of step t while step t+1 runs, and H sub-steps cycle the wrapped env's own
        # two output buffers: hand out alternating copies of our own.
        obs = env.get_observations()
        self._obs_out = [obs.clone() for _ in range(2)]
        self._obs_parity = 0

    # ------------------------------------------------------------------------------------------ rsl_rl VecEnv API
    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        sub_actions = actions.reshape(self.num_envs, self.chunk, -1)
        self._rewards.zero_()
        self._done.zero_()
        self._time_out.zero_()
        for h in range(self.chunk):
            _, rewards, dones, extras = self.env.step(sub_actions[:, h])
            live = ~self._done
            self._rewards += torch.where(live, rewards, 0.0)
            ended = dones & live
            self._time_out |= ended & extras["time_outs"].to(self.device, torch.bool)
            for name, buf in self.env.episode_metric_buffers.items():
                self._metrics[name] = torch.where(ended, buf, self._metrics[name])
            self._done |= ended
        if self.chunk > 1:
            # Episodes that ended before the last sub-step ran their leftover sub-steps in a new episode: restart it.
            early = self._done & ~dones
            if bool(early.any()):
                self.env.reset_envs(early)
        extras = {"time_outs": self._time_out.clone()}
        if self._metrics and bool(self._done.any()):
            extras["log"] = {f"Episode/{name}": buf[self._done] for name, buf in self._metrics.items()}
        return self._publish(self.env.get_observations()), self._rewards.clone(), self._done.clone(), extras

    def get_observations(self) -> TensorDict:
        return self._publish(self.env.get_observations())

    def reset(self) -> TensorDict:
        return self._publish(self.env.reset())

    def reset_envs(self, mask: torch.Tensor) -> None:
        self.env.reset_envs(mask)

    @property
    def episode_length_buf(self) -> torch.Tensor:
        return torch.div(self.env.episode_length_buf, self.chunk, rounding_mode="floor")

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        self.env.episode_length_buf = value * self.chunk

    @property
    def episode_metric_buffers(self) -> dict[str, torch.Tensor]:
        """Per-env episode metrics at the sub-step that ended the episode, for envs done at the last step."""
        return self._metrics

    @property
    def step_dt(self) -> float:
        return self.env.step_dt * self.chunk

    @property
    def unwrapped(self):
        return self.env.unwrapped

    def __getattr__(self, name: str):  # everything else (task-specific helpers) is the wrapped env's
        if name == "env":
            raise AttributeError(name)
        return getattr(self.env, name)

    # ------------------------------------------------------------------------------------------ internals
    def _publish(self, obs: TensorDict) -> TensorDict:
        out = self._obs_out[self._obs_parity]
        self._obs_parity ^= 1
        out.update_(obs)
        return out
