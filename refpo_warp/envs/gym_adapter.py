"""A refpo_warp environment behind gymnasium 1.x's vector-env API (numpy in, numpy out).

The autoreset mode is gymnasium's default, ``NEXT_STEP`` (that of its own vector envs), so gymnasium's observation
wrappers (``NormalizeObservation``, ``DtypeObservation``, every ``VectorObservationWrapper``), which accept only
``NEXT_STEP`` or ``DISABLED``, wrap the adapter as they are. A step that ends an episode returns its last
observation, and the next step resets that env (its action is ignored; reward 0, not terminated or truncated) and
returns the new episode's first observation. The Warp env resets finished envs inside its step, and has by then
stepped the start it had already drawn, so it is reset once more: each finished episode costs one wasted env step.

``autoreset_mode=AutoresetMode.SAME_STEP`` is the Warp env's own behaviour, without the wasted step: a step that
ends an episode returns the next episode's first observation, with the last observation of the finished one in
``infos["final_obs"]`` and that step's info (the episode metrics) in ``infos["final_info"]``.
``RecordEpisodeStatistics`` and the reward wrappers take either mode.

Every call returns new arrays (never views of the env's buffers, which later steps overwrite), and every info key
comes with gymnasium's ``_key`` mask of the envs it is valid for.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector import AutoresetMode

AUTORESET_MODES = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)  # the first is the default


def _numpy(tensor: torch.Tensor) -> np.ndarray:
    """A numpy copy that shares no memory with ``tensor``."""
    return tensor.detach().to("cpu", copy=True).numpy()


class GymVectorEnv(gym.vector.VectorEnv):
    """gymnasium ``VectorEnv`` view of a ``WarpVecEnv``: one observation group, Box spaces.

    Args:
        env: The Warp env (its class must record final observations, ``supports_final_observations``).
        obs_group: The observation group returned as the observation.
        autoreset_mode: ``AutoresetMode.NEXT_STEP`` (gymnasium's default) or ``AutoresetMode.SAME_STEP`` (the env's
            own behaviour, one env step less per episode; gymnasium's observation wrappers refuse it).
        action_bound: Bound of the action Box; None: 1 where the env clips actions to [-1, 1], unbounded where it
            squashes them with tanh (``env.action_transform``).
    """

    def __init__(
        self,
        env,
        obs_group: str = "policy",
        autoreset_mode: AutoresetMode = AutoresetMode.NEXT_STEP,
        action_bound: float | None = None,
    ) -> None:
        if autoreset_mode not in AUTORESET_MODES:
            raise ValueError(f"autoreset_mode must be one of {[m.name for m in AUTORESET_MODES]}, got {autoreset_mode}")
        groups = list(env.get_observations().keys())
        if obs_group not in groups:
            raise ValueError(f"obs_group '{obs_group}' is not an observation group of this env; choose from {groups}")
        env.enable_final_observations()
        self.env = env
        self.obs_group = obs_group
        self.metadata = {"autoreset_mode": autoreset_mode}
        self.render_mode = None
        self.num_envs = env.num_envs
        obs_dim = env.get_observations()[obs_group].shape[-1]
        if action_bound is None:
            action_bound = np.inf if getattr(env.cfg, "action_transform", "clip") == "tanh" else 1.0
        self.single_observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(obs_dim,), dtype=np.float32)
        self.single_action_space = gym.spaces.Box(
            -action_bound, action_bound, shape=(env.num_actions,), dtype=np.float32
        )
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, self.num_envs)
        self._reset_pending = np.zeros(self.num_envs, dtype=bool)  # NEXT_STEP: envs to reset at the next step

    @property
    def autoreset_mode(self) -> AutoresetMode:
        return self.metadata["autoreset_mode"]

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset every env; ``seed`` restarts the env's random streams (and the adapter's ``np_random``)."""
        super().reset(seed=seed)
        if seed is not None:
            self.env.reseed(int(seed))
        obs = self.env.reset()
        self._reset_pending[:] = False
        return _numpy(obs[self.obs_group]), {}

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        actions = np.asarray(actions, dtype=np.float32)
        if actions.shape != self.action_space.shape:
            raise ValueError(f"actions must have shape {self.action_space.shape}, got {actions.shape}")
        obs, rewards, dones, extras = self.env.step(torch.from_numpy(actions).to(self.env.device))
        truncated = _numpy(extras["time_outs"]).astype(bool)
        terminated = _numpy(dones).astype(bool) & ~truncated
        done = terminated | truncated
        observations = _numpy(obs[self.obs_group])
        final_obs = _numpy(self.env.final_observations[self.obs_group]) if done.any() else None
        metrics = {name: _numpy(buf) for name, buf in self.env.episode_metric_buffers.items()}
        rewards = _numpy(rewards).astype(np.float64)
        infos: dict = {}

        if self.autoreset_mode == AutoresetMode.SAME_STEP:
            if done.any():
                assert final_obs is not None  # read above when any env is done
                infos["final_obs"] = np.full(self.num_envs, None, dtype=object)
                for i in np.flatnonzero(done):
                    infos["final_obs"][i] = final_obs[i]
                infos["_final_obs"] = done.copy()
                infos["final_info"] = _masked(metrics, done)
                infos["_final_info"] = done.copy()
            return observations, rewards, terminated, truncated, infos

        # NEXT_STEP: envs that finished at the previous step start their next episode now.
        pending = self._reset_pending
        if pending.any():
            self.env.reset_envs(torch.from_numpy(pending).to(self.env.device))
            observations[pending] = _numpy(self.env.get_observations()[self.obs_group])[pending]
            rewards[pending] = 0.0
            terminated[pending] = truncated[pending] = done[pending] = False
        if done.any():
            assert final_obs is not None  # read above, before reset_envs, when any env is done
            observations[done] = final_obs[done]
            infos.update(_masked(metrics, done))
        self._reset_pending = done
        return observations, rewards, terminated, truncated, infos

    def close_extras(self, **kwargs) -> None:
        self.env = None


def _masked(values: dict[str, np.ndarray], mask: np.ndarray) -> dict[str, np.ndarray]:
    """gymnasium's vector info layout: each key's per-env values plus ``_key``, the envs they are valid for."""
    out: dict[str, np.ndarray] = {}
    for name, value in values.items():
        out[name] = np.where(mask, value, np.zeros_like(value))
        out[f"_{name}"] = mask.copy()
    return out
