"""Base class of every refpo_warp environment: an rsl_rl ``VecEnv`` whose per-step work runs in Warp kernels.

A subclass allocates its state in ``_build`` and launches its kernels in ``_step_impl`` (action, physics,
reward/termination, auto-reset and observations for all envs at once) and ``_reset_impl`` (reset the envs selected
by a boolean mask and write their observations). The base class owns the buffers rsl_rl sees, exposed to the
kernels as zero-copy Warp views, and replays the whole step as one captured graph after a warm-up step (a CUDA
graph on GPU, a Warp CPU graph on CPU).

Finished envs are reset inside the step, so the observation a step returns for them already starts the next
episode. A subclass that sets ``supports_final_observations`` also writes each env's observation *before* that
reset into ``buffers.final_obs`` (at least while ``record_final_obs`` is set); the gymnasium adapter needs it for
``final_obs``. rsl_rl never reads it.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar

import torch
import warp as wp
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from refpo_warp.device import init_warp, resolve_device
from refpo_warp.options import Flag, Int, OneOf, check_options, rules_for

ACTION_TRANSFORMS = ("clip", "tanh")


@dataclass
class EnvCfg:
    """Options shared by every environment; task cfgs subclass this."""

    max_episode_length: int = 1000
    graph_capture: bool = True
    """Replay the step as a captured graph after one eager warm-up step (CUDA graph or Warp CPU graph)."""
    action_transform: str = "clip"
    """What the env does with the policy's actions before its dynamics: ``clip`` to [-1, 1] (the task kernels
    clip), or ``tanh`` first (MuJoCo Playground sends tanh(action) to the env; the learner keeps the pre-tanh
    action, so every algorithm trains on what it sampled)."""
    reset_group_size: int = 1
    """Envs [g G, (g + 1) G) form group g: the k-th episode of every member starts from the same initial state (one
    random stream per group and episode index; Flow-GRPO's groups). 1: an independent stream per env."""
    action_chunk: int = 1
    """Env steps per policy action: above 1, ``refpo_warp.registry.make_env`` wraps the env in an
    ``ActionChunkWrapper`` whose actions are ``action_chunk`` env actions run open-loop (ReinFlow's horizon)."""

    # Valid values of the fields (refpo_warp.options); a subclass adds the rules of its own fields the same way.
    option_rules = {"max_episode_length": Int(1, 10_000_000), "graph_capture": Flag(),
                    "action_transform": OneOf(ACTION_TRANSFORMS), "reset_group_size": Int(1, 1_000_000),
                    "action_chunk": Int(1, 1000, fixed=True)}  # the chunk sets the policy's action size  # fmt: skip

    def __post_init__(self) -> None:
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        for name, value in check_options(rules_for(type(self)), values, "env.").items():
            object.__setattr__(self, name, value)


@dataclass
class EnvBuffers:
    """Zero-copy Warp views of the torch buffers that kernels write (built once, never reallocated)."""

    actions: object
    rewards: object
    terminated: object
    truncated: object
    episode_length: object
    rng: object
    obs: dict
    metrics: dict
    final_obs: dict


class WarpVecEnv(VecEnv):
    """rsl_rl ``VecEnv`` over Warp kernels; see the module docstring for the subclass contract."""

    cfg_class: ClassVar[type] = EnvCfg
    episode_metrics: ClassVar[tuple[str, ...]] = ()
    """Per-episode values a subclass writes at termination (e.g. ``success``); logged and used by evaluation."""
    supports_final_observations: ClassVar[bool] = False
    """Whether ``_step_impl`` writes ``buffers.final_obs`` (see the module docstring) when ``record_final_obs``."""

    def __init__(self, cfg: EnvCfg, num_envs: int, device: str = "auto", seed: int = 0) -> None:
        if num_envs < 1:
            raise ValueError(f"num_envs must be >= 1, got {num_envs}")
        init_warp()
        self.cfg = cfg
        self.num_envs = int(num_envs)
        self.device = resolve_device(device)
        self.wp_device = wp.get_device(self.device)
        self.seed = int(seed)
        self.max_episode_length = int(cfg.max_episode_length)

        self.reset_group_size = int(cfg.reset_group_size)
        if self.num_envs % self.reset_group_size:
            raise ValueError(f"env.reset_group_size ({cfg.reset_group_size}) must divide num_envs ({self.num_envs})")
        self.num_actions, obs_dims = self._spaces()
        n, dev = self.num_envs, self.device
        self._actions = torch.zeros(n, self.num_actions, device=dev)
        self._rewards = torch.zeros(n, device=dev)
        self._terminated = torch.zeros(n, dtype=torch.bool, device=dev)
        self._truncated = torch.zeros(n, dtype=torch.bool, device=dev)
        self._episode_length = torch.zeros(n, dtype=torch.int32, device=dev)
        self._obs = {name: torch.zeros(n, dim, device=dev) for name, dim in obs_dims.items()}
        self._metrics = {name: torch.zeros(n, device=dev) for name in self.episode_metrics}
        self._final_obs = {name: torch.zeros(n, dim, device=dev) for name, dim in obs_dims.items()}
        self.record_final_obs = False
        # rsl_rl keeps the observation of step t while step t+1 runs: hand out alternating copies.
        self._obs_out = [TensorDict({k: v.clone() for k, v in self._obs.items()}, batch_size=[n]) for _ in range(2)]
        self._obs_parity = 0

        rng = torch.zeros(n, dtype=torch.int32, device=dev)
        self.buffers = EnvBuffers(
            actions=wp.from_torch(self._actions),
            rewards=wp.from_torch(self._rewards),
            terminated=wp.from_torch(self._terminated, dtype=wp.bool),
            truncated=wp.from_torch(self._truncated, dtype=wp.bool),
            episode_length=wp.from_torch(self._episode_length),
            rng=wp.from_torch(rng, dtype=wp.uint32),
            obs={k: wp.from_torch(v) for k, v in self._obs.items()},
            metrics={k: wp.from_torch(v) for k, v in self._metrics.items()},
            final_obs={k: wp.from_torch(v) for k, v in self._final_obs.items()},
        )
        if self.reset_group_size > 1:  # group streams: a per-env base seed and episode index
            self._group_base = wp.zeros(n, dtype=wp.int32, device=self.wp_device)
            self._episode_index = wp.zeros(n, dtype=wp.int32, device=self.wp_device)
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
        """Launch the kernels of one env step for all envs (must be graph-capturable: no host syncs)."""
        raise NotImplementedError

    def _reset_impl(self, mask) -> None:
        """Reset the envs where the Warp bool array ``mask`` is true and write their observations."""
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
            self._reset_impl(wp_mask)
            self._next_group_streams(wp_mask, wp_mask)
        keep = ~mask.to(self.device, torch.bool)
        self._terminated &= keep
        self._truncated &= keep

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        self._actions.copy_(actions)
        self._run_step()
        dones = self._terminated | self._truncated
        extras = {"time_outs": self._truncated.clone()}
        if self._metrics and bool(dones.any()):
            extras["log"] = {f"Episode/{name}": buf[dones] for name, buf in self._metrics.items()}
        return self._publish_obs(), self._rewards.clone(), dones, extras

    @property
    def episode_metric_buffers(self) -> dict[str, torch.Tensor]:
        """Per-env values of ``episode_metrics``, valid for the envs whose episode ended at the last step."""
        return self._metrics

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
                self._transform_and_step()
                self._steps_taken += 1
                # Capture after the eager warm-up step: every module is loaded and lazy buffers exist.
                if self.cfg.graph_capture and self._steps_taken == 1 and self._can_capture():
                    with wp.ScopedCapture(device=self.wp_device) as capture:
                        self._transform_and_step()
                    self._graph = capture.graph

    def _transform_and_step(self) -> None:
        if self.cfg.action_transform == "tanh":
            self.transform_actions(self.buffers.actions)
        self._step_impl()
        self._next_group_streams(self.buffers.terminated, self.buffers.truncated)

    def _next_group_streams(self, ended_a, ended_b) -> None:
        """After envs (``ended_a`` or ``ended_b``) drew their reset: point them at their group's next episode stream."""
        if self.reset_group_size > 1:
            wp.launch(_next_group_streams, dim=self.num_envs, device=self.wp_device,
                      inputs=[ended_a, ended_b, self._group_base, self._episode_index, self.buffers.rng])  # fmt: skip

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
        if self.reset_group_size > 1:
            wp.launch(_seed_group_streams, dim=self.num_envs, device=self.wp_device,
                      inputs=[seed, self.reset_group_size, self._group_base, self._episode_index, self.buffers.rng])
        else:
            wp.launch(_seed_streams, dim=self.num_envs, inputs=[seed, self.buffers.rng], device=self.wp_device)


@wp.kernel
def _tanh_in_place(actions: wp.array2d(dtype=float)):
    i, j = wp.tid()
    actions[i, j] = wp.tanh(actions[i, j])


@wp.kernel
def _seed_streams(seed: int, rng: wp.array(dtype=wp.uint32)):
    # Independent counter-based random stream per env; kernels advance rng[i] in place.
    i = wp.tid()
    rng[i] = wp.rand_init(seed, i)


@wp.kernel
def _seed_group_streams(seed: int, group_size: int, base: wp.array(dtype=wp.int32),
                        episode: wp.array(dtype=wp.int32), rng: wp.array(dtype=wp.uint32)):  # fmt: skip
    # Stream of env i's k-th episode: rand_init(base of its group, k); kernels draw resets (and only resets) from it.
    i = wp.tid()
    base[i] = wp.int32(wp.rand_init(seed, i // group_size))
    episode[i] = 0
    rng[i] = wp.rand_init(base[i], 0)


@wp.kernel
def _next_group_streams(ended_a: wp.array(dtype=wp.bool), ended_b: wp.array(dtype=wp.bool),
                        base: wp.array(dtype=wp.int32), episode: wp.array(dtype=wp.int32),
                        rng: wp.array(dtype=wp.uint32)):  # fmt: skip
    i = wp.tid()
    if ended_a[i] or ended_b[i]:
        episode[i] = episode[i] + 1
        rng[i] = wp.rand_init(base[i], episode[i])
