"""Coupled Reflow: the rollout keeps each action's initial noise, the term on a hand-made batch is its formula, and on
a 1-D toy target coupled pairs make the 1-step sample land where the N-step one does, where independent pairs do not."""

import copy

import pytest
import torch
from rollouts import random_rollout, small_flow_algorithm  # tests/algorithms/rollouts.py
from tensordict import TensorDict

from refpo_warp.algorithms import ReFPO
from refpo_warp.algorithms.reflow_schedule import ReflowSchedule
from refpo_warp.models import FlowActor
from refpo_warp.models.flow_diagnostics import one_step_consistency

N, T, OBS, ACT = 6, 3, 4, 2


def build(**kwargs) -> ReFPO:
    return small_flow_algorithm(
        ReFPO, N, T, OBS, ACT, num_mc_samples=3, num_learning_epochs=1, num_mini_batches=1, **kwargs
    )[0]


def test_the_coupled_term_on_a_batch_is_the_cfm_error_of_the_rollouts_own_pairs():
    alg = build(reflow_pairs="coupled")
    random_rollout(alg, T, N, OBS)
    alg.before_update()
    batch = next(iter(alg.minibatches()))
    _, stats = alg.policy_loss(batch)
    tau, eps0, a = batch.field("tau"), batch.field("eps0"), batch.actions  # (B, K), (B, A), (B, A)
    t = tau.unsqueeze(-1)
    x = (1 - t) * eps0.unsqueeze(1) + t * a.unsqueeze(1)  # x_tau on the straight path from eps_0 to a
    feat = alg.actor.velocity.project_obs(alg.actor.encode(batch.observations))
    v = alg.actor.velocity(
        feat.unsqueeze(1).expand(-1, tau.shape[1], -1).reshape(-1, feat.shape[-1]), x.reshape(-1, ACT), tau.reshape(-1)
    ).reshape(x.shape)
    expected = (v - (a - eps0).unsqueeze(1)).square().mean()
    torch.testing.assert_close(stats["reflow"], expected, rtol=1e-5, atol=1e-6)
    independent = build()
    random_rollout(independent, T, N, OBS)
    independent.before_update()
    assert "eps0" not in independent.store  # stored only where the coupled term uses it


def test_every_rollout_action_is_the_flow_of_its_stored_noise_with_chunks_and_resets():
    """GridWorld with 2-move action chunks and 3-step episodes (resets inside the rollout): each stored action is the
    N-step Euler sample of its observation from its stored eps_0 (no post-sample perturbation here)."""
    from refpo_warp.benchmarks.update_time import fill_rollout
    from refpo_warp.config.resolve import resolve
    from refpo_warp.runner.build import build_runner

    run = resolve(
        [
            "task=gridworld",
            "algo=refpo",
            "device=cpu",
            "num_envs=4",
            "runner.num_steps_per_env=6",
            "env.action_chunk=2",
            "env.max_episode_length=3",
            "algorithm.reflow_pairs=coupled",
            "algorithm.num_mc_samples=2",
            "eval.interval=0",
        ]
    )
    env, runner = build_runner(run, None)
    alg = runner.alg
    fill_rollout(env, alg)
    obs, actions = alg.storage.observations.flatten(0, 1), alg.storage.actions.flatten(0, 1)
    eps0 = alg.store.flat("eps0")
    assert eps0.shape == actions.shape == (6 * 4, 4)  # every action of the rollout, a whole chunk each
    with torch.no_grad():
        again = alg.actor.velocity.integrate(
            alg.actor.velocity.project_obs(alg.actor.encode(obs)), eps0, alg.actor.num_flow_steps
        )
    torch.testing.assert_close(again, actions)
    assert alg.storage.dones.any()  # the rollout did cross episode ends


def test_coupled_pairs_make_one_step_land_where_n_steps_do_on_a_bimodal_toy():
    """a in {-1, +1} at one observation: CFM on independent pairs learns crossing (curved) Euler paths, so one step
    lands between the modes; regressing on the policy's own (eps_0, a_N(eps_0)) pairs straightens them."""
    torch.manual_seed(0)
    batch = 256
    obs = TensorDict({"policy": torch.zeros(batch, 2)}, batch_size=[batch])
    actor = FlowActor(obs[:1], {"actor": ["policy"]}, "actor", 1, hidden_dims=[64, 64], num_flow_steps=10)

    def fit(model, steps: int, coupled: bool) -> None:
        opt = torch.optim.Adam(model.parameters(), lr=3e-3)
        for _ in range(steps):
            if coupled:
                with torch.no_grad():
                    a = model.sample(obs)  # a rollout: the policy's own actions and the noise each came from
                    eps = model._last_noise.unsqueeze(1)
            else:
                a = torch.where(torch.rand(batch, 1) < 0.5, -1.0, 1.0)
                eps = torch.randn(batch, 1, 1)
            loss = model.cfm_terms(obs, a, torch.rand(batch, 1), eps).velocity_error.mean()
            opt.zero_grad()
            loss.backward()
            opt.step()

    fit(actor, 200, coupled=False)
    independent, coupled = copy.deepcopy(actor), copy.deepcopy(actor)
    fit(independent, 200, coupled=False)
    fit(coupled, 200, coupled=True)
    errors = [
        one_step_consistency(m, obs, 10, generator=torch.Generator().manual_seed(1))["one_step_error"]
        for m in (independent, coupled)
    ]
    assert errors[0] > 0.3 and errors[1] < 0.2 * errors[0], errors


def test_the_adaptive_coefficient_moves_only_outside_the_band_and_stays_in_its_range():
    schedule = ReflowSchedule("adaptive", target=0.25, coef_range=(0.01, 0.2))
    assert schedule.start(0.04) == 0.04 and schedule.start(1.0) == 0.2
    assert schedule.step(0.04, 0.25) == 0.04 and schedule.step(0.04, 0.13) == 0.04  # inside [target / 2, 2 target]
    assert schedule.step(0.04, 0.6) == pytest.approx(0.06) and schedule.step(0.04, 0.1) == pytest.approx(0.04 / 1.5)
    assert schedule.step(0.19, 5.0) == 0.2 and schedule.step(0.011, 0.0) == 0.01
    assert ReflowSchedule("fixed").step(0.04, 100.0) == 0.04


def test_an_adaptive_run_logs_its_coefficient_and_one_step_statistics_every_update():
    alg = build(reflow_schedule="adaptive", one_step_states=8)
    random_rollout(alg, T, N, OBS)
    out = alg.update()
    assert {"Flow/one_step_error", "Flow/policy_spread", "Flow/one_step_ratio", "Flow/reflow_coef"} <= out.keys()
    # the first update's lambda is 0.04 moved once by the rule: x 1.5 above 2 x target (0.25), / 1.5 below target / 2
    ratio = out["Flow/one_step_ratio"]
    expected = 0.04 * 1.5 if ratio > 0.5 else 0.04 / 1.5 if ratio < 0.125 else 0.04
    assert out["Flow/reflow_coef"] == pytest.approx(expected), ratio
    raised = build(reflow_schedule="adaptive", one_step_states=8, one_step_target=1e-6)  # every ratio is above
    random_rollout(raised, T, N, OBS)
    assert raised.update()["Flow/reflow_coef"] == pytest.approx(0.06)
    with pytest.raises(ValueError, match="one_step_states"):
        build(reflow_schedule="adaptive", one_step_states=0)
