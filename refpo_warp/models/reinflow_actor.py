"""ReinFlowActor: a flow policy with a learned exploration-noise network, sampled as a noisy Euler chain (ReinFlow).

Following ``ReinFlow/ReinFlow`` (``model/flow/mlp_flow.py`` ``NoisyFlowMLP``, ``ft_ppo/ppoflow.py``), in the project's
flow time (tau = 0 noise, tau = 1 action) with K = ``num_flow_steps``, t_k = k / K and D = the action size (a whole
action chunk when the env is wrapped in chunks):

    x_0 ~ N(0, I);   mu_k = clamp(x_k + v(x_k, t_k; o) / K, +-denoised_clip)
    x_{k+1} = mu_k + std_k * clamp(z, +-randn_clip),   z ~ N(0, I);   x_K clamped to +-action_clip

The noise sigma_k is learned on the last ``ft_denoising_steps`` steps by the noise network (an MLP with Tanh on
[time embedding of t_k, normalised observation]) and bounded through
log sigma^2 = log sigma_min^2 + (log sigma_max^2 - log sigma_min^2) (tanh(h) + 1) / 2; earlier steps use the fixed
schedule (``lin``: 0.1 t, ``vp``: sqrt(0.2 t (1 - t)), ``const``: sigma_min), clamped to [sigma_min, sigma_max].
The std actually sampled with is std_k = max(sigma_k, ``min_sampling_std``).

Chain log-likelihood and entropy, each divided by the number of terms (K + 1) and by D (ReinFlow's two normalisations):
    log pi = [log N(x_0; 0, I) + sum_k log N(x_{k+1}; mu_k, std_k^2 I)] / ((K + 1) D)
    H      = [D c + sum_k sum_d (c + log std_k,d)] / ((K + 1) D),   c = log(2 pi e) / 2
Both use the time grid and the std the chain was sampled with (our choice: the original recomputes its log-probs on
another time grid and without the std floor, see docs/algorithms.md).

Deterministic sampling (evaluation) runs the same chain without noise (clamps kept), from random or zero x_0.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from enum import Enum

import torch
from rsl_rl.utils import resolve_nn_activation
from tensordict import TensorDict
from torch import nn

from refpo_warp.models.sampled_policy import NUM_FLOW_STEPS, SampledPolicyOptions, SampledPolicyProtocol
from refpo_warp.models.velocity_field import VelocityField
from refpo_warp.utils.option_rules import Int, OneOf, Real
from refpo_warp.utils.options import choices, constructor_options, option
from refpo_warp.utils.rsl_rl_options import HIDDEN_DIMS, Activation


class NoiseSchedule(str, Enum):
    LIN = "lin"  # 0.1 t (table (d) "Linear")
    VP = "vp"  # sqrt(0.2 t (1 - t))
    CONST = "const"  # sigma_min


NOISE_SCHEDULES = choices(NoiseSchedule)
GAUSSIAN_ENTROPY = 0.5 * math.log(2.0 * math.pi * math.e)
LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


def fixed_sigma(t: float, schedule: str, sigma_min: float, sigma_max: float) -> float:
    """ReinFlow's schedule for the steps without learned noise, clamped to [sigma_min, sigma_max]."""
    if schedule == "lin":
        sigma = 0.1 * t
    elif schedule == "vp":
        sigma = math.sqrt(0.2 * t * (1.0 - t))
    elif schedule == "const":
        sigma = sigma_min
    else:
        raise ValueError(f"noise_schedule must be one of {NOISE_SCHEDULES}, got '{schedule}'")
    return min(max(sigma, sigma_min), sigma_max)


class ReinFlowActor(SampledPolicyProtocol, nn.Module):
    """ReinFlow's noisy flow policy with the constructor and model protocol of rsl_rl's ``MLPModel``: rsl_rl's
    ``obs``, ``obs_groups``, ``obs_set`` and ``output_dim``, then the options below by keyword."""

    @dataclass(frozen=True)
    class Options(SampledPolicyOptions):
        """ReinFlow's actor options; "table (d)" is the ReFPO paper's ReinFlow table."""

        num_flow_steps: int = option(
            4,
            NUM_FLOW_STEPS.with_fixed(None),
            "K, denoising steps (table (d): 4); fixed on resume: K shapes the noisy chain it trains on",
        )
        time_embed_dim: int = option(16, Int(2, 1024, multiple_of=2), "channels of the time embedding (table (d): 16)")
        output_scale: float = option(1.0, Real(0, 1e6, lo_open=True), "multiplies the velocity head")
        noise_hidden_dims: tuple[int, ...] | list[int] = option(
            (64, 64), HIDDEN_DIMS, "hidden layer sizes of the noise network (ReinFlow gym configs: [64, 64])"
        )
        noise_activation: str = option("tanh", OneOf(Activation), "activation of the noise network (ReinFlow: Tanh)")
        ft_denoising_steps: int = option(2, Int(0, 1000), "the last steps, whose noise is learned (table (d): 2)")
        sigma_min: float = option(
            0.08, Real(0, 100, lo_open=True, fixed=False), "lower bound of sigma (table (d): 0.08)"
        )
        sigma_max: float = option(
            0.16, Real(0, 100, lo_open=True, fixed=False), "upper bound of sigma (table (d): 0.16)"
        )
        noise_schedule: str = option(
            "lin",
            OneOf(NoiseSchedule, fixed=False),
            'fixed sigma of the other steps: lin 0.1 t (table (d) "Linear"), vp sqrt(0.2 t (1 - t)), const sigma_min',
        )
        min_sampling_std: float = option(
            0.10, Real(0, 100, fixed=False), "floor of the std sampled with (table (d): 0.10)"
        )
        denoised_clip: float = option(
            1.0, Real(0, 1e6, lo_open=True, fixed=False), "clamp of every step mean (ReinFlow: 1)"
        )
        randn_clip: float = option(
            3.0, Real(0, 1e6, lo_open=True, fixed=False), "truncation of the noise, in stds (ReinFlow: 3)"
        )
        action_clip: float = option(
            1.0, Real(0, 1e6, lo_open=True, fixed=False), "clamp of the final action (table (d) action range [-1, 1])"
        )

    def __init__(
        self, obs: TensorDict, obs_groups: dict[str, list[str]], obs_set: str, output_dim: int, **options
    ) -> None:
        super().__init__()
        o = constructor_options(type(self), type(self).Options, options)
        if o.distribution_cfg is not None:
            warnings.warn("ReinFlowActor ignores distribution_cfg: its noisy Euler chain defines the distribution.")
        if o.ft_denoising_steps > o.num_flow_steps:
            raise ValueError(
                f"ft_denoising_steps ({o.ft_denoising_steps}) must not exceed num_flow_steps ({o.num_flow_steps})"
            )
        if o.sigma_min > o.sigma_max:
            raise ValueError(f"sigma_min ({o.sigma_min}) must not exceed sigma_max ({o.sigma_max})")
        self._set_up_observations(obs, obs_groups, obs_set, output_dim, o.obs_normalization, o.obs_clip)
        self.velocity = VelocityField(
            self.obs_dim, self.action_dim, o.hidden_dims, o.activation, o.time_embed_dim, o.output_scale
        )
        layers, width = [], o.time_embed_dim + self.obs_dim
        for hidden in o.noise_hidden_dims:
            layers += [nn.Linear(width, hidden), resolve_nn_activation(o.noise_activation)]
            width = hidden
        self.noise_net = nn.Sequential(*layers, nn.Linear(width, self.action_dim))
        self.num_flow_steps = int(o.num_flow_steps)
        self.ft_denoising_steps = int(o.ft_denoising_steps)
        self.sigma_min = float(o.sigma_min)
        self.sigma_max: torch.Tensor  # the buffer's type (a class-level annotation would be TorchScript's to read)
        self.register_buffer("sigma_max", torch.tensor(float(o.sigma_max)))  # decayed by the algorithm, checkpointed
        self.noise_schedule = o.noise_schedule
        self.min_sampling_std = float(o.min_sampling_std)
        self.denoised_clip = float(o.denoised_clip)
        self.randn_clip = float(o.randn_clip)
        self.action_clip = float(o.action_clip)

    # ------------------------------------------------------------------------------------------------ the chain
    def step_std(self, obs_norm: torch.Tensor, k: int, num_steps: int) -> torch.Tensor:
        """The std step k samples with, max(sigma_k, min_sampling_std), shape (B, D)."""
        t = k / num_steps
        if k >= num_steps - self.ft_denoising_steps:
            time = self.velocity.embedding(obs_norm.new_full((obs_norm.shape[0],), t)).detach()
            h = torch.tanh(self.noise_net(torch.cat([time, obs_norm], dim=-1)))
            log_min, log_max = 2.0 * math.log(self.sigma_min), 2.0 * torch.log(self.sigma_max)
            sigma = torch.exp(0.5 * (log_min + (log_max - log_min) * (h + 1.0) / 2.0))
        else:
            fixed = fixed_sigma(t, self.noise_schedule, self.sigma_min, math.inf)
            sigma = obs_norm.new_full((obs_norm.shape[0], self.action_dim), fixed).minimum(self.sigma_max)
        return sigma.clamp(min=self.min_sampling_std)

    def step_mean(self, obs_feat: torch.Tensor, x: torch.Tensor, k: int, num_steps: int) -> torch.Tensor:
        tau = x.new_full(x.shape[:-1], k / num_steps)
        return (x + self.velocity(obs_feat, x, tau) / num_steps).clamp(-self.denoised_clip, self.denoised_clip)

    def run_chain(self, obs: TensorDict, num_steps: int, noisy: bool, x0: torch.Tensor) -> torch.Tensor:
        """The chain x_0..x_K (B, K + 1, D) from ``x0``, with the truncated noise if ``noisy``."""
        obs_norm = self.encode(obs)
        obs_feat = self.velocity.project_obs(obs_norm)
        x, chain = x0, [x0]
        for k in range(num_steps):
            x = self.step_mean(obs_feat, x, k, num_steps)
            if noisy:
                z = torch.randn_like(x).clamp(-self.randn_clip, self.randn_clip)
                x = x + self.step_std(obs_norm, k, num_steps) * z
            if k == num_steps - 1:
                x = x.clamp(-self.action_clip, self.action_clip)
            chain.append(x)
        return torch.stack(chain, dim=1)

    def chain_log_prob(self, obs: TensorDict, chain: torch.Tensor, with_entropy: bool = False):
        """Normalised log pi (B,) of a stored chain (B, K + 1, D), teacher-forced; with ``with_entropy`` also the
        normalised chain entropy (B,) and the mean std (see the module docstring)."""
        num_steps = chain.shape[1] - 1
        obs_norm = self.encode(obs)
        obs_feat = self.velocity.project_obs(obs_norm)
        x = chain[:, :-1]
        tau = (torch.arange(num_steps, device=chain.device, dtype=chain.dtype) / num_steps).expand(x.shape[:-1])
        mean = (x + self.velocity(obs_feat, x, tau) / num_steps).clamp(-self.denoised_clip, self.denoised_clip)
        std = torch.stack([self.step_std(obs_norm, k, num_steps) for k in range(num_steps)], dim=1)
        transitions = -(chain[:, 1:] - mean).square() / (2.0 * std.square()) - torch.log(std) - LOG_SQRT_2PI
        initial = -0.5 * chain[:, 0].square() - LOG_SQRT_2PI
        terms = (num_steps + 1) * self.action_dim
        log_prob = (initial.sum(dim=-1) + transitions.sum(dim=(1, 2))) / terms
        if not with_entropy:
            return log_prob
        entropy = (terms * GAUSSIAN_ENTROPY + torch.log(std).sum(dim=(1, 2))) / terms
        return log_prob, entropy, std.mean()

    # ------------------------------------------------------------------------------------------------ sampling
    def sample(
        self,
        obs: TensorDict,
        num_steps: int | None = None,
        initial_noise: str = "random",
        perturbation: bool = False,
        noise: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """Actions from the chain with ``num_steps`` steps (default K) from random, zero or the given x_0: the
        deterministic chain, or with ``perturbation`` the noisy one the rollout samples."""
        n = self._sampling_steps(num_steps, initial_noise)
        if noise is None:
            first = next(iter(obs.values()))
            shape = (first.shape[0], self.action_dim)
            noise = (
                torch.randn(shape, device=first.device)
                if initial_noise == "random"
                else first.new_zeros(torch.Size(shape))
            )
        actions = self.run_chain(obs, n, perturbation, noise)[:, -1]
        self._last_actions = actions.detach()
        return actions

    def sample_chain(self, obs: TensorDict) -> tuple[torch.Tensor, torch.Tensor]:
        """A rollout sample: the noisy chain (B, K + 1, D) from random x_0 and its normalised log-probability (B,)."""
        first = next(iter(obs.values()))
        chain = self.run_chain(
            obs, self.num_flow_steps, True, torch.randn(first.shape[0], self.action_dim, device=first.device)
        )
        self._last_actions = chain[:, -1].detach()
        return chain, self.chain_log_prob(obs, chain)

    def forward(
        self,
        obs: TensorDict,
        masks=None,
        hidden_state=None,
        stochastic_output: bool = False,
        num_steps: int | None = None,
    ) -> torch.Tensor:
        """rsl_rl's model call: the noisy chain from random x_0 with ``stochastic_output``, else the deterministic
        chain from zero x_0 (what inference uses)."""
        if stochastic_output:
            return self.sample(obs, num_steps, "random", perturbation=True)
        return self.sample(obs, num_steps, "zero", perturbation=False)

    # --------------------------------------------- rsl_rl model protocol (the rest: SampledPolicyProtocol)
    def get_output_log_prob(self, outputs: torch.Tensor) -> torch.Tensor:
        raise NotImplementedError(
            "ReinFlowActor's likelihood is that of its whole chain; train it with "
            "refpo_warp.algorithms:ReinFlow, not with rsl_rl's PPO."
        )

    @property
    def output_entropy(self) -> torch.Tensor:
        raise NotImplementedError("ReinFlowActor's entropy is that of its whole chain (chain_log_prob).")
