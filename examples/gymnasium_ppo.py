#!/usr/bin/env python
"""Train a gymnasium-API agent on a Warp env: a small PPO in plain torch that sees only gymnasium's vector API.

    python examples/gymnasium_ppo.py                     # GridWorld, 64 envs, 30-step episodes: ~7 s on one CPU core
    python examples/gymnasium_ppo.py --iterations 100 --num-envs 256

The env is ``refpo_warp.envs.gym_adapter.GymVectorEnv`` (with same-step autoreset) wrapped in gymnasium's
``RecordEpisodeStatistics``; the agent uses ``reset``/``step``, the spaces, ``infos["final_obs"]`` (to bootstrap the
value of time-outs from the observation that ended the episode, not from the next episode's first one) and
``infos["episode"]``. Nothing here is refpo_warp-specific beyond building the env.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
import torch
from gymnasium.vector import AutoresetMode
from gymnasium.wrappers.vector import RecordEpisodeStatistics
from torch import nn

from refpo_warp import make_env
from refpo_warp.envs.gym_adapter import GymVectorEnv


def mlp(inputs: int, outputs: int, hidden: int = 64) -> nn.Sequential:
    return nn.Sequential(
        nn.Linear(inputs, hidden), nn.Tanh(), nn.Linear(hidden, hidden), nn.Tanh(), nn.Linear(hidden, outputs)
    )


class Agent(nn.Module):
    """Gaussian policy (state-independent std) and a value function, both small MLPs."""

    def __init__(self, obs_dim: int, act_dim: int) -> None:
        super().__init__()
        self.mean, self.value = mlp(obs_dim, act_dim), mlp(obs_dim, 1)
        self.log_std = nn.Parameter(torch.zeros(act_dim))

    def dist(self, obs: torch.Tensor) -> torch.distributions.Normal:
        return torch.distributions.Normal(self.mean(obs), self.log_std.exp())


def value_of_reached_state(agent: Agent, next_obs: np.ndarray, terminated: np.ndarray, infos: dict) -> torch.Tensor:
    """V(s_{t+1}) for the state each env actually reached: ``final_obs`` where an episode ended (same-step
    autoreset), 0 where it terminated (no future), so time-outs are bootstrapped and terminations are not."""
    reached = next_obs.copy()
    if "final_obs" in infos:
        ended = infos["_final_obs"]
        reached[ended] = np.stack(infos["final_obs"][ended])
    with torch.no_grad():
        values = agent.value(torch.from_numpy(reached)).squeeze(-1)
    return values * torch.from_numpy(~terminated).float()


def ppo_update(agent, optimizer, batch: dict, epochs: int = 4, minibatches: int = 4, clip: float = 0.2) -> None:
    n = batch["obs"].shape[0]
    for _ in range(epochs):
        for idx in torch.randperm(n).chunk(minibatches):
            dist = agent.dist(batch["obs"][idx])
            ratio = (dist.log_prob(batch["actions"][idx]).sum(-1) - batch["logp"][idx]).exp()
            adv = batch["advantages"][idx]
            adv = (adv - adv.mean()) / (adv.std() + 1e-8)
            policy_loss = -torch.min(ratio * adv, ratio.clamp(1 - clip, 1 + clip) * adv).mean()
            value_loss = (agent.value(batch["obs"][idx]).squeeze(-1) - batch["returns"][idx]).pow(2).mean()
            optimizer.zero_grad()
            (policy_loss + 0.5 * value_loss).backward()
            nn.utils.clip_grad_norm_(agent.parameters(), 1.0)
            optimizer.step()


def train(
    task: str = "gridworld",
    num_envs: int = 64,
    steps: int = 32,
    iterations: int = 60,
    seed: int = 0,
    gamma: float = 0.99,
    lam: float = 0.95,
    lr: float = 3e-4,
    max_episode_length: int = 30,
    quiet: bool = False,
) -> list[float]:
    """Run PPO; returns the mean episode return of each iteration (NaN where no episode ended)."""
    torch.manual_seed(seed)
    warp_env = make_env(task, num_envs=num_envs, device="cpu", seed=seed, max_episode_length=max_episode_length)
    env = RecordEpisodeStatistics(GymVectorEnv(warp_env, autoreset_mode=AutoresetMode.SAME_STEP))  # final_obs
    agent = Agent(env.single_observation_space.shape[0], env.single_action_space.shape[0])
    optimizer = torch.optim.Adam(agent.parameters(), lr=lr)
    low, high = env.single_action_space.low, env.single_action_space.high
    obs, _ = env.reset(seed=seed)
    history = []
    for it in range(iterations):
        rollout = {k: [] for k in ("obs", "actions", "logp", "values", "rewards", "next_values", "dones")}
        returns = []
        for _ in range(steps):
            obs_t = torch.from_numpy(obs)
            with torch.no_grad():
                dist = agent.dist(obs_t)
                actions = dist.sample()
                rollout["logp"].append(dist.log_prob(actions).sum(-1))
                rollout["values"].append(agent.value(obs_t).squeeze(-1))
            obs, rewards, terminated, truncated, infos = env.step(np.clip(actions.numpy(), low, high))
            rollout["obs"].append(obs_t)
            rollout["actions"].append(actions)
            rollout["rewards"].append(torch.from_numpy(rewards).float())
            rollout["next_values"].append(value_of_reached_state(agent, obs, terminated, infos))
            rollout["dones"].append(torch.from_numpy(terminated | truncated).float())
            if "episode" in infos:
                returns.extend(infos["episode"]["r"][infos["_episode"]].tolist())
        data = {k: torch.stack(v) for k, v in rollout.items()}
        # GAE over the rollout; an episode boundary cuts the chain (the next step belongs to a new episode).
        advantages = torch.zeros_like(data["rewards"])
        running = torch.zeros(num_envs)
        for t in reversed(range(steps)):
            delta = data["rewards"][t] + gamma * data["next_values"][t] - data["values"][t]
            running = delta + gamma * lam * (1.0 - data["dones"][t]) * running
            advantages[t] = running
        batch = {
            "obs": data["obs"].flatten(0, 1),
            "actions": data["actions"].flatten(0, 1),
            "logp": data["logp"].flatten(),
            "advantages": advantages.flatten(),
            "returns": (advantages + data["values"]).flatten(),
        }
        ppo_update(agent, optimizer, batch)
        history.append(float(np.mean(returns)) if returns else float("nan"))
        if not quiet:
            print(
                f"iteration {it:3d}/{iterations - 1}  episodes {len(returns):4d}  mean return {history[-1]:6.2f}",
                flush=True,
            )
    env.close()
    return history


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", default="gridworld")
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--steps", type=int, default=32, help="env steps per iteration")
    parser.add_argument("--iterations", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-episode-length", type=int, default=30)
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    train(args.task, args.num_envs, args.steps, args.iterations, args.seed, max_episode_length=args.max_episode_length)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
