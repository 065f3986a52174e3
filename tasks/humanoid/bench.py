"""Env-stepping throughput of the humanoid tracking env: ``python tools/bench.py humanoid [--num-envs N] ...``.

Timed with ``refpo_warp.benchmarking.env_steps_per_second``: uniform random actions in [-1, 1] drawn ahead of time,
after warm-up steps (the first step compiles kernels and captures the step graph); counts env steps per second
including resets of finished episodes. Defaults: 64 envs on CPU, 4096 on CUDA.
"""

from __future__ import annotations

import argparse
import json
import time

import torch

from refpo_warp.benchmarking import env_steps_per_second
from refpo_warp.device import resolve_device
from refpo_warp.registry import make_env


class _CountEpisodes:
    """The env's stepping interface, adding each step's finished episodes to a device counter (no host sync)."""

    def __init__(self, env) -> None:
        self.env, self.device, self.num_envs, self.num_actions = env, env.device, env.num_envs, env.num_actions
        self.ended = torch.zeros((), dtype=torch.int64, device=env.device)

    def step(self, actions: torch.Tensor):
        out = self.env.step(actions)
        self.ended += out[2].sum()
        return out


def measure(task: str, num_envs: int, device: str, steps: int, warmup: int, seed: int = 0, **env_cfg) -> dict:
    """Build the env, warm up, then time ``steps`` random-action steps; returns the measured numbers."""
    start = time.perf_counter()
    env = make_env(task, num_envs=num_envs, device=device, seed=seed, **env_cfg)
    build_s = time.perf_counter() - start
    start = time.perf_counter()
    if warmup > 0:
        env_steps_per_second(env, steps=warmup, warmup=0, seed=seed)
    warmup_s = time.perf_counter() - start
    counted = _CountEpisodes(env)
    rate = env_steps_per_second(counted, steps=steps, warmup=0, seed=seed)
    return {
        "task": task, "device": env.device, "num_envs": num_envs, "steps": steps,
        "env_steps_per_s": rate, "ms_per_step": 1e3 * num_envs / rate,
        "episodes_ended": int(counted.ended), "build_s": build_s, "warmup_s": warmup_s,
        "graph_captured": env._graph is not None,
    }  # fmt: skip


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="tools/bench.py humanoid", description=__doc__.split("\n\n")[0])
    parser.add_argument("--task", default="humanoid_all")
    parser.add_argument("--device", default="auto")
    parser.add_argument("--num-envs", type=int, default=None, help="default: 64 on CPU, 4096 on CUDA")
    parser.add_argument("--steps", type=int, default=None, help="timed steps (default: 30 on CPU, 300 on CUDA)")
    parser.add_argument("--warmup", type=int, default=3)
    parser.add_argument("--json", action="store_true", help="print the result as one JSON line")
    args = parser.parse_args(argv)

    device = resolve_device(args.device)
    cpu = device == "cpu"
    num_envs = args.num_envs or (64 if cpu else 4096)
    steps = args.steps or (30 if cpu else 300)
    result = measure(args.task, num_envs, device, steps, args.warmup)
    if args.json:
        print(json.dumps(result))
        return
    print(f"{result['task']} on {result['device']}: {num_envs} envs, {steps} steps after {args.warmup} warm-up "
          f"(graph captured: {result['graph_captured']})")  # fmt: skip
    print(f"  {result['env_steps_per_s']:,.0f} env steps/s ({result['ms_per_step']:.1f} ms per step, "
          f"{result['episodes_ended']} episodes ended); build {result['build_s']:.1f} s, "
          f"warm-up {result['warmup_s']:.1f} s")  # fmt: skip


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
