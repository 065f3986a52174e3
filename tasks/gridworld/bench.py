"""GridWorld benchmark: the Warp env against the same dynamics in numpy under gymnasium's SyncVectorEnv.

    refpo bench gridworld [num_envs=4096] [device=auto] [gym_steps=20]

Action latency and update time on the GridWorld config: ``refpo bench latency tasks=gridworld`` and
``refpo bench algorithms task=gridworld``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.option_rules import DEVICE_DOC, DEVICE_RULE, Int
from refpo_warp.utils.options import option
from refpo_warp.utils.timing import env_steps_per_second, print_table


def gym_steps_per_second(num_envs: int, steps: int) -> float:
    """The same dynamics as a numpy gymnasium env, vectorised by gymnasium's SyncVectorEnv."""
    import gymnasium as gym

    from refpo_warp.tasks.gridworld.gym_env import GridWorldGymEnv

    envs = gym.vector.SyncVectorEnv([GridWorldGymEnv for _ in range(num_envs)])
    envs.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, size=(8, num_envs, 2)).astype(np.float32)
    envs.step(actions[0])
    start = time.perf_counter()
    for i in range(steps):
        envs.step(actions[i % 8])
    elapsed = time.perf_counter() - start
    envs.close()
    return steps * num_envs / elapsed


@dataclass(frozen=True)
class Options:
    num_envs: int = option(4096, Int(1, 1 << 22), "envs of both")
    device: str = option("auto", DEVICE_RULE, DEVICE_DOC)
    gym_steps: int = option(20, Int(1), "timed steps of the gymnasium baseline")


def run(args: Options, _: dict | None = None) -> None:
    device = resolve_device(args.device)
    print(f"GridWorld benchmark on {device}, {args.num_envs} envs, torch threads {torch.get_num_threads()}", flush=True)

    env = make_env("gridworld", num_envs=args.num_envs, device=device)
    warp_sps = env_steps_per_second(env, steps=500)
    gym_sps = gym_steps_per_second(args.num_envs, args.gym_steps)
    print_table(
        [
            {"env": "refpo_warp GridWorld (Warp kernel)", "env steps/s": f"{warp_sps:,.0f}"},
            {"env": "gymnasium SyncVectorEnv (numpy)", "env steps/s": f"{gym_sps:,.0f}"},
            {"env": "speed-up", "env steps/s": f"{warp_sps / gym_sps:,.0f}x"},
        ],
        ["env", "env steps/s"],
        title=f"Env steps per second, {args.num_envs} envs, uniform random actions",
    )
