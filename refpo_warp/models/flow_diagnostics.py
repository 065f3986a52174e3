"""Diagnostics of a flow policy on on-policy observations: Straightness Error, one-step consistency, the velocity
Jacobian.

Straightness Error (paper §4.2): the mean of |v(x_tau, tau; o) - (a - eps)|^2 / A over pairs (tau, eps) drawn the
way training draws them, for actions the policy samples at observations o visited by the policy (not only reset
states). It measures the CFM residual on fresh, independent (eps, a) pairs, not the paths the sampler takes.

One-step consistency (ours, ``docs/algorithms.md``): with the same initial noise eps for both, the mean over
observations, noises and action dimensions of |T(a_1(eps)) - T(a_N(eps))|^2, where a_n(eps) is the n-step Euler
sample and T the env's action transform (tanh or a clip to [-1, 1]: the env's action space). It is 0 exactly when one
Euler step lands where N steps do, i.e. on the sampler's own paths. Beside it, the policy's spread: the variance over
noises of T(a_N) at one observation, averaged over observations and dimensions, and their ratio (scale-free).

Jacobian diagnostics (paper Appendix C; the definitions are our choice, ``docs/algorithms.md``): the spatial
Jacobian J = dv/dx (A x A, output scale included) at the points where the N-step Euler sampler evaluates v, i.e.
(x_k, tau_k = k/N) for k < N from x_0 ~ N(0, I). Its spectral norm ||J||_2 is the operator norm in the one-step
Euler error bound h^2/2 (|d_tau v| + ||J|| |v|). Reported: the mean and 95th percentile of ||J||_2, the fraction
of points with ||J||_2 > ``threshold`` (Jac. Expl.; 2.0, where a step of h = 1 can amplify errors), the mean of
||J||_F / sqrt(A), and the mean spectral norm per tau_k.
"""

from __future__ import annotations

from collections.abc import Callable

import torch

JACOBIAN_THRESHOLD = 2.0
JACOBIAN_CHUNK = 64  # rows per vmap of jacrev: its memory grows with rows x A^2 x the network's activations
ACTION_TRANSFORMS = ("tanh", "clip", None)


def env_actions(actions: torch.Tensor, transform: str | None) -> torch.Tensor:
    """Actions as the env applies them: tanh, a clip to [-1, 1], or unchanged (None)."""
    if transform == "tanh":
        return torch.tanh(actions)
    if transform == "clip":
        return actions.clamp(-1.0, 1.0)
    if transform is None:
        return actions
    raise ValueError(f"action transform must be one of {ACTION_TRANSFORMS}, got {transform!r}")


def spectral_norms(
    velocity: Callable, obs_feat: torch.Tensor, x: torch.Tensor, tau: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """(||J||_2, ||J||_F) of J = d velocity(obs_feat, x, tau) / dx for each row of x (B, A); exact, by jacrev."""

    def single(feat, xi, ti):
        return velocity(feat.unsqueeze(0), xi.unsqueeze(0), ti.unsqueeze(0)).squeeze(0)

    jacobian = torch.func.vmap(torch.func.jacrev(single, argnums=1))
    spectral, frobenius = [], []
    for i in range(0, x.shape[0], JACOBIAN_CHUNK):  # exact per row, so chunking changes no number
        jac = jacobian(obs_feat[i : i + JACOBIAN_CHUNK], x[i : i + JACOBIAN_CHUNK], tau[i : i + JACOBIAN_CHUNK])
        # jac carries a graph to the network's parameters: keep only the norms' values, so each chunk's graph goes
        spectral.append(torch.linalg.matrix_norm(jac, ord=2).detach())
        frobenius.append(torch.linalg.matrix_norm(jac, ord="fro").detach())
        del jac  # before the next chunk's, so that one chunk's memory at most is live
    return torch.cat(spectral), torch.cat(frobenius)


@torch.no_grad()
def jacobian_statistics(actor, obs, num_steps: int = 10, threshold: float = JACOBIAN_THRESHOLD) -> dict:
    """Jacobian statistics of ``actor.velocity`` along N-step Euler paths from random noise at observations ``obs``."""
    field = actor.velocity
    obs_feat = field.project_obs(actor.encode(obs))
    x = torch.randn(obs_feat.shape[0], actor.action_dim, device=obs_feat.device)
    dt = 1.0 / num_steps
    spectral_steps, frobenius_steps = [], []
    for k in range(num_steps):
        tau = torch.full((x.shape[0],), k * dt, device=x.device)
        with torch.enable_grad():
            s, f = spectral_norms(field.forward, obs_feat, x, tau)
        spectral_steps.append(s)
        frobenius_steps.append(f)
        x = x + dt * field(obs_feat, x, tau)
    spectral = torch.stack(spectral_steps)  # (N, M)
    frobenius = torch.stack(frobenius_steps)
    flat = spectral.flatten()
    return {
        "jacobian_norm_mean": float(flat.mean()),
        "jacobian_norm_p95": float(torch.quantile(flat, 0.95)),
        "jacobian_explosion_rate": float((flat > threshold).float().mean()),
        "jacobian_fro_norm_mean": float(frobenius.mean() / actor.action_dim**0.5),
        "jacobian_norm_by_tau": [float(v) for v in spectral.mean(dim=1)],
    }


@torch.no_grad()
def straightness_error(actor, obs, sample_tau: Callable[[tuple[int, ...]], torch.Tensor], num_pairs: int = 8) -> float:
    """Mean |v - (a - eps)|^2 / A on ``num_pairs`` pairs per observation, actions sampled as in a rollout."""
    actions = actor.sample(obs, initial_noise="random", perturbation=True)
    n = actions.shape[0]
    tau = sample_tau((n, num_pairs)).to(actions.device)
    eps = torch.randn(n, num_pairs, actions.shape[1], device=actions.device)
    return float(actor.cfm_terms(obs, actions, tau, eps).velocity_error.mean())


@torch.no_grad()
def one_step_consistency(
    actor, obs, num_steps: int, transform: str | None = None, noises: int = 4, generator: torch.Generator | None = None
) -> dict[str, float]:
    """One-step error, policy spread and their ratio at observations ``obs`` (see the module docstring): ``noises``
    shared initial noises per observation, drawn from ``generator`` (so a caller's random stream is left alone)."""
    field = actor.velocity
    feat = field.project_obs(actor.encode(obs))
    rows, dim = feat.shape[0], actor.action_dim
    eps = torch.randn(noises * rows, dim, generator=generator, device="cpu").to(feat.device)
    feat = feat.repeat(noises, 1)  # noise-major: row j of block k is observation j
    one = env_actions(field.integrate(feat, eps, 1), transform).reshape(noises, rows, dim)
    many = env_actions(field.integrate(feat, eps, num_steps), transform).reshape(noises, rows, dim)
    error = float((one - many).square().mean())
    spread = float(many.var(dim=0).mean()) if noises > 1 else float("nan")  # unbiased over the noises
    return {"one_step_error": error, "policy_spread": spread, "one_step_ratio": error / max(spread, 1e-12)}
