"""GridWorld benchmark: the Warp env against the same dynamics in numpy under gymnasium's SyncVectorEnv.

    refpo bench gridworld [--num-envs 4096] [--device auto] [--gym-steps 20]

Action latency and update time on the GridWorld config: ``refpo bench latency --tasks gridworld`` and
``refpo bench algorithms --task gridworld``.
"""

from __future__ import annotations

import time

import numpy as np
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.utils.command_line import Flag, parse_flags, usage
from refpo_warp.utils.device import resolve_device
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


FLAGS = (
    Flag("--num-envs", int, "envs of both", default=4096),
    Flag("--device", str, "auto, cpu or cuda:N", default="auto"),
    Flag("--gym-steps", int, "timed steps of the gymnasium baseline", default=20),
)
USAGE = usage("refpo bench gridworld [flags]", __doc__.split("\n\n")[0], FLAGS)


def main(argv: list[str]) -> None:
    args, _ = parse_flags("bench gridworld", argv, FLAGS, renamed={"--envs": "--num-envs"})
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
