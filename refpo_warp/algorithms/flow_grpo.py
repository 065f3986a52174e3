"""Flow-GRPO for online control: the denoising MDP of an SDE-sampled flow policy, group-relative advantages, no critic.

Rollout (``act``): the flow actor's velocity field is sampled with Flow-GRPO's marginal-preserving SDE
(``refpo_warp.algorithms.flow_sde``; noise level a, N = the actor's ``num_flow_steps``), the feather noise is added to
the last state, and the chain x_0..x_N, the step means and the per-step log-probabilities (averaged over action dims)
are stored in the algorithm's own ``TransitionStore``.

Advantages (``compute_returns``, our choice for an online task): per env and time step the discounted reward-to-go
inside the rollout window, G_t = sum_{l >= 0} gamma^l r_{t+l}, cut at episode ends and not bootstrapped; then, per time
step, A = clip((G - mean of G over the env's group) / (std + 1e-4), -adv_clip, adv_clip), with the std over all envs
at that time step (Flow-GRPO's ``global_std``) or over the group. A group is ``group_size`` consecutive envs whose
episodes start from the same initial states: the env option ``reset_group_size`` (``WarpVecEnv``).

Update (``policy_loss``): the stored chain is teacher-forced under the current parameters; for every trained step k
ratio_k = exp(logp_new,k - logp_old,k) and the loss is the mean over (sample, step) of PPO's clipped surrogate
(``clip_param``) plus ``kl_coef`` * mean_d (mu_theta,k - mu_ref,k)^2 / (2 s_k^2) (the Flow-GRPO code's KL term),
with mu_ref the rollout policy's step mean (``kl_reference="rollout"``) or a frozen copy of the initial policy's
(``"initial"``). There is no value network: ``construct_algorithm`` puts a ``NoCritic`` in rsl_rl's critic slot
whatever the config's critic section says.

Evaluation uses the actor's deterministic ODE (``FlowActor.sample``), e.g. at N = 10 and N = 1.
"""

from __future__ import annotations

import copy
import warnings
from enum import Enum

import torch
from rsl_rl.algorithms import PPO as RslPPO
from tensordict import TensorDict
from torch import nn

from refpo_warp.algorithms.flow_sde import gaussian_log_prob, sample_sde_chain, sde_grid, sde_means
from refpo_warp.algorithms.on_policy import Minibatch, OnPolicyAlgorithm
from refpo_warp.models.flow_actor import FlowActor
from refpo_warp.utils.option_rules import Flag, Int, OneOf, Real
from refpo_warp.utils.options import choices, option


class KlReference(str, Enum):
    ROLLOUT = "rollout"  # the policy that collected the batch: a trust-region penalty
    INITIAL = "initial"  # a frozen copy of the policy at construction


class GroupStd(str, Enum):
    GLOBAL = "global"  # over all envs at a time step (Flow-GRPO's default)
    GROUP = "group"  # within the group


NO_CRITIC = "refpo_warp.models:NoCritic"


def discounted_reward_to_go(rewards: torch.Tensor, dones: torch.Tensor, gamma: float) -> torch.Tensor:
    """G_t = r_t + gamma (1 - done_t) G_{t+1} inside the window (G_T = 0): (T, E) rewards and dones -> (T, E)."""
    out = torch.empty_like(rewards)
    running = torch.zeros_like(rewards[0])
    for t in reversed(range(rewards.shape[0])):
        running = rewards[t] + gamma * (1.0 - dones[t].float()) * running
        out[t] = running
    return out


def group_advantages(
    returns: torch.Tensor, group_size: int, std_mode: str = "global", clip: float | None = 8.0, eps: float = 1e-4
) -> torch.Tensor:
    """Group-relative advantages of (T, E) returns; groups are ``group_size`` consecutive envs (see module docstring).

    The std is the population std (Flow-GRPO's ``np.std``) over all E envs at each time step (``"global"``) or over
    the group (``"group"``).
    """
    steps, envs = returns.shape
    if envs % group_size:
        raise ValueError(f"{envs} envs cannot form groups of {group_size}")
    grouped = returns.reshape(steps, envs // group_size, group_size)
    centred = grouped - grouped.mean(dim=-1, keepdim=True)
    if std_mode == "global":
        std = returns.std(dim=1, unbiased=False).reshape(steps, 1, 1)
    elif std_mode == "group":
        std = grouped.std(dim=-1, unbiased=False, keepdim=True)
    else:
        raise ValueError(f"group_std must be one of {choices(GroupStd)}, got '{std_mode}'")
    advantages = (centred / (std + eps)).reshape(steps, envs)
    return advantages if clip is None else advantages.clamp(-clip, clip)


class FlowGRPO(OnPolicyAlgorithm):
    """Flow-GRPO on rsl_rl's PPO machinery (see the module docstring); defaults from the ReFPO paper's table (c)."""

    uses_critic = False

    # Options (refpo_warp/utils/options.py), besides the shared ones (OnPolicyAlgorithm) and rsl_rl's PPO arguments.
    noise_level: float = option(
        1.0,
        Real(0, 100, lo_open=True),
        "a, the SDE noise level (table (c): 1.0; Flow-GRPO's default 0.7); the log-probabilities need noise",
    )
    feather_std: float = option(
        0.05, Real(0, 100), "std of the Gaussian noise added to the sampled action (table (c): 0.05)"
    )
    feather_in_chain: bool = option(
        True,
        Flag(),
        "the feathered action replaces x_N in the chain (FPO's denoising_mdp); else it stays outside the likelihood",
    )
    kl_coef: float = option(5e-3, Real(0, 1e6), "beta of the KL term (table (c): 5e-3); 0 turns it off")
    kl_reference: str = option(
        "rollout",
        OneOf(KlReference),
        "rollout: the policy that collected the batch; initial: a frozen copy of the policy at construction",
    )
    group_size: int | None = option(
        None, Int(2, 1_000_000, optional=True), "envs per group; null: the env's reset_group_size"
    )
    group_std: str = option(
        "global",
        OneOf(GroupStd),
        "advantage std over all envs at a time step (global, Flow-GRPO's default) or within the group",
    )
    adv_clip: float | None = option(
        8.0, Real(0, None, lo_open=True, optional=True), "clip of the advantages (table (c): 8); null: no clip"
    )
    timestep_fraction: float = option(
        1.0,
        Real(0, 1, lo_open=True),
        "train the first int(N * fraction) denoising steps (Flow-GRPO: 0.99, i.e. 9 of 10)",
    )
    explosion_threshold: float = option(
        3.0, Real(0, None, lo_open=True), "|log rho| above which a step counts in Flow/explosion_rate"
    )
    clip_param: float = option(0.1, doc="PPO clip range (table (c))")
    learning_rate: float = option(1e-4, doc="learning rate (table (c))")
    schedule: str = option("fixed", doc="learning-rate schedule (rsl_rl's default: adaptive)")
    entropy_coef: float = option(0.0, doc="entropy bonus (rsl_rl's default: 0.01)")
    value_loss_coef: float = option(0.0, doc="no critic, no value loss")

    def check_actor(self, actor: nn.Module) -> None:
        if not (hasattr(actor, "velocity") and hasattr(actor, "encode") and hasattr(actor, "num_flow_steps")):
            raise TypeError("FlowGRPO needs a flow actor; set actor.class_name to refpo_warp.models:FlowActor")

    def __init__(self, actor: FlowActor, critic: nn.Module, storage, **kwargs) -> None:
        super().__init__(actor, critic, storage, **kwargs)
        if self.bound_coef > 0:
            warnings.warn("FlowGRPO ignores bound_coef: its policy predicts no clean action to bound.")
        self.grid = sde_grid(actor.num_flow_steps, self.noise_level, self.device)  # fixed: the stored chains' N
        self.num_trained_steps = max(1, int(actor.num_flow_steps * self.timestep_fraction))
        self.reference_actor = None
        if self.kl_reference == "initial" and self.kl_coef > 0:
            self.reference_actor = copy.deepcopy(actor).eval().requires_grad_(False)

    @staticmethod
    def construct_algorithm(obs: TensorDict, env, cfg: dict, device: str) -> FlowGRPO:
        """rsl_rl's construction with a ``NoCritic`` in the critic slot; the group size comes from the env."""
        configured = cfg["critic"]
        cfg["critic"] = {"class_name": NO_CRITIC}
        try:
            alg = RslPPO.construct_algorithm(obs, env, cfg, device)
        finally:
            cfg["critic"] = configured
        alg.set_group_size(int(getattr(getattr(env, "cfg", None), "reset_group_size", 1)))
        return alg

    def set_group_size(self, env_group_size: int) -> None:
        """Use the env's ``reset_group_size`` (or check that an explicit ``group_size`` matches it)."""
        if self.group_size is None:
            self.group_size = env_group_size
        elif self.group_size != env_group_size:
            raise ValueError(
                f"algorithm.group_size={self.group_size} but the env's reset_group_size is "
                f"{env_group_size}: group members must share their initial states; set env."
                "reset_group_size to the group size (and leave algorithm.group_size null)"
            )
        if self.group_size < 2:
            raise ValueError(
                "Flow-GRPO needs groups of envs that start from the same states: set "
                "env.reset_group_size (e.g. 8, table (c)) to a divisor of num_envs"
            )

    # ---------------------------------------------------------------------------------------------- rollout
    def act(self, obs: TensorDict) -> torch.Tensor:
        actor = self.actor
        obs_feat = actor.velocity.project_obs(actor.encode(obs))
        action, chain, means, log_probs = sample_sde_chain(
            actor.velocity, obs_feat, actor.action_dim, self.grid, self.feather_std, self.feather_in_chain
        )
        self.store.write(self.storage.step, chain=chain, old_mean=means, old_log_prob=log_probs)
        t = self.transition
        t.actions = action
        t.values = self.critic(obs)
        t.actions_log_prob = log_probs.sum(dim=-1)
        t.distribution_params = ()
        t.observations = obs
        return action

    def compute_returns(self, obs: TensorDict) -> None:
        st = self.storage
        if self.group_size is None:
            raise RuntimeError("FlowGRPO.group_size is unset: build it through construct_algorithm or set_group_size")
        returns = discounted_reward_to_go(st.rewards.squeeze(-1), st.dones.squeeze(-1), self.gamma)
        st.returns = returns.unsqueeze(-1)
        st.advantages = group_advantages(returns, self.group_size, self.group_std, self.adv_clip).unsqueeze(-1)

    # ---------------------------------------------------------------------------------------------- update
    def step_means(self, actor, obs: TensorDict, chain: torch.Tensor) -> torch.Tensor:
        return sde_means(actor.velocity, actor.velocity.project_obs(actor.encode(obs)), chain, self.grid)

    def policy_loss(self, batch: Minibatch) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        k = self.num_trained_steps
        chain = batch.field("chain")
        mean = self.step_means(self.actor, batch.observations, chain)[:, :k]
        log_prob = gaussian_log_prob(chain[:, 1 : k + 1], mean, self.grid.std[:k].expand(chain.shape[0], -1))
        log_ratio = log_prob - batch.field("old_log_prob")[:, :k]
        ratio = torch.exp(log_ratio)
        adv = batch.advantages.unsqueeze(-1)
        surrogate = torch.max(-adv * ratio, -adv * ratio.clamp(1.0 - self.clip_param, 1.0 + self.clip_param)).mean()
        loss = surrogate
        stats = {"surrogate": surrogate}
        if self.kl_coef > 0:
            if self.reference_actor is None:
                reference = batch.field("old_mean")[:, :k]
            else:
                with torch.no_grad():
                    reference = self.step_means(self.reference_actor, batch.observations, chain)[:, :k]
            kl = ((mean - reference).square().mean(dim=-1) / (2.0 * self.grid.scale[:k].square())).mean()
            loss = loss + self.kl_coef * kl
            stats["kl"] = kl
        with torch.no_grad():
            stats.update(
                {
                    "Flow/ratio_mean": ratio.mean(),
                    "Flow/ratio_max": ratio.max(),
                    "Flow/clip_fraction": ((ratio - 1.0).abs() > self.clip_param).float().mean(),
                    "Flow/explosion_rate": (log_ratio.abs() > self.explosion_threshold).float().mean(),
                    "Flow/approx_kl": ((ratio - 1.0) - log_ratio).mean(),
                }
            )
        return loss, stats

    def kl_estimate(self, stats: dict[str, torch.Tensor]) -> torch.Tensor | None:
        return stats.get("Flow/approx_kl")
