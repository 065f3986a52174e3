"""The one-step sampler probes against fields whose answers are known in closed form."""

import sys

import pytest
import torch
from tensordict import TensorDict

from refpo_warp.models import FlowActor
from refpo_warp.utils.paths import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "docs" / "results" / "one_step"))  # the probes live beside their analysis script
from one_step_probes import drive, sampler_probe, velocity_error_by_tau

OBS, ACT, ROWS = 3, 2, 256


def actor_with_field(field, obs_dim=OBS):
    """A FlowActor whose velocity prediction is ``field(x, tau)`` (the network bypassed; velocity parameterisation,
    so the prediction is the velocity for the sampler and for the CFM terms alike)."""
    obs = TensorDict({"policy": torch.zeros(1, obs_dim)}, batch_size=[1])
    actor = FlowActor(obs, {"actor": ["policy"]}, "actor", ACT, hidden_dims=[8])
    actor.velocity.predict = lambda feat, x, tau: field(x, tau)
    return actor


def observations(rows=ROWS):
    return TensorDict({"policy": torch.randn(rows, OBS, generator=torch.Generator().manual_seed(0))}, batch_size=[rows])


def gaussian_marginal_field(m: float, s: float):
    """The exact CFM (independent-pair) field between N(0, 1) and N(m, s^2) per dimension: E[a - eps | x_tau = x] =
    m + (tau s^2 - (1 - tau)) / ((1 - tau)^2 + tau^2 s^2) (x - tau m)."""

    def field(x, tau):
        t = tau.unsqueeze(-1) if tau.dim() == x.dim() - 1 else tau
        return m + (t * s**2 - (1 - t)) / ((1 - t) ** 2 + t**2 * s**2) * (x - t * m)

    return field


def test_the_marginal_fields_one_step_lands_on_the_mean_action_for_every_noise():
    m, s = 0.4, 0.3
    actor = actor_with_field(gaussian_marginal_field(m, s))
    probe = sampler_probe(
        actor, observations(), num_steps=50, transform=None, noises=16, generator=torch.Generator().manual_seed(1)
    )
    # at tau = 0 the field is m - x: one Euler step gives exactly m, whatever eps
    assert probe["one_step_spread"] == pytest.approx(0.0, abs=1e-10)
    assert probe["abs_action_1"] == pytest.approx(m, rel=1e-6)
    # 50 Euler steps of the exact field give (close to) N(m, s^2): spread s^2, and a_1 = m sits at its mean, up to
    # the sampling error of a mean over 16 noises (s^2 / 16)
    assert probe["policy_spread"] == pytest.approx(s**2, rel=0.1)
    assert probe["mean_gap"] == pytest.approx(s**2 / 16, rel=0.3)
    assert probe["one_step_error"] == pytest.approx(probe["policy_spread"], rel=0.15)


def test_a_constant_field_is_straight_on_its_own_paths_and_not_on_independent_pairs():
    # v = c: a = eps_0 + c. Own path: v - (a - eps_0) = 0 at every tau. Independent eps: v - (a - eps) = eps - eps_0,
    # whose mean square per dimension is 2 (two independent standard normals).
    actor = actor_with_field(lambda x, tau: torch.full_like(x, 0.7))
    taus = [0.0, 0.5, 0.9]
    out = velocity_error_by_tau(actor, observations(), 10, taus, noises=8, generator=torch.Generator().manual_seed(2))
    assert out["tau"] == taus
    assert out["own_path"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-10)
    assert out["independent"] == pytest.approx([2.0, 2.0, 2.0], rel=0.1)
    probe = sampler_probe(actor, observations(), 10, None, generator=torch.Generator().manual_seed(3))
    assert probe["one_step_error"] == pytest.approx(0.0, abs=1e-10)
    # a_1 = eps_0 + c, not the mean: |eps_0 - mean of 16 eps|^2 = (1 - 1/16) per dimension
    assert probe["mean_gap"] == pytest.approx(15 / 16, rel=0.15)


def test_saturation_is_counted_before_the_transform_and_actions_after_it():
    actor = actor_with_field(lambda x, tau: torch.full_like(x, 3.0))  # a = eps + 3: almost always beyond 1
    probe = sampler_probe(actor, observations(), 10, "clip", generator=torch.Generator().manual_seed(4))
    assert probe["saturated_1"] == probe["saturated_n"] > 0.97
    assert probe["abs_action_1"] <= 1.0 and probe["abs_action_n"] > 0.97


def test_drive_plays_the_same_starts_with_the_same_noise():
    from refpo_warp.envs.registry import make_env

    def point_mass():
        return make_env("dmc_point_mass", num_envs=4, device="cpu", seed=5)

    # v = 0.2: a = x_0 + 0.2 whatever the number of steps, so N = 1 and N = 10 act alike only on the same noise
    actor = actor_with_field(lambda x, tau: torch.full_like(x, 0.2), obs_dim=4)
    runs = [drive(actor, point_mass(), n, 6, seed=0) for n in (1, 10)]
    assert runs[0]["obs"].shape == (7, 4, 4) and runs[0]["actions"].shape == (6, 4, 2)
    gen = torch.Generator().manual_seed(0)
    noise = torch.stack([torch.randn(4, 2, generator=gen) for _ in range(6)])  # seed 0's draws, one per step
    for run in runs:
        torch.testing.assert_close(run["actions"], noise + 0.2)
    torch.testing.assert_close(runs[0]["obs"], runs[1]["obs"])  # same starts, same actions: the same path
    still = drive(actor_with_field(lambda x, tau: -x, obs_dim=4), point_mass(), 1, 6, seed=0)  # a = 0 after 1 step
    torch.testing.assert_close(still["obs"][0], runs[0]["obs"][0])  # the env seed's starts
    assert still["actions"].abs().max() < 1e-6
    torch.testing.assert_close(still["obs"][-1, :, 2:], torch.zeros(4, 2), atol=1e-6, rtol=0)  # never moved
