"""The parts of rsl_rl's model protocol that every sampled (flow) policy answers the same way.

The observation set-up (the actor's groups, concatenated, normalised and optionally clamped) and what rsl_rl's runner
and PPO-style algorithms call on the actor: recurrent-state hooks (a flow policy has no hidden state), the
observation-normaliser update, and ``output_mean`` / ``output_std``, which rsl_rl logs as the policy's action
statistics; a sampled policy reports those of the last batch it sampled (``_last_actions``).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from rsl_rl.modules import EmpiricalNormalization
from tensordict import TensorDict
from torch import nn

from refpo_warp.models.normalization import update_normalizer, with_clip
from refpo_warp.models.stateless import Stateless
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Check, Flag, Int, OneOf, Real, mapping_or_none
from refpo_warp.utils.options import option
from refpo_warp.utils.rsl_rl_options import HIDDEN_DIMS, Activation

NUM_FLOW_STEPS = Int(1, 1000, fixed=False)  # Euler / chain steps N of a sampler; any N samples the same policy


@dataclass(frozen=True)
class SampledPolicyOptions:
    """The options every sampled policy's velocity MLP shares (the first fields of each actor's ``Options``)."""

    hidden_dims: tuple[int, ...] | list[int] = option(
        (256, 256, 256), HIDDEN_DIMS, "hidden layer sizes of the velocity MLP"
    )
    activation: str = option("elu", OneOf(Activation), "activation of the velocity MLP")
    obs_normalization: bool = option(False, Flag(), "normalise the observation (rsl_rl's EmpiricalNormalization)")
    obs_clip: float | None = option(
        None,
        Real(0, 1e6, lo_open=True, optional=True),
        "clamp the normalised observation to [-obs_clip, obs_clip] (Puffer-PHC: 10); null: no clamp",
    )
    distribution_cfg: dict | None = option(
        None,
        Check(mapping_or_none, "a mapping (ignored)", optional=True),
        "accepted for config compatibility and ignored: the sampler, not a parametric distribution, gives the actions",
    )


INITIAL_NOISE = ("random", "zero")
INITIAL_NOISE_RULE = OneOf(INITIAL_NOISE)


def noise_protocols(key: str, value) -> list[str]:
    """One initial-noise protocol or a list of them, as a list without repeats (the first is the headline)."""
    items = value if isinstance(value, (list, tuple)) else [value]
    if not items:
        raise ConfigError(f"{key}=[] is invalid; expected random, zero or a list of them (e.g. [random, zero])")
    out = [INITIAL_NOISE_RULE.check(key, item) for item in items]
    if len(set(out)) < len(out):
        raise ConfigError(f"{key}={value} is invalid: a protocol is listed twice")
    return out


NOISE_PROTOCOLS_RULE = Check(noise_protocols, "random, zero or a list of them (e.g. [random, zero])")


class SampledPolicyProtocol(Stateless):
    """Mixin for an ``nn.Module`` actor: ``_set_up_observations`` in its ``__init__``; its sampler sets
    ``_last_actions`` (the last sampled batch)."""

    def _set_up_observations(
        self,
        obs: TensorDict,
        obs_groups: dict[str, list[str]],
        obs_set: str,
        output_dim: int,
        obs_normalization: bool,
        obs_clip: float | None,
    ) -> None:
        """``obs_groups`` (this actor's, 1-D each), ``obs_dim``, ``action_dim`` and the normaliser (rsl_rl's, clamped
        to ``obs_clip`` if set); call after ``nn.Module.__init__``."""
        self.obs_groups = list(obs_groups[obs_set])
        for group in self.obs_groups:
            if obs[group].dim() != 2:
                raise ValueError(
                    f"{type(self).__name__} needs 1-D observation groups; '{group}' has shape {obs[group].shape}"
                )
        self.obs_dim = sum(obs[g].shape[-1] for g in self.obs_groups)
        self.action_dim = int(output_dim)
        self.obs_normalization = obs_normalization
        self.num_flow_steps: int  # the sampler's default number of steps, each actor's (declared for the type only)
        self.obs_normalizer: nn.Module = with_clip(
            EmpiricalNormalization(self.obs_dim) if obs_normalization else nn.Identity(), obs_clip
        )
        self._last_actions = torch.zeros(1, self.action_dim)

    def _sampling_steps(self, num_steps: int | None, initial_noise: str) -> int:
        """The steps of one ``sample`` call (``num_flow_steps`` by default), both arguments checked."""
        INITIAL_NOISE_RULE.check("initial_noise", initial_noise)
        return NUM_FLOW_STEPS.check("num_steps", int(num_steps or self.num_flow_steps))

    def _flat_obs(self, obs: TensorDict) -> torch.Tensor:
        return torch.cat([obs[g] for g in self.obs_groups], dim=-1)

    def encode(self, obs: TensorDict) -> torch.Tensor:
        """Concatenate this actor's observation groups and normalise them (clamped to ``obs_clip`` if set)."""
        return self.obs_normalizer(self._flat_obs(obs))

    def update_normalization(self, obs: TensorDict) -> None:
        if self.obs_normalization:
            update_normalizer(self.obs_normalizer, self._flat_obs(obs))

    @property
    def output_mean(self) -> torch.Tensor:
        return self._last_actions.mean(dim=0)

    @property
    def output_std(self) -> torch.Tensor:
        """Per-dimension spread of the last sampled batch (rsl_rl logs it as the policy's action std)."""
        if self._last_actions.shape[0] < 2:
            return torch.zeros(self.action_dim)
        return self._last_actions.std(dim=0)
