"""Probes of a flow policy's one-step sampler, for ``one_step_analysis.py`` beside it: where a_1(eps) lands against
a_N(eps), against the policy's mean action and against the noise it started from; the velocity error by flow time on the
sampler's own straight paths and on independent pairs; and what the 1-step and N-step policies do in an env from
the same initial states.

A velocity field trained by conditional flow matching on independent pairs (eps, a), eps ~ N(0, I) independent of
a, has at tau = 0 the velocity E[a - eps | x_0 = eps] = E[a] - eps, so one Euler step lands on the policy's mean
action whatever the noise: ``mean_gap`` (the distance of a_1 to the mean of a_N over noises) then goes to 0 while
``one_step_error`` goes to the policy's spread. Straight paths (coupled pairs) give a_1(eps) = a_N(eps) instead.
"""

from __future__ import annotations

import torch

from refpo_warp.models.flow_diagnostics import env_actions


def _noise(rows: int, dim: int, generator: torch.Generator | None, device) -> torch.Tensor:
    return torch.randn(rows, dim, generator=generator, device="cpu").to(device)


@torch.no_grad()
def sampler_probe(
    actor, obs, num_steps: int, transform: str | None, noises: int = 16, generator: torch.Generator | None = None
) -> dict[str, float]:
    """Means over observations, ``noises`` shared noises each and action dimensions, in the env's action space:

    - ``one_step_error``: |a_1(eps) - a_N(eps)|^2; ``policy_spread``: the variance over noises of a_N;
    - ``mean_gap``: |a_1(eps) - mean_eps a_N|^2, the mean over the drawn noises (spread / noises when one step
      gives the policy's mean action: the sampling error of that mean; about the spread when a_1 follows eps);
    - ``one_step_spread``: the variance over noises of a_1 (how much the one-step action still depends on eps);
    - ``saturated_n``, ``saturated_1``: the share of action components beyond [-1, 1] before the transform;
    - ``abs_action_n``, ``abs_action_1``: the mean |action| after it.
    """
    field = actor.velocity
    feat = field.project_obs(actor.encode(obs))
    rows, dim = feat.shape[0], actor.action_dim
    eps = _noise(noises * rows, dim, generator, feat.device)
    feat = feat.repeat(noises, 1)  # noise-major: row j of block k is observation j
    raw_1, raw_n = field.integrate(feat, eps, 1), field.integrate(feat, eps, num_steps)
    one = env_actions(raw_1, transform).reshape(noises, rows, dim)
    many = env_actions(raw_n, transform).reshape(noises, rows, dim)
    return {
        "one_step_error": float((one - many).square().mean()),
        "policy_spread": float(many.var(dim=0).mean()),
        "mean_gap": float((one - many.mean(dim=0)).square().mean()),
        "one_step_spread": float(one.var(dim=0).mean()),
        "saturated_n": float((raw_n.abs() > 1).float().mean()),
        "saturated_1": float((raw_1.abs() > 1).float().mean()),
        "abs_action_n": float(many.abs().mean()),
        "abs_action_1": float(one.abs().mean()),
    }


@torch.no_grad()
def velocity_error_by_tau(
    actor, obs, num_steps: int, taus: list[float], noises: int = 8, generator: torch.Generator | None = None
) -> dict[str, list[float]]:
    """|v(x_tau, tau) - (a - eps)|^2 per flow time (mean over observations, noises and action dimensions), for the
    policy's own N-step samples a = a_N(eps_0):

    - ``own_path``: eps = eps_0, the noise a was integrated from (the coupled pair; 0 at every tau when the sampler's
      paths are straight);
    - ``independent``: eps drawn afresh (the paper's pairs: the CFM residual, never 0 for a spread-out policy).
    """
    rows, dim = obs.batch_size[0], actor.action_dim
    device = actor.encode(obs).device
    obs = obs.repeat(noises) if hasattr(obs, "repeat") else obs
    eps0 = _noise(noises * rows, dim, generator, device)
    feat = actor.velocity.project_obs(actor.encode(obs))
    actions = actor.velocity.integrate(feat, eps0, num_steps)
    fresh = _noise(noises * rows, dim, generator, device)
    out: dict[str, list[float]] = {"tau": list(taus), "own_path": [], "independent": []}
    for tau in taus:
        t = torch.full((noises * rows, 1), float(tau), device=device)
        for key, eps in (("own_path", eps0), ("independent", fresh)):
            error = actor.cfm_terms(obs, actions, t, eps.unsqueeze(1)).velocity_error
            out[key].append(float(error.mean()))
    return out


@torch.no_grad()
def drive(actor, env, flow_steps: int, steps: int, seed: int, initial_noise: str = "random") -> dict[str, torch.Tensor]:
    """Roll the ``flow_steps``-step policy for ``steps`` env steps from the env's reset states (the same states for
    the same env seed), with the sampler's noise drawn from ``seed``; returns the observations (steps + 1, envs, obs),
    the actions and the rewards of every step."""
    obs = env.reset()
    generator = torch.Generator().manual_seed(seed)
    group = next(iter(obs.keys()))
    observations, actions, rewards = [obs[group].clone()], [], []
    for _ in range(steps):
        noise = _noise(env.num_envs, actor.action_dim, generator, env.device)
        if initial_noise == "zero":
            noise = torch.zeros_like(noise)
        action = actor.sample(obs, flow_steps, noise=noise)
        obs, reward, _, _ = env.step(action)
        observations.append(obs[group].clone())
        actions.append(action.clone())
        rewards.append(reward.clone())
    return {"obs": torch.stack(observations), "actions": torch.stack(actions), "rewards": torch.stack(rewards)}
