"""FlowActor: a flow-matching policy that plugs into rsl_rl wherever an actor ``class_name`` is accepted.

Convention (the whole project's): tau in [0, 1], tau = 0 is noise eps ~ N(0, I), tau = 1 is the action a;
x_tau = (1 - tau) eps + tau a; the target velocity is a - eps; actions are sampled by integrating
dx/dtau = v(x, tau; o) with N Euler steps from tau = 0 (``refpo_warp.models.velocity_field`` for the network).

CFM loss per (action, tau, eps), averaged over action dimensions, times ``loss_scale``. With e_v = v - (a - eps) the
velocity error and e_a = a_hat - a = (1 - tau) e_v the error of the predicted clean action:
- ``output_mode="u"``: |e_v|^2, plain velocity regression (ReFPO's mode);
- ``output_mode="eps"``: tau^2 |e_v|^2, the reference FPO default ("u_but_supervise_as_eps");
- ``output_mode="data"``: |e_a|^2 = (1 - tau)^2 |e_v|^2, the Puffer-PHC humanoid loss (with ``loss_scale`` 200, i.e.
  1 / (2 * 0.05^2), its Gaussian "log-probability" scale).
Whatever the parameterisation, the error is computed in the space the network predicts and converted, so the ratio,
the Reflow term and the bound loss all see one consistent set of numbers.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from enum import Enum

import torch
from tensordict import TensorDict
from torch import nn

from refpo_warp.models.sampled_policy import NUM_FLOW_STEPS, SampledPolicyOptions, SampledPolicyProtocol
from refpo_warp.models.velocity_field import DATA_GUARD, Parameterization, TimeConditioning, VelocityField
from refpo_warp.utils.option_rules import Int, OneOf, Real
from refpo_warp.utils.options import choices, constructor_options, option


class OutputMode(str, Enum):
    U = "u"  # |e_v|^2, plain velocity regression (ReFPO's)
    EPS = "eps"  # tau^2 |e_v|^2, the reference FPO's "u_but_supervise_as_eps"
    DATA = "data"  # |a_hat - a|^2 = (1 - tau)^2 |e_v|^2 (Puffer-PHC)


OUTPUT_MODES = choices(OutputMode)


@dataclass
class CfmTerms:
    """Per-sample CFM quantities on K stored (tau, eps) pairs: squared errors (B, K) and the predicted action."""

    velocity_error: torch.Tensor  # mean over action dims of |v - (a - eps)|^2: the Straightness Error's summand
    action_error: torch.Tensor  # mean over action dims of |a_hat - a|^2
    clean_action: torch.Tensor  # a_hat (B, K, A), the action the network predicts at (x_tau, tau)
    velocity_residual: torch.Tensor | None = None  # e_v = v - (a - eps) per action dim (B, K, A)


def cfm_loss(terms: CfmTerms, tau: torch.Tensor, output_mode: str, loss_scale: float) -> torch.Tensor:
    """The CFM loss per sample (B, K) in ``output_mode`` (see the module docstring)."""
    if output_mode == "u":
        loss = terms.velocity_error
    elif output_mode == "eps":
        loss = tau.square() * terms.velocity_error
    elif output_mode == "data":
        loss = terms.action_error
    else:
        raise ValueError(f"output_mode must be one of {OUTPUT_MODES}, got '{output_mode}'")
    return loss_scale * loss


class FlowActor(SampledPolicyProtocol, nn.Module):
    """Flow-matching actor with the constructor and model protocol of rsl_rl's ``MLPModel``: rsl_rl's ``obs``,
    ``obs_groups``, ``obs_set`` and ``output_dim``, then the options below by keyword."""

    @dataclass(frozen=True)
    class Options(SampledPolicyOptions):
        """The flow actor's options (``docs/algorithms.md``, "Flow actor")."""

        num_flow_steps: int = option(
            10,
            NUM_FLOW_STEPS,
            "N, Euler steps that sample an action; may change at any time (train with 10, deploy with 1) and on resume",
        )
        time_embed_dim: int = option(
            8,
            Int(2, 1024, multiple_of=2),
            "channels of the time embedding: 2^k sinusoid (concat) or DiT sinusoid (adaln; Puffer-PHC: 256)",
        )
        output_mode: str = option(
            "u",
            OneOf(OutputMode),
            "the CFM loss: u |e_v|^2, eps tau^2 |e_v|^2 "
            "(Playground), data |a_hat - a|^2 (Puffer-PHC); e_v = v - (a - eps)",
        )
        output_scale: float = option(1.0, Real(0, 1e6, lo_open=True), "multiplies the head (Playground: 0.25)")
        action_noise_std: float = option(
            0.0,
            Real(0, 1e3, fixed=False),
            "Gaussian perturbation of rollout actions, stored with the action (Puffer-PHC: 0.05)",
        )
        parameterization: str = option(
            "velocity",
            OneOf(Parameterization),
            "the head predicts v, or the clean action a_hat with v = (a_hat - x) / (1 - tau) (Puffer-PHC)",
        )
        time_conditioning: str = option(
            "concat",
            OneOf(TimeConditioning),
            "tau enters the first layer "
            "as [cos(tau 2^k), sin(tau 2^k)] (Playground), or the last "
            "hidden layer through adaLN (Puffer-PHC)",
        )
        head_init_gain: float | None = option(
            None,
            Real(0, 1e3, lo_open=True, optional=True),
            "orthogonal head init with this gain, zero bias (Puffer-PHC: 0.01); null keeps PyTorch's",
        )
        loss_scale: float = option(
            1.0,
            Real(0, 1e6, lo_open=True),
            "multiplies the CFM loss, hence the ratio's log and the Reflow term (Puffer-PHC: 200 = 1 / (2 * 0.05^2))",
        )

    def __init__(
        self, obs: TensorDict, obs_groups: dict[str, list[str]], obs_set: str, output_dim: int, **options
    ) -> None:
        super().__init__()
        o = constructor_options(type(self), type(self).Options, options)
        if o.distribution_cfg is not None:
            warnings.warn("FlowActor ignores distribution_cfg: actions are sampled by integrating the flow.")
        self._set_up_observations(obs, obs_groups, obs_set, output_dim, o.obs_normalization, o.obs_clip)
        self.velocity = VelocityField(
            self.obs_dim,
            output_dim,
            o.hidden_dims,
            o.activation,
            o.time_embed_dim,
            o.output_scale,
            o.parameterization,
            o.time_conditioning,
            o.head_init_gain,
        )
        self.num_flow_steps = int(o.num_flow_steps)
        self.output_mode = o.output_mode
        self.loss_scale = float(o.loss_scale)
        self.action_noise_std = float(o.action_noise_std)

    # ------------------------------------------------------------------------------------------------ sampling
    def sample(
        self,
        obs: TensorDict,
        num_steps: int | None = None,
        initial_noise: str = "random",
        perturbation: bool = False,
        noise: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """Actions from the flow: integrate from random (or zero, or the given) noise with ``num_steps`` Euler steps
        (default ``num_flow_steps``), then add the ``action_noise_std`` perturbation if ``perturbation``."""
        n = self._sampling_steps(num_steps, initial_noise)
        obs_norm = self.encode(obs)
        if noise is None:
            shape = (obs_norm.shape[0], self.action_dim)
            random = initial_noise == "random"
            noise = torch.randn(shape, device=obs_norm.device) if random else obs_norm.new_zeros(shape)
        actions = self.velocity.integrate(self.velocity.project_obs(obs_norm), noise, n)
        if perturbation and self.action_noise_std > 0:
            actions = actions + self.action_noise_std * torch.randn_like(actions)
        self._last_actions = actions.detach()
        self._last_noise = noise.detach()  # x_0 of each action: the coupled Reflow pairs it with the action
        return actions

    def forward(
        self,
        obs: TensorDict,
        masks=None,
        hidden_state=None,
        stochastic_output: bool = False,
        num_steps: int | None = None,
    ) -> torch.Tensor:
        """rsl_rl's model call: a rollout sample (random noise, perturbation on) with ``stochastic_output``, else the
        deterministic output (zero noise, no perturbation), which is what inference and export use."""
        if stochastic_output:
            return self.sample(obs, num_steps, "random", perturbation=True)
        return self.sample(obs, num_steps, "zero", perturbation=False)

    # ------------------------------------------------------------------------------------------------ CFM loss
    def cfm_terms(self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor) -> CfmTerms:
        """CFM errors on the pairs tau (B, K), eps (B, K, A) for actions (B, A), in one forward pass."""
        obs_feat = self.velocity.project_obs(self.encode(obs))
        a = actions.unsqueeze(1)
        t = tau.unsqueeze(-1)
        x_tau = (1.0 - t) * eps + t * a
        prediction = self.velocity.predict(obs_feat, x_tau, tau)
        if self.velocity.parameterization == "velocity":
            e_v = prediction - (a - eps)
            e_a = (1.0 - t) * e_v
            clean = a + e_a
        else:  # the error of the clean action is native; the velocity error divides by the guarded 1 - tau
            clean = prediction
            e_a = prediction - a
            e_v = e_a / (1.0 - t).clamp(min=DATA_GUARD)
        return CfmTerms(e_v.square().mean(dim=-1), e_a.square().mean(dim=-1), clean, e_v)

    def cfm_loss(
        self,
        obs: TensorDict,
        actions: torch.Tensor,
        tau: torch.Tensor,
        eps: torch.Tensor,
        output_mode: str | None = None,
    ) -> torch.Tensor:
        """CFM loss per (action, tau, eps) sample, shape (B, K), in ``output_mode`` (default: the actor's)."""
        return cfm_loss(self.cfm_terms(obs, actions, tau, eps), tau, output_mode or self.output_mode, self.loss_scale)

    def velocity_error(self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor):
        """|v - (a - eps)|^2 averaged over action dims, shape (B, K): the Straightness Error's summand."""
        return self.cfm_terms(obs, actions, tau, eps).velocity_error

    # --------------------------------------------- rsl_rl model protocol (the rest: SampledPolicyProtocol)
    def get_output_log_prob(self, outputs: torch.Tensor) -> torch.Tensor:
        raise NotImplementedError(
            "A flow policy has no tractable action likelihood; train it with refpo_warp.algorithms:ReFPO "
            "(set reflow_coef=0 for FPO), not with rsl_rl's PPO."
        )

    @property
    def output_entropy(self) -> torch.Tensor:
        raise NotImplementedError("A flow policy has no closed-form entropy; see get_output_log_prob.")

    def as_jit(self, num_flow_steps: int | None = None, noise_input: bool = False) -> nn.Module:
        """TorchScript-able sampler (``refpo_warp.models.flow_export.FlowSampler``); obs only unless ``noise_input``."""
        from refpo_warp.models.flow_export import FlowSampler

        return FlowSampler(self, num_flow_steps, noise_input)

    def as_onnx(self, verbose: bool = False, num_flow_steps: int | None = None, noise_input: bool = False) -> nn.Module:
        """ONNX-exportable sampler (the Euler loop unrolls when traced); obs only unless ``noise_input``."""
        from refpo_warp.models.flow_export import FlowSampler

        return FlowSampler(self, num_flow_steps, noise_input)
