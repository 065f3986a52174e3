"""GridWorld benchmark: Warp env vs gymnasium SyncVectorEnv, action latency N=1 vs N=10, ReFPO vs FPO update time.

    python tools/bench.py gridworld [--envs 4096] [--device auto]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import time

import numpy as np
import torch
from tensordict import TensorDict

from refpo_warp.benchmarking import env_steps_per_second, print_table, time_call
from refpo_warp.device import resolve_device
from refpo_warp.registry import make_env


def gym_steps_per_second(num_envs: int, steps: int) -> float:
    """The same dynamics as a numpy gymnasium env, vectorised by gymnasium's SyncVectorEnv."""
    import gymnasium as gym

    from tasks.gridworld.gym_env import GridWorldGymEnv

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


def build_algorithm(reflow_coef: float, device: str, num_envs: int):
    """ReFPO with the paper's GridWorld settings (task config) on a filled rollout, ready for update()."""
    from refpo_warp.config import resolve_config
    from refpo_warp.runner_setup import build_runner

    cfg = resolve_config(["task=gridworld", f"algorithm.reflow_coef={reflow_coef}", f"device={device}",
                          f"num_envs={num_envs}"])  # fmt: skip
    with contextlib.redirect_stdout(io.StringIO()):  # rsl_rl prints the model structure
        env, runner = build_runner(cfg, None)
    return env, runner.alg


def fill_rollout(env, alg) -> None:
    obs = env.get_observations()
    with torch.inference_mode():
        for _ in range(alg.storage.num_transitions_per_env):
            actions = alg.act(obs)
            obs, rew, dones, extras = env.step(actions)
            alg.process_env_step(obs, rew, dones, extras)
        alg.compute_returns(obs)


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="bench.py gridworld", description=__doc__)
    parser.add_argument("--envs", type=int, default=4096)
    parser.add_argument("--device", default="auto")
    parser.add_argument("--gym-steps", type=int, default=20)
    args = parser.parse_args(argv)
    device = resolve_device(args.device)
    print(f"GridWorld benchmark on {device}, {args.envs} envs, torch threads {torch.get_num_threads()}", flush=True)

    env = make_env("gridworld", num_envs=args.envs, device=device)
    warp_sps = env_steps_per_second(env, steps=500)
    gym_sps = gym_steps_per_second(args.envs, args.gym_steps)
    print_table([
        {"env": "refpo_warp GridWorld (Warp kernel)", "env steps/s": f"{warp_sps:,.0f}"},
        {"env": "gymnasium SyncVectorEnv (numpy)", "env steps/s": f"{gym_sps:,.0f}"},
        {"env": "speed-up", "env steps/s": f"{warp_sps / gym_sps:,.0f}x"},
    ], ["env", "env steps/s"], title=f"Env steps per second, {args.envs} envs, uniform random actions")  # fmt: skip

    env, alg = build_algorithm(0.1, device, 16)
    actor = alg.get_policy().eval()
    obs = TensorDict({"policy": torch.rand(args.envs, 2, device=device) * 2 - 1}, batch_size=[args.envs])
    rows = []
    for n in (1, 10):
        actor.num_flow_steps = n
        with torch.inference_mode():
            latency = time_call(lambda: actor(obs, stochastic_output=True), device=device)
        rows.append({"flow steps N": n, f"latency for {args.envs} obs (ms)": f"{latency * 1e3:.3f}"})
    ratio = float(rows[1][list(rows[1])[1]]) / float(rows[0][list(rows[0])[1]])
    print_table(rows, ["flow steps N", f"latency for {args.envs} obs (ms)"], title="Action latency, N = 1 vs N = 10",
                notes=(f"N=10 / N=1 latency ratio: {ratio:.1f}x",))  # fmt: skip

    update_times = {}
    for name, coef in (("FPO", 0.0), ("ReFPO", 0.1)):
        torch.manual_seed(0)
        env, alg = build_algorithm(coef, device, 16)
        times = []
        for _ in range(3):
            fill_rollout(env, alg)
            start = time.perf_counter()
            alg.update()
            times.append(time.perf_counter() - start)
        update_times[name] = sorted(times)[1]
    ratio = update_times["ReFPO"] / update_times["FPO"]
    print_table([{"algorithm": k, "update time (s)": f"{v:.3f}"} for k, v in update_times.items()],
                ["algorithm", "update time (s)"], title="Update time, GridWorld config (16 envs), median of 3",
                notes=(f"ReFPO / FPO update-time ratio: {ratio:.3f}",))  # fmt: skip
