"""Flow-GRPO's marginal-preserving SDE sampler, in the project's flow time (tau = 0 noise, tau = 1 action).

Flow-GRPO (Liu et al. 2025, ``yifan123/flow_grpo`` ``sd3_sde_with_logprob.py``) replaces each Euler step of the
probability-flow ODE by an Euler-Maruyama step of the reverse SDE with the same marginals. Translated from its SD3
convention (sigma = 1 - tau, model output -v) to ours, with N steps of h = 1/N, tau_k = k h, sigma_k = 1 - tau_k and
the noise level a:

    s_k     = a sqrt(sigma_k / (1 - sigma_k))    for k >= 1;   s_0 = a sqrt(1 / h)  (the code's sigma = 1 rule:
                                                                 the second grid value in the denominator)
    mu_k    = x_k + h v_k - h s_k^2 / (2 sigma_k) (x_k - tau_k v_k)
    x_{k+1} = mu_k + s_k sqrt(h) z_k,  z_k ~ N(0, I)

Each step's log-probability is the Gaussian log-density of x_{k+1} under N(mu_k, (s_k sqrt(h))^2 I), averaged (not
summed) over action dimensions, as the code does. With a = 0 this is the Euler ODE sampler.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from refpo_warp.models.sampled_policy import NUM_FLOW_STEPS

LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


@dataclass
class SdeGrid:
    """Per-step constants of the N-step SDE: flow times, noise scales s_k and transition stds s_k sqrt(h)."""

    tau: torch.Tensor  # (N,)
    scale: torch.Tensor  # (N,) s_k
    std: torch.Tensor  # (N,) s_k sqrt(h)

    @property
    def num_steps(self) -> int:
        return int(self.tau.shape[0])


def sde_grid(num_steps: int, noise_level: float, device="cpu") -> SdeGrid:
    """The grid of an N-step SDE with noise level a (see the module docstring)."""
    NUM_FLOW_STEPS.check("num_steps", num_steps)
    h = 1.0 / num_steps
    tau = torch.arange(num_steps, dtype=torch.float64) * h
    sigma = 1.0 - tau
    denominator = (1.0 - sigma).clone()
    denominator[0] = h  # sigma_0 = 1: Flow-GRPO divides by 1 - sigma_1 = h instead of 0
    scale = noise_level * torch.sqrt(sigma / denominator)
    std = scale * math.sqrt(h)
    return SdeGrid(tau.float().to(device), scale.float().to(device), std.float().to(device))


def sde_mean(x: torch.Tensor, velocity: torch.Tensor, tau: torch.Tensor, scale: torch.Tensor, h: float) -> torch.Tensor:
    """mu = x + h v - h s^2 / (2 sigma) (x - tau v); ``tau`` and ``scale`` broadcast against x without its last axis."""
    tau, scale = tau.unsqueeze(-1), scale.unsqueeze(-1)
    sigma = 1.0 - tau
    return x + h * velocity - h * scale.square() / (2.0 * sigma) * (x - tau * velocity)


def gaussian_log_prob(x: torch.Tensor, mean: torch.Tensor, std: torch.Tensor) -> torch.Tensor:
    """log N(x; mean, std^2 I) averaged over the last axis; ``std`` broadcasts against x without its last axis."""
    std = std.unsqueeze(-1)
    return (-(x - mean).square() / (2.0 * std.square()) - torch.log(std) - LOG_SQRT_2PI).mean(dim=-1)


def sde_means(velocity_field, obs_feat: torch.Tensor, chain: torch.Tensor, grid: SdeGrid) -> torch.Tensor:
    """Teacher-forced step means mu_k (B, N, A) of a stored chain (B, N + 1, A), all N steps in one forward pass."""
    x = chain[:, :-1]
    tau = grid.tau.expand(x.shape[0], -1)
    v = velocity_field(obs_feat, x, tau)
    return sde_mean(x, v, tau, grid.scale.expand_as(tau), 1.0 / grid.num_steps)


@torch.no_grad()
def sample_sde_chain(
    velocity_field,
    obs_feat: torch.Tensor,
    action_dim: int,
    grid: SdeGrid,
    feather_std: float = 0.0,
    feather_in_chain: bool = True,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Sample the SDE from x_0 ~ N(0, I) and add the feather noise to the last state.

    Returns (action, chain (B, N + 1, A), step means (B, N, A), step log-probs (B, N)). With ``feather_in_chain``
    the feathered action replaces x_N in the chain (the FPO ``denoising_mdp`` path), so the last step's log-prob is
    that of the action sent to the env; otherwise the chain ends at the SDE sample and the feather stays outside.
    """
    n = obs_feat.shape[0]
    h = 1.0 / grid.num_steps
    x = torch.randn(n, action_dim, device=obs_feat.device)
    states, step_means = [x], []
    for k in range(grid.num_steps):
        tau = grid.tau[k].expand(n)
        mean = sde_mean(x, velocity_field(obs_feat, x, tau), tau, grid.scale[k].expand(n), h)
        x = mean + grid.std[k] * torch.randn_like(mean)
        states.append(x)
        step_means.append(mean)
    action = x + feather_std * torch.randn_like(x) if feather_std > 0 else x
    if feather_in_chain:
        states[-1] = action
    chain = torch.stack(states, dim=1)
    means = torch.stack(step_means, dim=1)
    log_probs = gaussian_log_prob(chain[:, 1:], means, grid.std.expand(n, -1))
    return action, chain, means, log_probs
