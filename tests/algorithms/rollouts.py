"""A rollout of random observations and rewards for an algorithm's unit tests (no env): every step acts, stores a
transition, and the returns are computed at the end."""

import torch
from tensordict import TensorDict


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
