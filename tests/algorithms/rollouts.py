"""The algorithm unit tests' small pieces (no env): a small flow algorithm, and a rollout of random observations and
rewards in which every step acts, stores a transition, and the returns are computed at the end."""

import torch
from rsl_rl.models import MLPModel
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from refpo_warp.models import FlowActor


def small_flow_algorithm(cls, envs: int, steps: int, obs_dim: int, action_dim: int, actor_kwargs=None, **kwargs):
    """``(cls(...), obs)``: a ReFPO-family algorithm on a 16 x 16 flow actor with 5 Euler steps and a 16-unit critic,
    a storage of ``steps x envs`` and one observation batch (torch seeded with 0 first)."""
    torch.manual_seed(0)
    obs = TensorDict({"policy": torch.randn(envs, obs_dim)}, batch_size=[envs])
    groups = {"actor": ["policy"], "critic": ["policy"]}
    actor = FlowActor(obs, groups, "actor", action_dim, hidden_dims=[16, 16], num_flow_steps=5, **(actor_kwargs or {}))
    critic = MLPModel(obs, groups, "critic", 1, hidden_dims=[16])
    return cls(actor, critic, RolloutStorage("rl", envs, steps, obs, [action_dim]), **kwargs), obs


def random_rollout(alg, steps: int, envs: int, obs_dim: int, seed: int = 1) -> None:
    """Fill ``alg``'s storage with ``steps`` steps of ``envs`` envs: N(0, 1) observations (group ``policy``) and
    rewards, no episode ends."""
    gen = torch.Generator().manual_seed(seed)
    with torch.inference_mode():
        for _ in range(steps):
            obs = TensorDict({"policy": torch.randn(envs, obs_dim, generator=gen)}, batch_size=[envs])
            alg.act(obs)
            alg.process_env_step(obs, torch.randn(envs, generator=gen), torch.zeros(envs, dtype=torch.bool), {})
        alg.compute_returns(obs)
