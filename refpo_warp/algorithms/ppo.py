"""Gaussian PPO: rsl_rl's PPO objective on the shared update loop (so it gets the same options as the flow methods).

With the default options an update is rsl_rl's ``PPO.update`` step for step (tests/algorithms/test_ppo.py checks the
parameters match). The shared options add what the paper's baselines use: Brax-style reward scaling (DMC, x10),
the soft bound loss on the mean action and joint gradient clipping (Puffer-PHC humanoid), per-pass reshuffling.
"""

from __future__ import annotations

import torch

from refpo_warp.algorithms.on_policy import Minibatch, OnPolicyAlgorithm, soft_bound_loss


class PPO(OnPolicyAlgorithm):
    """Clipped-surrogate PPO for rsl_rl's Gaussian (or any distribution) ``MLPModel`` actor."""

    def policy_loss(self, batch: Minibatch) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        st = self.storage
        old_log_prob = st.actions_log_prob.flatten(0, 1)[batch.indices].squeeze(-1)
        old_params = tuple(p.flatten(0, 1)[batch.indices] for p in st.distribution_params)
        self.actor(batch.observations, stochastic_output=True)  # refreshes the actor's distribution
        log_prob = self.actor.get_output_log_prob(batch.actions)
        entropy = self.actor.output_entropy.mean()
        ratio = torch.exp(log_prob - old_log_prob)
        surrogate = torch.max(
            -batch.advantages * ratio, -batch.advantages * ratio.clamp(1.0 - self.clip_param, 1.0 + self.clip_param)
        ).mean()
        loss = surrogate - self.entropy_coef * entropy
        stats = {"surrogate": surrogate, "entropy": entropy}
        if self.bound_coef > 0:
            stats["bound"] = soft_bound_loss(self.actor.output_mean, self.bound)
            loss = loss + self.bound_coef * stats["bound"]
        if self.desired_kl is not None and self.schedule == "adaptive":
            with torch.no_grad():
                stats["approx_kl"] = self.actor.get_kl_divergence(
                    old_params, self.actor.output_distribution_params
                ).mean()
        return loss, stats
