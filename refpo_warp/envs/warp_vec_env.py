"""Base class of every refpo_warp environment: an rsl_rl ``VecEnv`` whose per-step work runs in Warp kernels.

The base owns the episode. One step, for all envs at once:

1. the actions (squashed by tanh first with ``action_transform: tanh``);
2. the task's ``_step_impl``: dynamics, then this step's ``rewards``, ``terminated`` (and, with
   ``task_truncation``, ``truncated``), its ``episode_metrics`` and per-step ``reward_terms``;
3. the base's ``finish_step`` kernel (``episode.py``): episode length, time-out, termination over time-out, the
   ``done`` reset mask, the episode sums of the reward terms, counters of finished envs back to zero;
4. with ``record_final_obs``, the task's ``_observe_final`` (each env's observation before its reset; the gymnasium
   adapter needs it, rsl_rl never reads it);
5. the task's ``_reset_impl(done)``: new episodes for finished envs, then every env's observation.

So the observation a step returns for a finished env already starts its next episode. A task whose whole step is a
few flops per env (GridWorld) may set ``step_finishes_episode`` and do 2, 3 (through ``episode.finish_env_step``, the
same rule), 4 and 5 in its own single kernel, where three launches would cost more than the work. The base owns the
buffers rsl_rl sees, exposed to the kernels as zero-copy Warp views, and replays the whole step as one captured graph
after a warm-up step (a CUDA graph on GPU, a Warp CPU graph on CPU).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from refpo_warp.envs.env_cfg import EnvCfg
from refpo_warp.envs.episode import finish_reward_terms, finish_step, restart_episodes
from refpo_warp.envs.random_streams import RandomStreams
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.warp_setup import init_warp, wp


@dataclass
class EnvBuffers:
    """Zero-copy Warp views of the torch buffers that kernels read and write (built once, never reallocated)."""

    actions: object
    rewards: object
    terminated: object
    truncated: object
    done: object  # the reset mask, written by the base
    episode_length: object
    rng: object
    obs: dict
    metrics: dict
    reward_terms: object  # (num_envs, len(reward_terms)) this step's value of each term
    final_obs: dict


class WarpVecEnv(VecEnv):
    """rsl_rl ``VecEnv`` over Warp kernels; see the module docstring for the step and the subclass contract."""

    cfg_class: ClassVar[type] = EnvCfg
    episode_metrics: tuple[str, ...] = ()
    """Per-episode values a subclass writes every step (valid where the episode ended, e.g. ``success``); logged as
    ``Episode/<name>`` and used by evaluation. A subclass may set it per instance in ``_spaces`` (a DMC task's own)."""
    curve_metrics: tuple[str, ...] = ()
    """Those of ``episode_metrics`` the periodic evaluation logs beside the return (``eval/<name>_N10``)."""
    reward_terms: ClassVar[tuple[str, ...]] = ()
    """Named parts of the reward whose per-step values the subclass writes to ``buffers.reward_terms``; their sums
    over each episode are logged as ``Episode_Reward/<name>``."""
    task_truncation: ClassVar[bool] = False
    """Whether ``_step_impl`` writes ``buffers.truncated`` (an episode end that is not a failure besides the
    time-out, e.g. the end of a motion clip)."""
    supports_final_observations: ClassVar[bool] = False
    """Whether the subclass writes ``buffers.final_obs``: in ``_observe_final`` (see the module docstring), or in its
    own step kernel with ``step_finishes_episode``."""
    step_finishes_episode: ClassVar[bool] = False
    """Whether ``_step_impl`` itself applies ``episode.finish_env_step``, writes ``final_obs`` and resets the envs
    that finished (one fused kernel); the base then launches neither ``finish_step`` nor ``_reset_impl`` after it.
    Only for tasks without ``reward_terms`` or ``task_truncation``."""
    env_steps_per_step: ClassVar[int] = 1
    """Env steps per ``step`` call (an ``ActionChunkWrapper`` runs several): what budgets and logs count."""

    def __init__(self, cfg: EnvCfg, num_envs: int, device: str = "auto", seed: int = 0) -> None:
        if num_envs < 1:
            raise ValueError(f"num_envs must be >= 1, got {num_envs}")
        if self.step_finishes_episode and (self.reward_terms or self.task_truncation):
            raise TypeError(
                f"{type(self).__name__}: step_finishes_episode cannot be combined with reward_terms or "
                "task_truncation (the base's finish kernels handle those)"
            )
        init_warp()
        self.cfg = cfg
        self.num_envs = int(num_envs)
        self.device = resolve_device(device)
        self.wp_device = wp.get_device(self.device)
        self.seed = int(seed)
        self.max_episode_length = int(cfg.max_episode_length)
        self.reset_group_size = int(cfg.reset_group_size)
        self.num_actions, obs_dims = self._spaces()
        n, dev = self.num_envs, self.device
        self._actions = torch.zeros(n, self.num_actions, device=dev)
        self._rewards = torch.zeros(n, device=dev)
        self._terminated = torch.zeros(n, dtype=torch.bool, device=dev)
        self._truncated = torch.zeros(n, dtype=torch.bool, device=dev)
        self._done = torch.zeros(n, dtype=torch.bool, device=dev)
        self._episode_length = torch.zeros(n, dtype=torch.int32, device=dev)
        self._obs = {name: torch.zeros(n, dim, device=dev) for name, dim in obs_dims.items()}
        self._metrics = {name: torch.zeros(n, device=dev) for name in self.episode_metrics}
        self._final_obs = {name: torch.zeros(n, dim, device=dev) for name, dim in obs_dims.items()}
        self.record_final_obs = False
        # rsl_rl keeps the observation of step t while step t+1 runs: hand out alternating copies.
        self._obs_out = [TensorDict({k: v.clone() for k, v in self._obs.items()}, batch_size=[n]) for _ in range(2)]
        self._obs_parity = 0
        # Per-episode sums of the reward terms: running, and of the episode that ended at the last step.
        width = max(len(self.reward_terms), 1)  # a Warp array needs a non-empty shape
        self._reward_terms = torch.zeros(n, width, device=dev)
        self._ended_terms = torch.zeros(n, width, device=dev)
        self._term_sums = wp.zeros((n, width), dtype=float, device=self.wp_device)
        self._ended_terms_view = wp.from_torch(self._ended_terms)

        rng = torch.zeros(n, dtype=torch.int32, device=dev)
        self.buffers = EnvBuffers(
            actions=wp.from_torch(self._actions),
            rewards=wp.from_torch(self._rewards),
            terminated=wp.from_torch(self._terminated, dtype=wp.bool),
            truncated=wp.from_torch(self._truncated, dtype=wp.bool),
            done=wp.from_torch(self._done, dtype=wp.bool),
            episode_length=wp.from_torch(self._episode_length),
            rng=wp.from_torch(rng, dtype=wp.uint32),
            obs={k: wp.from_torch(v) for k, v in self._obs.items()},
            metrics={k: wp.from_torch(v) for k, v in self._metrics.items()},
            reward_terms=wp.from_torch(self._reward_terms),
            final_obs={k: wp.from_torch(v) for k, v in self._final_obs.items()},
        )
        self._streams = RandomStreams(self.buffers.rng, self.reset_group_size, self.wp_device)
        self.reseed(self.seed)
        self._graph = None
        self._steps_taken = 0

        with wp.ScopedDevice(self.wp_device):
            self._build()
        self.reset()

    # ----------------------------------------------------------------------------------------- subclass contract
    def _spaces(self) -> tuple[int, dict[str, int]]:
        """Return ``(num_actions, {obs_group: dim})``; called before any buffer exists."""
        raise NotImplementedError

    def _build(self) -> None:
        """Allocate task state (models, Warp arrays) on ``self.wp_device``."""
        raise NotImplementedError

    def _step_impl(self) -> None:
        """Launch the dynamics of one step for all envs and write ``rewards``, ``terminated`` (every env, every step),
        ``episode_metrics`` and ``reward_terms``; must be graph-capturable (no host syncs). ``episode_length`` still
        holds the count before this step (the state reached is step ``episode_length + 1``)."""
        raise NotImplementedError

    def _reset_impl(self, mask) -> None:
        """Start new episodes where the Warp bool array ``mask`` is set (draw them from ``buffers.rng``), then make
        every env's observation current. The base has already restarted their episode counters."""
        raise NotImplementedError

    def _observe_final(self) -> None:
        """Write every env's observation of the state the step reached into ``buffers.final_obs`` (before resets)."""
        raise NotImplementedError

    # ----------------------------------------------------------------------------------------- rsl_rl VecEnv API
    @property
    def episode_length_buf(self) -> torch.Tensor:
        return self._episode_length

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        # rsl_rl reassigns this attribute (random initial episode lengths); kernels alias the buffer, so copy.
        self._episode_length.copy_(value.to(self._episode_length.dtype))

    def get_observations(self) -> TensorDict:
        return self._publish_obs()

    def reset(self) -> TensorDict:
        """Reset every env (eagerly) and return the first observations."""
        mask = torch.ones(self.num_envs, dtype=torch.bool, device=self.device)
        self.reset_envs(mask)
        return self._publish_obs()

    def reset_envs(self, mask: torch.Tensor) -> None:
        """Reset the envs selected by a boolean mask, leaving the others untouched."""
        wp_mask = wp.from_torch(mask.to(self.device, torch.bool).contiguous(), dtype=wp.bool)
        with wp.ScopedDevice(self.wp_device):
            self.restart_counters(wp_mask)
            self._reset_impl(wp_mask)
            self._streams.next_episode(wp_mask)

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        self._actions.copy_(actions)
        self._run_step()
        dones = self._done.clone()
        extras: dict[str, Any] = {"time_outs": self._truncated.clone()}
        if (self._metrics or self.reward_terms) and bool(dones.any()):
            extras["log"] = {f"Episode/{name}": buf[dones] for name, buf in self._metrics.items()}
            if self.reward_terms:
                ended_terms = self._ended_terms[dones]
                extras["log"].update(
                    {f"Episode_Reward/{t}": ended_terms[:, k] for k, t in enumerate(self.reward_terms)}
                )
        return self._publish_obs(), self._rewards.clone(), dones, extras

    @property
    def episode_metric_buffers(self) -> dict[str, torch.Tensor]:
        """Per-env values of ``episode_metrics``, valid for the envs whose episode ended at the last step."""
        return self._metrics

    def restart_counters(self, mask=None) -> None:
        """Episode length, return and reward-term sums of the envs in ``mask`` (a Warp bool array; None: all) back
        to a fresh episode's, and their end flags cleared; for tasks that place envs in a state themselves."""
        if mask is None:
            mask = wp.from_torch(torch.ones(self.num_envs, dtype=torch.bool, device=self.device), dtype=wp.bool)
        b = self.buffers
        wp.launch(
            restart_episodes,
            dim=self.num_envs,
            device=self.wp_device,
            inputs=[mask, len(self.reward_terms), b.episode_length, self._term_sums, b.terminated, b.truncated, b.done],
        )

    def enable_final_observations(self) -> None:
        """Make every step also write the observation each env had before its auto-reset (``final_observations``).

        Off by default, as it may cost an extra observation pass per step. The step graph is captured again.
        """
        if not self.supports_final_observations:
            raise NotImplementedError(
                f"{type(self).__name__} does not record the observation before an auto-reset "
                "(supports_final_observations is False), which the gymnasium adapter needs"
            )
        if not self.record_final_obs:
            self.record_final_obs = True
            self._graph, self._steps_taken = None, 0  # the next step runs eagerly, then is captured with the writes

    @property
    def final_observations(self) -> dict[str, torch.Tensor]:
        """Per group, every env's observation after the last step but before its auto-reset (live buffers; equal
        to the returned observation for envs that did not finish). Needs ``enable_final_observations()``."""
        if not self.record_final_obs:
            raise RuntimeError("call enable_final_observations() before stepping to record final observations")
        return self._final_obs

    @property
    def unwrapped(self) -> WarpVecEnv:
        return self

    @property
    def step_dt(self) -> float:
        """Control period in seconds (1 for grid tasks); used by rsl_rl's RND extension."""
        return 1.0

    # ----------------------------------------------------------------------------------------- internals
    def _run_step(self) -> None:
        with wp.ScopedDevice(self.wp_device):
            if self._graph is not None:
                wp.capture_launch(self._graph)
            else:
                self._launch_step()
                self._steps_taken += 1
                # Capture after the eager warm-up step: every module is loaded and lazy buffers exist.
                if self.cfg.graph_capture and self._steps_taken == 1 and self._can_capture():
                    with wp.ScopedCapture(device=self.wp_device) as capture:
                        self._launch_step()
                    self._graph = capture.graph

    def _launch_step(self) -> None:
        """Every kernel of one step, in the order of the module docstring."""
        b = self.buffers
        if self.cfg.action_transform == "tanh":
            self.transform_actions(b.actions)
        self._step_impl()
        if not self.step_finishes_episode:
            wp.launch(
                finish_step,
                dim=self.num_envs,
                device=self.wp_device,
                inputs=[
                    self.max_episode_length,
                    int(self.task_truncation),
                    b.terminated,
                    b.truncated,
                    b.episode_length,
                ],
                outputs=[b.done],
            )
            if self.reward_terms:
                wp.launch(
                    finish_reward_terms,
                    dim=(self.num_envs, len(self.reward_terms)),
                    device=self.wp_device,
                    inputs=[b.reward_terms, b.done, self._term_sums],
                    outputs=[self._ended_terms_view],
                )
            if self.record_final_obs:
                self._observe_final()
            self._reset_impl(b.done)
        self._streams.next_episode(b.done)

    def transform_actions(self, actions) -> None:
        """Apply ``action_transform`` in place to a Warp (num_envs, num_actions) array (``clip`` is the tasks')."""
        if self.cfg.action_transform == "tanh":
            wp.launch(_tanh_in_place, dim=actions.shape, inputs=[actions], device=self.wp_device)

    def _can_capture(self) -> bool:
        return self.wp_device.is_cpu or self.wp_device.is_mempool_enabled

    def _publish_obs(self) -> TensorDict:
        out = self._obs_out[self._obs_parity]
        self._obs_parity ^= 1
        for name, buf in self._obs.items():
            out[name].copy_(buf)
        return out

    def reseed(self, seed: int) -> None:
        """Restart every env's random stream from ``seed`` (gymnasium's ``reset(seed=...)``)."""
        self._streams.reseed(seed)


@wp.kernel
def _tanh_in_place(actions: wp.array2d(dtype=float)):
    i, j = wp.tid()
    actions[i, j] = wp.tanh(actions[i, j])
