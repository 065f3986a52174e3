"""The flow policy's velocity network v(x_tau, tau; o) and its sinusoidal time embedding.

The first layer acts on concat(o, x_tau, emb(tau)); it is split into an observation part, computed once per
observation, and an (x_tau, emb) part, so K CFM samples per action and N Euler steps per action reuse the
observation projection instead of recomputing it.
"""

from __future__ import annotations

import torch
from rsl_rl.utils import resolve_nn_activation
from torch import nn


class SinusoidalEmbedding(nn.Module):
    """tau -> [cos(tau * 2^k), sin(tau * 2^k)] for k < dim/2 (the reference FPO embedding)."""

    def __init__(self, dim: int) -> None:
        super().__init__()
        if dim < 2 or dim % 2:
            raise ValueError(f"time_embed_dim must be an even number >= 2, got {dim}")
        self.register_buffer("freqs", 2.0 ** torch.arange(dim // 2, dtype=torch.float32))

    def forward(self, tau: torch.Tensor) -> torch.Tensor:
        angles = tau.unsqueeze(-1) * self.freqs
        return torch.cat([torch.cos(angles), torch.sin(angles)], dim=-1)


class VelocityField(nn.Module):
    """MLP velocity field; ``output_scale`` multiplies the raw output (the reference Playground setup uses 0.25)."""

    def __init__(
        self,
        obs_dim: int,
        action_dim: int,
        hidden_dims: list[int] | tuple[int, ...],
        activation: str,
        time_embed_dim: int,
        output_scale: float = 1.0,
    ) -> None:
        super().__init__()
        if not hidden_dims:
            raise ValueError("hidden_dims must name at least one hidden layer")
        self.embedding = SinusoidalEmbedding(time_embed_dim)
        self.obs_proj = nn.Linear(obs_dim, hidden_dims[0])
        self.sample_proj = nn.Linear(action_dim + time_embed_dim, hidden_dims[0], bias=False)
        layers: list[nn.Module] = [resolve_nn_activation(activation)]
        for d_in, d_out in zip(hidden_dims[:-1], hidden_dims[1:]):
            layers += [nn.Linear(d_in, d_out), resolve_nn_activation(activation)]
        layers.append(nn.Linear(hidden_dims[-1], action_dim))
        self.trunk = nn.Sequential(*layers)
        self.output_scale = float(output_scale)
        self.action_dim = action_dim

    def project_obs(self, obs: torch.Tensor) -> torch.Tensor:
        """First-layer contribution of the (normalised) observation, shape (B, H)."""
        return self.obs_proj(obs)

    def forward(self, obs_feat: torch.Tensor, x: torch.Tensor, tau: torch.Tensor) -> torch.Tensor:
        """Velocity at ``x`` (B, [K,] A) and ``tau`` (B, [K]) given ``obs_feat`` = ``project_obs(obs)`` (B, H)."""
        h = self.sample_proj(torch.cat([x, self.embedding(tau)], dim=-1))
        if h.dim() == 3:  # (B, K, H): broadcast the observation over the K samples
            h = h + obs_feat.unsqueeze(1)
        else:
            h = h + obs_feat
        return self.trunk(h) * self.output_scale

    def integrate(self, obs_feat: torch.Tensor, noise: torch.Tensor, num_steps: int) -> torch.Tensor:
        """Euler-integrate dx/dtau = v from ``noise`` at tau = 0 to tau = 1 in ``num_steps`` steps (the sampler)."""
        x = noise
        dt = 1.0 / num_steps
        for k in range(num_steps):
            tau = torch.full(x.shape[:-1], k * dt, device=x.device, dtype=x.dtype)
            x = x + dt * self.forward(obs_feat, x, tau)
        return x
