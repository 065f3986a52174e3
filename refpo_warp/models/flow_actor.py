"""FlowActor: a flow-matching policy that plugs into rsl_rl wherever an actor ``class_name`` is accepted.

Convention (DESIGN.md): tau in [0, 1], tau = 0 is noise eps ~ N(0, I), tau = 1 is the action a;
x_tau = (1 - tau) eps + tau a; the target velocity is a - eps; actions are sampled by integrating
dx/dtau = v(x, tau; o) with N Euler steps from tau = 0.

CFM loss per (action, tau, eps), averaged over action dimensions:
- ``output_mode="u"``: ||v - (a - eps)||^2 (plain velocity regression, ReFPO's mode);
- ``output_mode="eps"``: tau^2 ||v - (a - eps)||^2, the reference FPO default ("u_but_supervise_as_eps", which
  supervises the implied noise prediction and so weights the velocity error by tau^2 in this convention).
"""

from __future__ import annotations

import copy
import warnings

import torch
from rsl_rl.modules import EmpiricalNormalization
from tensordict import TensorDict
from torch import nn

from refpo_warp.models.velocity_field import VelocityField

OUTPUT_MODES = ("u", "eps")


class FlowActor(nn.Module):
    """Flow-matching actor with the constructor and model protocol of rsl_rl's ``MLPModel``.

    Args:
        obs, obs_groups, obs_set, output_dim: As for rsl_rl models (passed by ``construct_algorithm``).
        hidden_dims, activation, obs_normalization: The velocity MLP and observation normalisation.
        distribution_cfg: Accepted for config compatibility; a flow policy has no parametric distribution.
        num_flow_steps: Euler steps N used to sample actions (change it at any time, e.g. N = 1 at deployment).
        time_embed_dim: Size of the sinusoidal embedding of tau.
        output_mode: ``"u"`` or ``"eps"`` weighting of the CFM loss (see module docstring).
        output_scale: Multiplier on the velocity MLP output.
        action_noise_std: Gaussian noise added to sampled actions when ``stochastic_output`` (reference PHC: 0.05).
    """

    is_recurrent: bool = False

    def __init__(
        self,
        obs: TensorDict,
        obs_groups: dict[str, list[str]],
        obs_set: str,
        output_dim: int,
        hidden_dims: tuple[int, ...] | list[int] = (256, 256, 256),
        activation: str = "elu",
        obs_normalization: bool = False,
        distribution_cfg: dict | None = None,
        num_flow_steps: int = 10,
        time_embed_dim: int = 8,
        output_mode: str = "u",
        output_scale: float = 1.0,
        action_noise_std: float = 0.0,
    ) -> None:
        super().__init__()
        if distribution_cfg is not None:
            warnings.warn("FlowActor ignores distribution_cfg: actions are sampled by integrating the flow.")
        if output_mode not in OUTPUT_MODES:
            raise ValueError(f"output_mode must be one of {OUTPUT_MODES}, got '{output_mode}'")
        self.obs_groups = list(obs_groups[obs_set])
        for group in self.obs_groups:
            if obs[group].dim() != 2:
                raise ValueError(f"FlowActor needs 1-D observation groups; '{group}' has shape {obs[group].shape}")
        self.obs_dim = sum(obs[g].shape[-1] for g in self.obs_groups)
        self.action_dim = output_dim
        self.obs_normalization = obs_normalization
        self.obs_normalizer = EmpiricalNormalization(self.obs_dim) if obs_normalization else nn.Identity()
        self.velocity = VelocityField(self.obs_dim, output_dim, hidden_dims, activation, time_embed_dim, output_scale)
        self.num_flow_steps = int(num_flow_steps)
        self.output_mode = output_mode
        self.action_noise_std = float(action_noise_std)
        self._last_actions = torch.zeros(1, output_dim)

    # ------------------------------------------------------------------------------------------------ sampling
    def encode(self, obs: TensorDict) -> torch.Tensor:
        """Concatenate this actor's observation groups and normalise them."""
        return self.obs_normalizer(torch.cat([obs[g] for g in self.obs_groups], dim=-1))

    def integrate(self, obs_norm: torch.Tensor, noise: torch.Tensor, num_steps: int | None = None) -> torch.Tensor:
        """Euler-integrate the flow from ``noise`` at tau = 0 to the action at tau = 1."""
        n = int(num_steps or self.num_flow_steps)
        if n < 1:
            raise ValueError(f"num_flow_steps must be >= 1, got {n}")
        return self.velocity.integrate(self.velocity.project_obs(obs_norm), noise, n)

    def forward(self, obs: TensorDict, masks=None, hidden_state=None, stochastic_output: bool = False,
                num_steps: int | None = None) -> torch.Tensor:  # fmt: skip
        """Sample actions; deterministic output integrates from zero noise (the flow's 'mode' for export).

        ``num_steps`` overrides ``num_flow_steps`` for this call (e.g. evaluating at N = 1).
        """
        obs_norm = self.encode(obs)
        shape = (obs_norm.shape[0], self.action_dim)
        noise = torch.randn(shape, device=obs_norm.device) if stochastic_output else obs_norm.new_zeros(shape)
        actions = self.integrate(obs_norm, noise, num_steps)
        if stochastic_output and self.action_noise_std > 0:
            actions = actions + self.action_noise_std * torch.randn_like(actions)
        self._last_actions = actions.detach()
        return actions

    # ------------------------------------------------------------------------------------------------ CFM loss
    def velocity_error(
        self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor
    ) -> torch.Tensor:
        """||v(x_tau, tau; o) - (a - eps)||^2 averaged over action dims, shape (B, K) for tau (B, K), eps (B, K, A)."""
        obs_feat = self.velocity.project_obs(self.encode(obs))
        a = actions.unsqueeze(1)
        x_tau = (1.0 - tau.unsqueeze(-1)) * eps + tau.unsqueeze(-1) * a
        v = self.velocity(obs_feat, x_tau, tau)
        return (v - (a - eps)).square().mean(dim=-1)

    def cfm_weight(self, tau: torch.Tensor, output_mode: str | None = None) -> torch.Tensor | float:
        """Per-sample weight of the velocity error in the CFM loss of ``output_mode`` (default: the actor's)."""
        return tau.square() if (output_mode or self.output_mode) == "eps" else 1.0

    def cfm_loss(self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor) -> torch.Tensor:
        """CFM loss per (action, tau, eps) sample in this actor's output mode, shape (B, K)."""
        return self.cfm_weight(tau) * self.velocity_error(obs, actions, tau, eps)

    # ------------------------------------------------------------------------------------------------ rsl_rl model protocol
    def reset(self, dones: torch.Tensor | None = None, hidden_state=None) -> None:
        pass

    def get_hidden_state(self):
        return None

    def detach_hidden_state(self, dones: torch.Tensor | None = None) -> None:
        pass

    def update_normalization(self, obs: TensorDict) -> None:
        if self.obs_normalization:
            self.obs_normalizer.update(torch.cat([obs[g] for g in self.obs_groups], dim=-1))

    @property
    def output_mean(self) -> torch.Tensor:
        return self._last_actions.mean(dim=0)

    @property
    def output_std(self) -> torch.Tensor:
        """Per-dimension spread of the last sampled batch (rsl_rl logs it as the policy's action std)."""
        if self._last_actions.shape[0] < 2:
            return torch.zeros(self.action_dim)
        return self._last_actions.std(dim=0)

    def get_output_log_prob(self, outputs: torch.Tensor) -> torch.Tensor:
        raise NotImplementedError(
            "A flow policy has no tractable action likelihood; train it with refpo_warp.algorithms:ReFPO "
            "(set reflow_coef=0 for FPO), not with rsl_rl's PPO."
        )

    @property
    def output_entropy(self) -> torch.Tensor:
        raise NotImplementedError("A flow policy has no closed-form entropy; see get_output_log_prob.")

    def as_jit(self) -> nn.Module:
        """TorchScript-able sampler: ``forward(obs, noise=None)`` with N = ``num_flow_steps`` Euler steps."""
        return FlowSampler(self)

    def as_onnx(self, verbose: bool = False) -> nn.Module:
        """ONNX-exportable sampler with inputs ``obs`` and ``noise`` (the Euler loop unrolls when traced)."""
        return FlowSampler(self, onnx=True)


class FlowSampler(nn.Module):
    """Export wrapper: normaliser + velocity field + an N-step Euler sampler, noise given as an input.

    ``forward(obs, noise)`` returns the action the flow maps ``noise`` to; ``noise=None`` (TorchScript only)
    integrates from zero noise, the deterministic output.
    """

    is_recurrent: bool = False

    def __init__(self, actor: FlowActor, onnx: bool = False) -> None:
        super().__init__()
        self.obs_normalizer = copy.deepcopy(actor.obs_normalizer)
        self.velocity = copy.deepcopy(actor.velocity)
        self.num_steps = int(actor.num_flow_steps)
        self.obs_dim = actor.obs_dim
        self.action_dim = actor.action_dim
        self.onnx = onnx

    def forward(self, obs: torch.Tensor, noise: torch.Tensor | None = None) -> torch.Tensor:
        x = torch.zeros(obs.shape[0], self.action_dim, device=obs.device) if noise is None else noise
        return self.velocity.integrate(self.velocity.project_obs(self.obs_normalizer(obs)), x, self.num_steps)

    @torch.jit.export
    def reset(self) -> None:
        pass

    def get_dummy_inputs(self) -> tuple[torch.Tensor, torch.Tensor]:
        return torch.zeros(1, self.obs_dim), torch.zeros(1, self.action_dim)

    @property
    def input_names(self) -> list[str]:
        return ["obs", "noise"]

    @property
    def output_names(self) -> list[str]:
        return ["actions"]
