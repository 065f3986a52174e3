"""Diagnostics of a trained flow policy on on-policy observations: Straightness Error and the velocity Jacobian.

Straightness Error (paper §4.2): the mean of |v(x_tau, tau; o) - (a - eps)|^2 / A over pairs (tau, eps) drawn the
way training draws them, for actions the policy samples at observations o visited by the policy (not only reset
states).

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


def spectral_norms(velocity: Callable, obs_feat: torch.Tensor, x: torch.Tensor, tau: torch.Tensor
                   ) -> tuple[torch.Tensor, torch.Tensor]:  # fmt: skip
    """(||J||_2, ||J||_F) of J = d velocity(obs_feat, x, tau) / dx for each row of x (B, A); exact, by jacrev."""

    def single(feat, xi, ti):
        return velocity(feat.unsqueeze(0), xi.unsqueeze(0), ti.unsqueeze(0)).squeeze(0)

    jac = torch.func.vmap(torch.func.jacrev(single, argnums=1))(obs_feat, x, tau)
    return torch.linalg.matrix_norm(jac, ord=2), torch.linalg.matrix_norm(jac, ord="fro")


@torch.no_grad()
def jacobian_statistics(actor, obs, num_steps: int = 10, threshold: float = JACOBIAN_THRESHOLD) -> dict:
    """Jacobian statistics of ``actor.velocity`` along N-step Euler paths from random noise at observations ``obs``."""
    field = actor.velocity
    obs_feat = field.project_obs(actor.encode(obs))
    x = torch.randn(obs_feat.shape[0], actor.action_dim, device=obs_feat.device)
    dt = 1.0 / num_steps
    spectral, frobenius = [], []
    for k in range(num_steps):
        tau = torch.full((x.shape[0],), k * dt, device=x.device)
        with torch.enable_grad():
            s, f = spectral_norms(field.forward, obs_feat, x, tau)
        spectral.append(s)
        frobenius.append(f)
        x = x + dt * field(obs_feat, x, tau)
    spectral = torch.stack(spectral)  # (N, M)
    frobenius = torch.stack(frobenius)
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
