"""ReFPO: FPO's clipped CFM-ratio surrogate plus an un-weighted Reflow (CFM) regulariser (paper Algorithm A.1).

Per action a_t the rollout stores K pairs (tau_k, eps_k). At the start of ``update`` (before any gradient step,
so under the rollout parameters) the old CFM losses L_old,k are computed in one batched pass. Each minibatch then
computes L_new,k on the same pairs and

    rho   = exp(mean_k L_old,k - mean_k L_new,k)                      (ratio_mode="mean", the reference default)
    L     = -min(rho A, clip(rho, 1 - e, 1 + e) A) + c_v L_value + reflow_coef * mean_k L_new,k

``reflow_coef = 0`` is FPO. With ``ratio_mode="per_sample"`` each pair has its own ratio and the surrogate is
averaged over pairs; ``log_ratio_clip`` clamps each pair's log-ratio L_old,k - L_new,k to [-c, c] (their mean, the
"mean" log-ratio, then lies in [-c, c] as well).
"""

from __future__ import annotations

import warnings

import torch
from tensordict import TensorDict
from torch import nn

from refpo_warp.algorithms.ppo import PPO
from refpo_warp.errors import NonFiniteLossError

TAU_SAMPLING = ("uniform", "discrete")
RATIO_MODES = ("mean", "per_sample")


def flow_statistics(old_loss, new_loss, log_rho, velocity_error, clip_param: float, explosion_threshold: float):
    """Per-minibatch diagnostics: ratio mean, clip fraction, Explosion Rate, Straightness Error, approx. KL.

    Explosion Rate is the fraction of (action, tau, eps) samples with |L_new - L_old| > ``explosion_threshold``
    (a proxy-ratio change beyond exp(3) for the default 3); Straightness Error is the mean squared difference
    between v_theta and the straight direction a - eps on the stored pairs.
    """
    ratio = torch.exp(log_rho)
    return {
        "ratio_mean": ratio.mean(),
        "clip_fraction": ((ratio - 1.0).abs() > clip_param).float().mean(),
        "explosion_rate": ((new_loss - old_loss).abs() > explosion_threshold).float().mean(),
        "straightness_error": velocity_error.mean(),
        "approx_kl": ((ratio - 1.0) - log_rho).mean(),
    }


class ReFPO(PPO):
    """Reflow-regularised Flow Matching Policy Gradients on rsl_rl's PPO machinery.

    Args (in addition to every rsl_rl PPO argument):
        reflow_coef: lambda, the weight of the un-weighted CFM (Reflow) term; 0 gives FPO.
        num_mc_samples: K, (tau, eps) pairs stored per action.
        output_mode: ``"u"`` or ``"eps"`` CFM weighting; default: the actor's ``output_mode``.
        tau_sampling: ``"uniform"`` (tau ~ U[0, 1)) or ``"discrete"`` (tau on the sampler's Euler grid k/N).
        ratio_mode: ``"mean"`` (average the K losses before the exp) or ``"per_sample"``.
        log_ratio_clip: Clamp for the log-ratio (None: no clamp).
        explosion_threshold: |L_new - L_old| above which a sample counts towards the Explosion Rate.
        value_clip_param: Clip range of the clipped value loss (None: ``clip_param``, as in rsl_rl's PPO). The
            reference humanoid setup clips the ratio at 0.01 but the value at 0.2.
        reward_scale: Multiplier on rewards for learning (Brax-style; logged returns stay unscaled).
    """

    def __init__(
        self,
        actor: nn.Module,
        critic: nn.Module,
        storage,
        reflow_coef: float = 0.04,
        num_mc_samples: int = 8,
        output_mode: str | None = None,
        tau_sampling: str = "uniform",
        ratio_mode: str = "mean",
        log_ratio_clip: float | None = None,
        explosion_threshold: float = 3.0,
        value_clip_param: float | None = None,
        **ppo_kwargs,
    ) -> None:
        for name in ("rnd_cfg", "symmetry_cfg"):
            if ppo_kwargs.get(name):
                raise ValueError(
                    f"ReFPO does not support {name}: it trains the flow actor through the CFM-ratio surrogate "
                    f"only. Remove '{name}' from the algorithm config (or set it to None)."
                )
        if getattr(critic, "is_recurrent", False) or getattr(actor, "is_recurrent", False):
            raise ValueError("ReFPO supports feed-forward actors and critics only (no recurrent models).")
        for method in ("cfm_loss", "velocity_error", "cfm_weight"):
            if not hasattr(actor, method):
                raise TypeError(
                    f"ReFPO needs a flow actor with {method}(); set actor.class_name to refpo_warp.models:FlowActor"
                )
        if tau_sampling not in TAU_SAMPLING:
            raise ValueError(f"tau_sampling must be one of {TAU_SAMPLING}, got '{tau_sampling}'")
        if ratio_mode not in RATIO_MODES:
            raise ValueError(f"ratio_mode must be one of {RATIO_MODES}, got '{ratio_mode}'")
        if output_mode not in (None, "u", "eps"):
            raise ValueError(f"output_mode must be 'u', 'eps' or None (the actor's), got '{output_mode}'")
        if num_mc_samples < 1:
            raise ValueError(f"num_mc_samples must be >= 1, got {num_mc_samples}")
        if ppo_kwargs.get("entropy_coef"):
            warnings.warn("ReFPO ignores entropy_coef: a flow policy has no closed-form entropy.")
        super().__init__(actor, critic, storage, **ppo_kwargs)
        self.reflow_coef = float(reflow_coef)
        self.num_mc_samples = int(num_mc_samples)
        self.output_mode = output_mode or actor.output_mode
        self.tau_sampling = tau_sampling
        self.ratio_mode = ratio_mode
        self.log_ratio_clip = None if log_ratio_clip is None else float(log_ratio_clip)
        self.explosion_threshold = float(explosion_threshold)
        self.value_clip_param = self.clip_param if value_clip_param is None else float(value_clip_param)

    # ---------------------------------------------------------------------------------------------- rollout
    def sample_pairs(self, batch: int, device) -> tuple[torch.Tensor, torch.Tensor]:
        """Draw K (tau, eps) pairs per action: tau (batch, K), eps (batch, K, A)."""
        k, a = self.num_mc_samples, self.actor.action_dim
        if self.tau_sampling == "uniform":
            tau = torch.rand(batch, k, device=device)
        else:  # the sampler's Euler grid {0, 1/N, ..., (N-1)/N}
            n = self.actor.num_flow_steps
            tau = torch.randint(0, n, (batch, k), device=device).float() / n
        return tau, torch.randn(batch, k, a, device=device)

    def act(self, obs: TensorDict) -> torch.Tensor:
        actions = self.actor(obs, stochastic_output=True).detach()
        n = actions.shape[0]
        tau, eps = self.sample_pairs(n, actions.device)
        t = self.transition
        t.hidden_states = (None, None)
        t.actions = actions
        t.values = self.critic(obs).detach()
        t.actions_log_prob = torch.zeros(n, device=actions.device)
        # (tau, eps, old CFM loss): the old losses are filled in at the start of update().
        t.distribution_params = (tau, eps, torch.zeros(n, self.num_mc_samples, device=actions.device))
        t.observations = obs
        return actions

    # ---------------------------------------------------------------------------------------------- losses
    def cfm_losses(self, obs: TensorDict, actions: torch.Tensor, tau: torch.Tensor, eps: torch.Tensor):
        """(CFM loss in ``output_mode``, unweighted velocity error), both (B, K)."""
        error = self.actor.velocity_error(obs, actions, tau, eps)
        return self.actor.cfm_weight(tau, self.output_mode) * error, error

    def log_ratio(self, old_loss: torch.Tensor, new_loss: torch.Tensor) -> torch.Tensor:
        """log rho: (B,) for ratio_mode "mean", (B, K) for "per_sample"."""
        diff = old_loss - new_loss
        if self.log_ratio_clip is not None:
            diff = diff.clamp(-self.log_ratio_clip, self.log_ratio_clip)
        if self.ratio_mode == "per_sample":
            return diff
        return diff.mean(dim=-1)  # a mean of values in [-c, c] is in [-c, c]: no second clamp needed

    def surrogate_loss(self, ratio: torch.Tensor, advantages: torch.Tensor) -> torch.Tensor:
        """PPO's clipped surrogate (to minimise); advantages broadcast over per-sample ratios."""
        adv = advantages.reshape(-1, *([1] * (ratio.dim() - 1)))
        unclipped = -adv * ratio
        clipped = -adv * ratio.clamp(1.0 - self.clip_param, 1.0 + self.clip_param)
        return torch.max(unclipped, clipped).mean()

    def value_loss(self, values: torch.Tensor, old_values: torch.Tensor, returns: torch.Tensor) -> torch.Tensor:
        if self.use_clipped_value_loss:
            clipped = old_values + (values - old_values).clamp(-self.value_clip_param, self.value_clip_param)
            return torch.max((values - returns).pow(2), (clipped - returns).pow(2)).mean()
        return (returns - values).pow(2).mean()

    def compute_old_losses(self, chunk: int = 65536) -> None:
        """Fill the stored old CFM losses under the current (= rollout) parameters, before any gradient step."""
        st = self.storage
        obs = st.observations.flatten(0, 1)
        actions = st.actions.flatten(0, 1)
        tau, eps, old = (p.flatten(0, 1) for p in st.distribution_params)
        with torch.inference_mode():  # the storage buffers were allocated in inference mode by the runner
            for i in range(0, actions.shape[0], chunk):
                sl = slice(i, i + chunk)
                old[sl] = self.cfm_losses(obs[sl], actions[sl], tau[sl], eps[sl])[0]

    # ---------------------------------------------------------------------------------------------- update
    def update(self) -> dict[str, float]:
        self.compute_old_losses()
        # Per-minibatch stats stay on the device (no host sync per minibatch); they are read once after the loop.
        keys: list[str] = []
        rows: list[torch.Tensor] = []
        ratio_max = torch.zeros((), device=self.device)
        device_type = torch.device(self.device).type
        for batch in self.storage.mini_batch_generator(self.num_mini_batches, self.num_learning_epochs):
            tau, eps, old_loss = batch.old_distribution_params
            advantages = batch.advantages.squeeze(-1)
            if self.normalize_advantage_per_mini_batch:
                advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
            with torch.autocast(device_type=device_type, enabled=self.use_mixed_precision, dtype=torch.bfloat16):
                new_loss, velocity_error = self.cfm_losses(batch.observations, batch.actions, tau, eps)
                log_rho = self.log_ratio(old_loss, new_loss)
                ratio = torch.exp(log_rho)
                surrogate = self.surrogate_loss(ratio, advantages)
                value_loss = self.value_loss(self.critic(batch.observations), batch.values, batch.returns)
                reflow = new_loss.mean()
                loss = surrogate + self.value_loss_coef * value_loss + self.reflow_coef * reflow
            if not torch.isfinite(loss):
                raise NonFiniteLossError(
                    f"Non-finite ReFPO loss (surrogate={surrogate.item():.4g}, value={value_loss.item():.4g}, "
                    f"reflow={reflow.item():.4g}, max log-ratio={log_rho.abs().max().item():.4g}); the update was "
                    "stopped before applying it. Try a smaller learning_rate or log_ratio_clip."
                )

            self.optimizer.zero_grad()
            loss.backward()
            if self.is_multi_gpu:
                self.reduce_parameters()
            nn.utils.clip_grad_norm_(self.actor.parameters(), self.max_grad_norm)
            nn.utils.clip_grad_norm_(self.critic.parameters(), self.max_grad_norm)
            self.optimizer.step()

            with torch.no_grad():
                stats = flow_statistics(old_loss, new_loss, log_rho, velocity_error, self.clip_param,
                                        self.explosion_threshold)  # fmt: skip
                self._adapt_learning_rate(stats["approx_kl"])
                stats.update(surrogate=surrogate, value=value_loss, reflow=reflow)
                keys = list(stats)
                rows.append(torch.stack([value.detach().float() for value in stats.values()]))
                ratio_max = torch.maximum(ratio_max, ratio.detach().max().float())

        # Normalisers follow the data after the update, as in rsl_rl's PPO.
        obs = self.storage.observations.flatten(0, 1)
        self.actor.update_normalization(obs)
        self.critic.update_normalization(obs)
        self.storage.clear()

        num_updates = self.num_learning_epochs * self.num_mini_batches
        sums = torch.stack(rows).cpu().double().sum(dim=0).tolist() if rows else []
        out = {key: value / num_updates for key, value in zip(keys, sums)}
        out["ratio_max"] = float(ratio_max)
        return out

    def _adapt_learning_rate(self, approx_kl: torch.Tensor) -> None:
        """rsl_rl's adaptive schedule, driven by the CFM-ratio estimate of the KL, E[(rho - 1) - log rho]."""
        if self.desired_kl is None or self.schedule != "adaptive":
            return
        if self.is_multi_gpu:
            torch.distributed.all_reduce(approx_kl, op=torch.distributed.ReduceOp.SUM)
            approx_kl /= self.gpu_world_size
        if approx_kl > self.desired_kl * 2.0:
            self.learning_rate = max(1e-5, self.learning_rate / 1.5)
        elif 0.0 < approx_kl < self.desired_kl / 2.0:
            self.learning_rate = min(1e-2, self.learning_rate * 1.5)
        for group in self.optimizer.param_groups:
            group["lr"] = self.learning_rate
