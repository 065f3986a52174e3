"""The flow policy's network: v(x_tau, tau; o), predicted as a velocity or as the clean action, with its time input.

Parameterisation (what the head predicts):
- ``velocity``: v directly (the paper's and Playground's set-up);
- ``data``: the clean action a_hat, turned into a velocity on the straight path by v = (a_hat - x) / (1 - tau)
  (Puffer-PHC's humanoid set-up). The last Euler step (tau = 1 - 1/N) then returns a_hat exactly. The division is
  guarded at ``1 - tau >= DATA_GUARD`` (the sampler never evaluates tau > 1 - 1/N; losses in data space never divide).

Time conditioning:
- ``concat``: the first layer acts on concat(o, x, emb(tau)) with emb = [cos(tau 2^k), sin(tau 2^k)] (Playground);
- ``adaln``: the first layer acts on concat(o, x); tau enters at the last hidden layer through adaptive LayerNorm,
  h <- LN(h) (1 + scale(c)) + shift(c), c = MLP(sinusoid(tau)) with DiT's sinusoid (max period 1e4); the modulation
  layer starts at zero, so the network starts time-independent (Puffer-PHC).

The first layer is split into an observation part, computed once per observation, and an (x, [emb]) part, so the K
CFM samples and N Euler steps per action reuse the observation projection.
"""

from __future__ import annotations

import itertools
import math
from enum import Enum

import torch
from rsl_rl.utils import resolve_nn_activation
from torch import nn

from refpo_warp.utils.options import choices


class Parameterization(str, Enum):
    VELOCITY = "velocity"  # the head predicts v
    DATA = "data"  # the head predicts the clean action a_hat (Puffer-PHC)


class TimeConditioning(str, Enum):
    CONCAT = "concat"  # emb(tau) concatenated to the first layer's input (Playground)
    ADALN = "adaln"  # adaptive LayerNorm at the last hidden layer (Puffer-PHC)


PARAMETERIZATIONS = choices(Parameterization)
TIME_CONDITIONINGS = choices(TimeConditioning)
DATA_GUARD = 1e-2


class SinusoidalEmbedding(nn.Module):
    """tau -> [cos(tau * 2^k), sin(tau * 2^k)] for k < dim/2 (the reference FPO embedding)."""

    def __init__(self, dim: int) -> None:
        super().__init__()
        if dim < 2 or dim % 2:
            raise ValueError(f"time_embed_dim must be an even number >= 2, got {dim}")
        self.freqs: torch.Tensor  # the buffer's type (a class-level annotation would be TorchScript's to read)
        self.register_buffer("freqs", 2.0 ** torch.arange(dim // 2, dtype=torch.float32))

    def forward(self, tau: torch.Tensor) -> torch.Tensor:
        angles = tau.unsqueeze(-1) * self.freqs
        return torch.cat([torch.cos(angles), torch.sin(angles)], dim=-1)


class TimestepEmbedding(nn.Module):
    """DiT's timestep embedding: sinusoid of ``dim`` channels (periods up to 1e4) followed by Linear-SiLU-Linear."""

    def __init__(self, dim: int, width: int, max_period: float = 1e4) -> None:
        super().__init__()
        if dim < 2 or dim % 2:
            raise ValueError(f"time_embed_dim must be an even number >= 2, got {dim}")
        half = dim // 2
        self.freqs: torch.Tensor  # the buffer's type (a class-level annotation would be TorchScript's to read)
        self.register_buffer("freqs", torch.exp(-math.log(max_period) * torch.arange(half, dtype=torch.float32) / half))
        self.mlp = nn.Sequential(nn.Linear(dim, width), nn.SiLU(), nn.Linear(width, width))

    def forward(self, tau: torch.Tensor) -> torch.Tensor:
        angles = tau.unsqueeze(-1) * self.freqs
        return self.mlp(torch.cat([torch.cos(angles), torch.sin(angles)], dim=-1))


class AdaLN(nn.Module):
    """LayerNorm without affine parameters, modulated by shift and scale from a condition (zero-initialised)."""

    def __init__(self, width: int) -> None:
        super().__init__()
        self.norm = nn.LayerNorm(width, elementwise_affine=False, eps=1e-6)
        head = nn.Linear(width, 2 * width)
        nn.init.zeros_(head.weight)
        nn.init.zeros_(head.bias)
        self.modulation = nn.Sequential(nn.SiLU(), head)

    def forward(self, h: torch.Tensor, cond: torch.Tensor) -> torch.Tensor:
        shift, scale = self.modulation(cond).chunk(2, dim=-1)
        return self.norm(h) * (1.0 + scale) + shift


class VelocityField(nn.Module):
    """MLP velocity field; ``output_scale`` multiplies the head (Playground: 0.25); see the module docstring."""

    def __init__(
        self,
        obs_dim: int,
        action_dim: int,
        hidden_dims: list[int] | tuple[int, ...],
        activation: str,
        time_embed_dim: int,
        output_scale: float = 1.0,
        parameterization: str = "velocity",
        time_conditioning: str = "concat",
        head_init_gain: float | None = None,
    ) -> None:
        super().__init__()
        if not hidden_dims:
            raise ValueError("hidden_dims must name at least one hidden layer")
        if parameterization not in PARAMETERIZATIONS:
            raise ValueError(f"parameterization must be one of {PARAMETERIZATIONS}, got '{parameterization}'")
        if time_conditioning not in TIME_CONDITIONINGS:
            raise ValueError(f"time_conditioning must be one of {TIME_CONDITIONINGS}, got '{time_conditioning}'")
        self.parameterization = parameterization
        self.time_conditioning = time_conditioning
        concat = time_conditioning == "concat"
        self.embedding = (
            SinusoidalEmbedding(time_embed_dim) if concat else TimestepEmbedding(time_embed_dim, hidden_dims[-1])
        )
        self.obs_proj = nn.Linear(obs_dim, hidden_dims[0])
        self.sample_proj = nn.Linear(action_dim + (time_embed_dim if concat else 0), hidden_dims[0], bias=False)
        layers: list[nn.Module] = []
        for d_in, d_out in itertools.pairwise(hidden_dims):
            layers += [resolve_nn_activation(activation), nn.Linear(d_in, d_out)]
        self.hidden = nn.Sequential(*layers)  # the last hidden layer's pre-activation comes out
        self.adaln = None if concat else AdaLN(hidden_dims[-1])
        self.activation = resolve_nn_activation(activation)
        self.head = nn.Linear(hidden_dims[-1], action_dim)
        if head_init_gain is not None:  # Puffer-PHC's layer_init: orthogonal weights, zero bias
            nn.init.orthogonal_(self.head.weight, gain=float(head_init_gain))
            nn.init.zeros_(self.head.bias)
        self.output_scale = float(output_scale)
        self.data_guard = DATA_GUARD  # an attribute, so TorchScript sees a constant
        self.action_dim = action_dim

    def project_obs(self, obs: torch.Tensor) -> torch.Tensor:
        """First-layer contribution of the (normalised) observation, shape (B, H)."""
        return self.obs_proj(obs)

    def predict(self, obs_feat: torch.Tensor, x: torch.Tensor, tau: torch.Tensor) -> torch.Tensor:
        """The head's prediction (a velocity or a clean action) at ``x`` (B, [K,] A), ``tau`` (B, [K])."""
        inputs = torch.cat([x, self.embedding(tau)], dim=-1) if self.adaln is None else x
        h = self.sample_proj(inputs)
        h = h + (obs_feat.unsqueeze(1) if h.dim() == 3 else obs_feat)  # (B, K, H): broadcast over the K samples
        h = self.hidden(h)
        if self.adaln is not None:
            h = self.adaln(h, self.embedding(tau))
        return self.head(self.activation(h)) * self.output_scale

    def velocity_from(self, prediction: torch.Tensor, x: torch.Tensor, tau: torch.Tensor) -> torch.Tensor:
        """The velocity a prediction stands for (identity for ``velocity``, (a_hat - x) / (1 - tau) for ``data``)."""
        if self.parameterization == "velocity":
            return prediction
        return (prediction - x) / (1.0 - tau).clamp(min=self.data_guard).unsqueeze(-1)

    def forward(self, obs_feat: torch.Tensor, x: torch.Tensor, tau: torch.Tensor) -> torch.Tensor:
        """Velocity at ``x`` and ``tau`` given ``obs_feat`` = ``project_obs(obs)``."""
        return self.velocity_from(self.predict(obs_feat, x, tau), x, tau)

    def integrate(self, obs_feat: torch.Tensor, noise: torch.Tensor, num_steps: int) -> torch.Tensor:
        """Euler-integrate dx/dtau = v from ``noise`` at tau = 0 to tau = 1 in ``num_steps`` steps (the sampler)."""
        x = noise
        dt = 1.0 / num_steps
        for k in range(num_steps):
            tau = torch.full(x.shape[:-1], k * dt, device=x.device, dtype=x.dtype)
            x = x + dt * self.forward(obs_feat, x, tau)
        return x
