"""ReFPO: FPO's clipped CFM-ratio surrogate plus an un-weighted Reflow (CFM) regulariser (paper Algorithm A.1).

Per action a_t the rollout stores K pairs (tau_k, eps_k). At the start of ``update`` (before any gradient step,
so under the rollout parameters) the old CFM losses L_old,k are computed in one batched pass. Each minibatch then
computes L_new,k on the same pairs and

    rho   = exp(mean_k L_old,k - mean_k L_new,k)                      (ratio_mode="mean", the reference default)
    L     = -min(rho A, clip(rho, 1 - e, 1 + e) A) + c_v L_value + reflow_coef * mean_k L_new,k [+ bound loss]

``reflow_coef = 0`` is FPO. ``trust_region`` replaces PPO's clip by SPO's penalty or FPO++'s asymmetric mix
(``refpo_warp.algorithms.trust_region``). With ``ratio_mode="per_sample"`` each pair has its own ratio and the
surrogate is averaged over pairs; ``log_ratio_clip`` clamps each pair's log-ratio L_old,k - L_new,k to [-c, c]
(their mean, the "mean" log-ratio, then lies in [-c, c] as well). The CFM loss (its output mode and scale) is the
actor's (``refpo_warp.models.flow_actor``), so the ratio and the Reflow term always use the same numbers.

Reflow pairs (``reflow_pairs``): ``independent`` (the paper's, the default) computes the Reflow term on the ratio's
own pairs; ``coupled`` (ours, ``docs/algorithms.md``) pairs each action a with the initial noise eps_0 its rollout
sample was integrated from (before any post-sample perturbation, which the stored action includes) and regresses
v(x_tau, tau) onto a - eps_0 at x_tau = (1 - tau) eps_0 + tau a, at the stored tau_k: the rectified flow's Reflow,
which straightens the sampler's own paths. The ratio keeps its independent pairs either way. The coefficient lambda
is fixed or adapted to the one-step consistency (``reflow_schedule``, ``refpo_warp/algorithms/reflow_schedule.py``).
``reflow_tau_weight: towards_zero`` weights the Reflow pairs by 1 - tau (normalised over the minibatch), towards the
small flow times that one Euler step reads. ``one_step_coef`` adds a one-step consistency term (ours): the mean over
actions of |v(eps_0, 0; o) - (a - eps_0)|^2 on the rollout's own (eps_0, a), i.e. |a_1(eps_0) - a| for the deployed
one-step sampler against the action the rollout's N-step sampler drew from the same noise: one extra network pass on
B rows beside the ratio's B x K.

Diagnostics (``Flow/...``, paper §4.2 and Appendix C): ``explosion_rate`` is the fraction of actions whose
log-ratio mean_k (L_old,k - L_new,k) exceeds ``explosion_threshold`` in magnitude (the paper's "Explosion" /
"Ratio Expl."), ``explosion_rate_pair`` the same per (tau, eps) pair; ``straightness_error`` the mean of
|v - (a - eps)|^2 on the stored pairs; ``ratio_mean``, ``ratio_max``, ``clip_fraction``, ``approx_kl``; per update,
on ``one_step_states`` states of the rollout, ``one_step_error``, ``policy_spread`` and ``one_step_ratio``
(``refpo_warp/models/flow_diagnostics.py``, in the env's action space) and the ``reflow_coef`` used.
"""

from __future__ import annotations

import warnings
from enum import Enum

import torch
from tensordict import TensorDict
from torch import nn

from refpo_warp.algorithms.on_policy import Minibatch, OnPolicyAlgorithm, soft_bound_loss
from refpo_warp.algorithms.reflow_schedule import ReflowSchedule, ScheduleMode, coefficient_range
from refpo_warp.algorithms.trust_region import TrustRegion, surrogate
from refpo_warp.models.flow_actor import OUTPUT_MODES, CfmTerms, FlowActor, cfm_loss
from refpo_warp.models.flow_diagnostics import one_step_consistency
from refpo_warp.utils.option_rules import Check, Int, OneOf, Real
from refpo_warp.utils.options import choices, option
from refpo_warp.utils.rsl_rl_versions import uncompiled


class TauSampling(str, Enum):
    UNIFORM = "uniform"  # U[0, 1)
    DISCRETE = "discrete"  # the sampler's Euler grid k/N (Playground)
    LOGIT_NORMAL = "logit_normal"  # Puffer-PHC's
    UNIFORM_INSET = "uniform_inset"  # U[0.005, 0.995] (FPO++)


class RatioMode(str, Enum):
    MEAN = "mean"  # average the K losses before the exp (the reference)
    PER_SAMPLE = "per_sample"  # one ratio per pair


class ReflowPairs(str, Enum):
    INDEPENDENT = "independent"  # the ratio's own pairs (the paper's)
    COUPLED = "coupled"  # the rollout's (eps_0, a) (ours)


class ReflowTauWeight(str, Enum):
    UNIFORM = "uniform"  # every pair alike (the paper's)
    TOWARDS_ZERO = "towards_zero"  # pairs weighted by 1 - tau (ours)


TAU_INSET = 0.005  # "uniform_inset" keeps flow times this far from both ends (FPO++)
DIAGNOSTIC_SEED_OFFSET = 7919  # the diagnostics' own random stream: they never move the training's


def sample_tau(
    shape: tuple[int, ...], mode: str, num_flow_steps: int, logit_mean: float, logit_std: float, device
) -> torch.Tensor:
    """Flow times for the CFM pairs: U[0, 1); the sampler's Euler grid {0, 1/N, ..., (N-1)/N}; logit-normal,
    tau = 1 / (1 + exp(logit_std * n + logit_mean)), n ~ N(0, 1), clipped to [1e-4, 1] (Puffer-PHC; with its
    mean -1.2 and std 1.2 the median is 0.77, towards the action end); or U[0.005, 0.995] (FPO++)."""
    if mode == "uniform":
        return torch.rand(shape, device=device)
    if mode == "uniform_inset":
        return TAU_INSET + (1.0 - 2.0 * TAU_INSET) * torch.rand(shape, device=device)
    if mode == "discrete":
        return torch.randint(0, num_flow_steps, shape, device=device).float() / num_flow_steps
    if mode == "logit_normal":
        sigma = torch.exp(torch.randn(shape, device=device) * logit_std + logit_mean)
        return (1.0 / (1.0 + sigma)).clamp(1e-4, 1.0)
    raise ValueError(f"tau_sampling must be one of {choices(TauSampling)}, got '{mode}'")


class ReFPO(OnPolicyAlgorithm):
    """Reflow-regularised Flow Matching Policy Gradients on rsl_rl's PPO machinery.

    The defaults are the project's tuned values (a fixed learning rate, not rsl_rl's adaptive schedule).
    """

    # Options (refpo_warp/utils/options.py), besides the shared ones (OnPolicyAlgorithm) and rsl_rl's PPO arguments.
    reflow_coef: float = option(
        0.04,
        Real(0, 1e6),
        "lambda, the weight of the un-weighted CFM (Reflow) term; 0 gives FPO; set per task in configs/task/*.yaml",
    )
    num_mc_samples: int = option(
        8, Int(1, 1024), "K, (tau, eps) pairs stored per action; set per task in configs/task/*.yaml"
    )
    output_mode: str | None = option(
        None, OneOf(None, OUTPUT_MODES), "the CFM loss mode (u, eps, data); null: the actor's output_mode"
    )
    tau_sampling: str = option(
        "uniform",
        OneOf(TauSampling),
        "flow times of the pairs: uniform "
        "U[0, 1), discrete k/N (Playground), logit_normal (Puffer-PHC), "
        "uniform_inset U[0.005, 0.995] (FPO++)",
    )
    tau_logit_mean: float = option(-1.2, Real(-10, 10), "mean of the logit-normal tau (Puffer-PHC: -1.2)")
    tau_logit_std: float = option(1.2, Real(0, 10, lo_open=True), "std of the logit-normal tau (Puffer-PHC: 1.2)")
    ratio_mode: str = option(
        "mean", OneOf(RatioMode), "mean: average the K losses before the exp; per_sample: one ratio per pair"
    )
    log_ratio_clip: float | None = option(
        None,
        Real(0, 100, lo_open=True, optional=True),
        "clamp each pair's log-ratio to [-c, c]; null: no clamp",
    )
    explosion_threshold: float = option(
        3.0, Real(0, None, lo_open=True), "|log-ratio| above which an action (or pair) counts in the Explosion Rate"
    )
    reflow_pairs: str = option(
        "independent",
        OneOf(ReflowPairs),
        "independent: the Reflow term on the ratio's pairs (the paper's); coupled: on the rollout's (eps_0, a)",
    )
    reflow_schedule: str = option(
        "fixed",
        OneOf(ScheduleMode),
        "fixed lambda (the paper's), or adaptive to the one-step ratio (reflow_schedule.py)",
    )
    one_step_target: float = option(
        0.25, Real(0, None, lo_open=True), "the one-step ratio the adaptive schedule steers towards"
    )
    reflow_coef_range: tuple[float, float] = option(
        (0.01, 0.2),
        Check(coefficient_range, "[min, max] with 0 <= min <= max"),
        "[min, max] of the adaptive lambda",
    )
    one_step_states: int = option(
        256,
        Int(0, 1_000_000),
        "rollout states of the per-update one-step diagnostic; 0 turns it off (the adaptive schedule needs it)",
    )
    trust_region: str = option(
        "ppo",
        OneOf(TrustRegion),
        "ppo: PPO's clip (the paper's); spo: SPO's "
        "penalty; aspo: clip for A > 0, penalty otherwise (FPO++; trust_region.py)",
    )
    reflow_tau_weight: str = option(
        "uniform",
        OneOf(ReflowTauWeight),
        "uniform (the paper's), or towards_zero: Reflow pairs weighted by 1 - tau (ours)",
    )
    one_step_coef: float = option(
        0.0,
        Real(0, 1e6),
        "weight of the one-step consistency term |v(eps_0, 0) - "
        "(a - eps_0)|^2 on the rollout's own noise and action (ours); 0: off",
    )
    clip_param: float = option(0.05, doc="PPO clip range (rsl_rl's default: 0.2)")
    learning_rate: float = option(3e-4, doc="learning rate (rsl_rl's default: 1e-3)")
    schedule: str = option(
        "fixed",
        doc="learning-rate schedule (rsl_rl's default: adaptive, which the proxy ratio's KL would drive to its bounds)",
    )
    entropy_coef: float = option(0.0, doc="ignored: a flow policy has no closed-form entropy (rsl_rl's: 0.01)")
    use_clipped_value_loss: bool = option(False, doc="PPO's clipped value loss (rsl_rl's default: true)")

    def check_actor(self, actor: nn.Module) -> None:
        for method in ("cfm_terms", "sample"):
            if not hasattr(actor, method):
                raise TypeError(
                    f"ReFPO needs a flow actor with {method}(); set actor.class_name to refpo_warp.models:FlowActor"
                )

    def __init__(self, actor: FlowActor, critic: nn.Module, storage, **kwargs) -> None:
        super().__init__(actor, critic, storage, **kwargs)
        if self.entropy_coef:
            warnings.warn("ReFPO ignores entropy_coef: a flow policy has no closed-form entropy.")
        if self.schedule == "adaptive" and self.kl_from_ratio():
            warnings.warn(
                "ReFPO with schedule='adaptive': rsl_rl's schedule would be driven by the CFM proxy ratio's KL "
                "estimate, which is not the policy's KL and moves the learning rate to its bounds within an "
                "iteration (measured: 1e-3 -> 2e-5). Use schedule='fixed' (ReFPO's default)."
            )
        self.output_mode = self.output_mode or actor.output_mode
        self.coef_schedule = ReflowSchedule(self.reflow_schedule, self.one_step_target, self.reflow_coef_range)
        self.reflow_coef = self.coef_schedule.start(self.reflow_coef)
        if self.coef_schedule.mode == "adaptive" and not self.one_step_states:
            raise ValueError("reflow_schedule='adaptive' needs the one-step diagnostic: set one_step_states > 0")
        self.action_transform: str | None = None  # the env's (construct_algorithm): the diagnostic's action space
        self.diagnostic_generator = torch.Generator().manual_seed(torch.initial_seed() + DIAGNOSTIC_SEED_OFFSET)
        self.one_step: dict[str, float] = {}

    @property
    def method_name(self) -> str:
        """FPO where the Reflow term stays off (``configs/algo/fpo.yaml``: ReFPO with a fixed reflow_coef of 0)."""
        if type(self) is ReFPO and self.coef_schedule.mode == "fixed" and self.reflow_coef == 0:
            return "FPO"
        return super().method_name

    @classmethod
    def construct_algorithm(cls, obs: TensorDict, env, cfg: dict, device: str) -> ReFPO:
        """rsl_rl's construction; the one-step diagnostic measures actions as the env applies them."""
        alg = super().construct_algorithm(obs, env, cfg, device)
        alg.action_transform = getattr(getattr(env, "cfg", None), "action_transform", None)
        return alg

    # ---------------------------------------------------------------------------------------------- rollout
    def sample_pairs(self, batch: int, device) -> tuple[torch.Tensor, torch.Tensor]:
        """Draw K (tau, eps) pairs per action: tau (batch, K), eps (batch, K, A)."""
        k, a = self.num_mc_samples, self.actor.action_dim
        tau = sample_tau(
            (batch, k), self.tau_sampling, self.actor.num_flow_steps, self.tau_logit_mean, self.tau_logit_std, device
        )
        return tau, torch.randn(batch, k, a, device=device)

    def act(self, obs: TensorDict) -> torch.Tensor:
        actions = self.actor(obs, stochastic_output=True).detach()
        n = actions.shape[0]
        tau, eps = self.sample_pairs(n, actions.device)
        self.store.write(self.storage.step, tau=tau, eps=eps)
        if self.reflow_pairs == "coupled" or self.one_step_coef > 0:  # the x_0 this action was integrated from
            self.store.write(self.storage.step, eps0=uncompiled(self, "actor")._last_noise)
        t = self.transition
        t.actions = actions
        t.values = self.critic(obs).detach()
        t.actions_log_prob = torch.zeros(n, device=actions.device)
        t.distribution_params = ()  # a flow has none; ReFPO's own data is in self.store
        t.observations = obs
        return actions

    # ---------------------------------------------------------------------------------------------- losses
    def cfm_losses(self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor):
        """(CFM loss per pair in ``output_mode``, the actor's CfmTerms), losses (B, K)."""
        terms = self.actor.cfm_terms(obs, actions, tau, eps)
        assert self.output_mode is not None  # the actor's when the option is null (__init__)
        return cfm_loss(terms, tau, self.output_mode, self.actor.loss_scale), terms

    def pair_log_ratios(
        self, old_loss: torch.Tensor, new_loss: torch.Tensor, advantages: torch.Tensor | None = None
    ) -> torch.Tensor:
        """L_old,k - L_new,k per pair (B, K), clamped by ``log_ratio_clip`` (``advantages``: for subclasses' caps)."""
        diff = old_loss - new_loss
        if self.log_ratio_clip is not None:
            diff = diff.clamp(-self.log_ratio_clip, self.log_ratio_clip)
        return diff

    def log_ratio(
        self, old_loss: torch.Tensor, new_loss: torch.Tensor, advantages: torch.Tensor | None = None
    ) -> torch.Tensor:
        """log rho: (B,) for ratio_mode "mean", (B, K) for "per_sample"."""
        diff = self.pair_log_ratios(old_loss, new_loss, advantages)
        if self.ratio_mode == "per_sample":
            return diff
        return diff.mean(dim=-1)  # a mean of values in [-c, c] is in [-c, c]: no second clamp needed

    def surrogate_loss(self, ratio: torch.Tensor, advantages: torch.Tensor) -> torch.Tensor:
        """The trust region's surrogate (to minimise); advantages broadcast over per-sample ratios."""
        return surrogate(ratio, advantages, self.clip_param, self.trust_region)

    def reflow_loss(self, new_loss: torch.Tensor, batch: Minibatch) -> torch.Tensor:
        """The Reflow term: the CFM loss of the current parameters on the Reflow pairs, un-weighted by the advantage;
        by flow time with ``reflow_tau_weight: towards_zero`` (weights 1 - tau, normalised over the minibatch)."""
        if self.reflow_tau_weight == "uniform":
            return new_loss.mean()
        weights = 1.0 - batch.field("tau")
        return (weights * new_loss).sum() / weights.sum().clamp(min=1e-12)

    def one_step_loss(self, batch: Minibatch) -> torch.Tensor:
        """mean_i |v(eps_0,i, 0; o_i) - (a_i - eps_0,i)|^2 / D: the one-step sampler's squared error against the
        rollout's own action from the same initial noise (see the module docstring)."""
        eps0 = batch.field("eps0").unsqueeze(1)
        tau = torch.zeros(eps0.shape[0], 1, device=eps0.device)
        return self.actor.cfm_terms(batch.observations, batch.actions, tau, eps0).velocity_error.mean()

    def reflow_pair_losses(self, batch: Minibatch, tau: torch.Tensor, eps: torch.Tensor, new_loss: torch.Tensor):
        """CFM losses (B, K) of the Reflow pairs: the ratio's (independent), or the rollout's (eps_0, a) at each
        tau_k (coupled)."""
        if self.reflow_pairs == "independent":
            return new_loss
        eps0 = batch.field("eps0").unsqueeze(1).expand_as(eps)
        return self.cfm_losses(batch.observations, batch.actions, tau, eps0)[0]

    def measure_one_step(self) -> None:
        """The one-step diagnostic on ``one_step_states`` states of this rollout (its own random stream), then the
        coefficient of the coming update."""
        if not self.one_step_states:
            return
        obs = self.storage.observations.flatten(0, 1)
        gen = self.diagnostic_generator
        rows = torch.randperm(obs.shape[0], generator=gen)[: self.one_step_states].to(obs.device)
        actor = uncompiled(self, "actor")
        self.one_step = one_step_consistency(
            actor, obs[rows], actor.num_flow_steps, self.action_transform, generator=gen
        )
        self.reflow_coef = self.coef_schedule.step(self.reflow_coef, self.one_step["one_step_ratio"])

    def old_pair_values(
        self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor
    ) -> dict[str, torch.Tensor]:
        """What the update keeps of the rollout parameters on the stored pairs, by store field: the old CFM losses
        (B, K); a subclass may add its own (FPO++'s old noise-end predictions)."""
        return {"old_loss": self.cfm_losses(obs, actions, tau, eps)[0]}

    def before_update(self, chunk: int = 65536) -> None:
        """Store the old CFM losses (``old_pair_values``) under the current (= rollout) parameters, before any
        gradient step."""
        self.measure_one_step()
        obs = self.storage.observations.flatten(0, 1)
        actions = self.storage.actions.flatten(0, 1)
        tau, eps = self.store.flat("tau"), self.store.flat("eps")
        with torch.inference_mode():
            parts = [
                self.old_pair_values(obs[i : i + chunk], actions[i : i + chunk], tau[i : i + chunk], eps[i : i + chunk])
                for i in range(0, actions.shape[0], chunk)
            ]
            self.store.write_all(**{name: torch.cat([part[name] for part in parts]) for name in parts[0]})

    def policy_loss(self, batch: Minibatch) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        tau, eps, old_loss = batch.field("tau"), batch.field("eps"), batch.field("old_loss")
        new_loss, terms = self.cfm_losses(batch.observations, batch.actions, tau, eps)
        log_rho = self.log_ratio(old_loss, new_loss, batch.advantages)
        ratio = torch.exp(log_rho)
        surrogate = self.surrogate_loss(ratio, batch.advantages)
        reflow = self.reflow_loss(self.reflow_pair_losses(batch, tau, eps, new_loss), batch)
        loss = surrogate + self.reflow_coef * reflow
        stats = {"surrogate": surrogate, "reflow": reflow}
        if self.one_step_coef > 0:
            stats["one_step"] = self.one_step_loss(batch)
            loss = loss + self.one_step_coef * stats["one_step"]
        if self.bound_coef > 0:
            stats["bound"] = soft_bound_loss(terms.clean_action, self.bound)
            loss = loss + self.bound_coef * stats["bound"]
        extra, extra_stats = self.pair_terms_loss(batch, tau, eps, terms)
        if extra is not None:
            loss = loss + extra
        stats.update(extra_stats)
        with torch.no_grad():
            stats.update(self.flow_statistics(old_loss, new_loss, log_rho, terms.velocity_error))
        return loss, stats

    def pair_terms_loss(
        self, batch: Minibatch, tau: torch.Tensor, eps: torch.Tensor, terms: CfmTerms
    ) -> tuple[torch.Tensor | None, dict[str, torch.Tensor]]:
        """A subclass's further loss on the minibatch's pairs (the actor's ``CfmTerms`` under the current
        parameters) and its statistics; None adds nothing (ReFPO)."""
        return None, {}

    def flow_statistics(self, old_loss, new_loss, log_rho, velocity_error) -> dict[str, torch.Tensor]:
        """Per-minibatch diagnostics (see the module docstring)."""
        ratio = torch.exp(log_rho)
        change = old_loss - new_loss
        return {
            "Flow/ratio_mean": ratio.mean(),
            "Flow/ratio_max": ratio.max(),
            "Flow/clip_fraction": ((ratio - 1.0).abs() > self.clip_param).float().mean(),
            "Flow/explosion_rate": (change.mean(dim=-1).abs() > self.explosion_threshold).float().mean(),
            "Flow/explosion_rate_pair": (change.abs() > self.explosion_threshold).float().mean(),
            "Flow/straightness_error": velocity_error.mean(),
            "Flow/approx_kl": ((ratio - 1.0) - log_rho).mean(),
        }

    def kl_estimate(self, stats: dict[str, torch.Tensor]) -> torch.Tensor | None:
        return stats.get("Flow/approx_kl")

    def kl_from_ratio(self) -> bool:
        """Whether the adaptive schedule reads the proxy ratio's KL estimate (ReFPO's only choice; FPO++'s
        ``adaptive_kl`` may pick the noise-end prediction instead)."""
        return True

    def update(self) -> dict[str, float]:
        out = super().update()
        out.update({f"Flow/{k}": v for k, v in self.one_step.items()})
        out["Flow/reflow_coef"] = self.reflow_coef
        return out

    # ---------------------------------------------------------------------------------------------- checkpoints
    def save(self) -> dict:
        saved = super().save()
        saved["reflow_coef"] = self.reflow_coef  # the adaptive schedule's state, and its random stream
        saved["diagnostic_rng"] = self.diagnostic_generator.get_state()
        return saved

    def load(self, loaded_dict: dict, load_cfg: dict | None, strict: bool) -> bool:
        out = super().load(loaded_dict, load_cfg, strict)
        if "reflow_coef" in loaded_dict and self.coef_schedule.mode == "adaptive":
            self.reflow_coef = float(loaded_dict["reflow_coef"])
        if isinstance(loaded_dict.get("diagnostic_rng"), torch.Tensor):
            self.diagnostic_generator.set_state(loaded_dict["diagnostic_rng"])
        return out
