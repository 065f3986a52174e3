"""Env-stepping throughput of the humanoid tracking env: ``refpo bench humanoid [num_envs=N] ...``.

Ours: timed with ``refpo_warp.utils.timing.env_steps_per_second``: uniform random actions in [-1, 1] drawn ahead of
time, after warm-up steps (the first step compiles kernels and captures the step graph). One env step is the whole
captured step: PD targets from the actions, the physics substeps (MuJoCo Warp), reference sampling, reward /
termination / episode metrics, new episodes for finished envs and the observations. Defaults: 64 envs on CPU, 4096
on CUDA.

Anchor, in the same run: MuJoCo C (``mujoco.rollout``, one thread, as Warp's CPU backend) stepping the model our
simulator compiled (``tasks/humanoid/mujoco_c.py``: same MJCF, timestep, substeps, integrator, solver and its
iterations, contacts and PD actuators) on the same number of worlds, with the same random PD targets. Random
actions end episodes after about two control steps, so the C worlds run episodes of our run's mean length, each
from the env's reference-state starts. Physics only on the C side: no rewards, observations, resets or reference
sampling.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.utils.atomic_files import write_json
from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.option_rules import DEVICE_DOC, DEVICE_RULE, Flag, Int, Text
from refpo_warp.utils.options import option
from refpo_warp.utils.timing import env_steps_per_second, print_title


class _CountEpisodes:
    """The env's stepping interface, adding each step's finished episodes to a device counter (no host sync)."""

    def __init__(self, env) -> None:
        self.env, self.device, self.num_envs, self.num_actions = env, env.device, env.num_envs, env.num_actions
        self.ended = torch.zeros((), dtype=torch.int64, device=env.device)

    def step(self, actions: torch.Tensor):
        out = self.env.step(actions)
        self.ended += out[2].sum()
        return out


def measure(
    task: str, num_envs: int, device: str, steps: int, warmup: int, seed: int = 0, with_c: bool = True, **env_cfg
) -> dict:
    """Build the env, warm up, time ``steps`` random-action steps, then (``with_c``) the MuJoCo C anchor."""
    start = time.perf_counter()
    env = make_env(task, num_envs=num_envs, device=device, seed=seed, **env_cfg)
    build_s = time.perf_counter() - start
    start = time.perf_counter()
    if warmup > 0:
        env_steps_per_second(env, steps=warmup, warmup=0, seed=seed)
    warmup_s = time.perf_counter() - start
    counted = _CountEpisodes(env)
    rate = env_steps_per_second(counted, steps=steps, warmup=0, seed=seed)
    ended = int(counted.ended)
    result = {
        "task": task,
        "device": env.device,
        "num_envs": num_envs,
        "steps": steps,
        "env_steps_per_s": rate,
        "ms_per_step": 1e3 * num_envs / rate,
        "episodes_ended": ended,
        "mean_episode_length": steps * num_envs / ended if ended else None,
        "build_s": build_s,
        "warmup_s": warmup_s,
        "graph_captured": env._graph is not None,
    }
    if with_c:
        length = round(result["mean_episode_length"]) if ended else steps
        result.update(mujoco_c(env, steps, length, seed))
        result["ours_over_c"] = rate / result["c_env_steps_per_s"]
        result["substeps"] = env.sim.substeps
    return result


def mujoco_c(env, steps: int, episode_length: int, seed: int = 0) -> dict:
    """MuJoCo C env steps per second on ``env``'s model and worlds: ``steps`` control steps in episodes of
    ``episode_length`` from the env's reference-state starts, uniform random actions mapped to PD targets as ours."""
    from refpo_warp.tasks.humanoid import mujoco_c as mc

    env.reset()  # fresh reference-state starts
    model = mc.c_model(env.sim)
    states = mc.c_states(model, env.sim)
    scale = env.action_scale.numpy() * ~env.frozen_dof.numpy()  # absolute PD targets, as ours
    rng = np.random.default_rng(seed)
    length = max(1, min(episode_length, steps))
    episodes = -(-steps // length)

    def run(count: int) -> float:
        targets = scale * rng.uniform(-1.0, 1.0, size=(count, env.num_envs, length, scale.size))
        start = time.perf_counter()
        for k in range(count):
            mc.rollout(model, states, targets[k], env.sim.substeps)
        return count * length * env.num_envs / (time.perf_counter() - start)

    run(1)  # warm-up
    return {"c_env_steps_per_s": run(episodes), "c_episode_length": length, "c_settings": mc.solver_settings(model)}


@dataclass(frozen=True)
class Options:
    task: str = option("humanoid_all", Text(), "a humanoid task id")
    device: str = option("auto", DEVICE_RULE, DEVICE_DOC)
    num_envs: int | None = option(None, Int(1, 1 << 22, optional=True), "envs (default: 64 on CPU, 4096 on CUDA)")
    timed_steps: int | None = option(None, Int(1, optional=True), "timed steps (default: 30 on CPU, 300 on CUDA)")
    warmup_steps: int = option(3, Int(0), "untimed steps first")
    mujoco_c: bool = option(True, Flag(), "also time the MuJoCo C anchor (false: ours only)")
    out: str | None = option(None, Text(optional=True), "also write the result to this JSON file")


REST_PREFIXES = ("env.",)
REST_DOC = "an env cfg option (e.g. env.njmax=320)"


def run(options: Options, given: dict[str, Any]) -> None:
    args = options
    device = resolve_device(args.device)
    cpu = device == "cpu"
    num_envs = args.num_envs or (64 if cpu else 4096)
    steps = args.timed_steps or (30 if cpu else 300)
    env_cfg: dict[str, Any] = {key.removeprefix("env."): value for key, value in given.items()}
    result = measure(args.task, num_envs, device, steps, args.warmup_steps, with_c=args.mujoco_c, **env_cfg)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        write_json(result, Path(args.out))
        print(f"wrote {args.out}")
    print_title(f"{result['task']} env steps per second on {result['device']}, {num_envs} envs")
    print(
        f"{result['task']} on {result['device']}: {num_envs} envs, {steps} steps after {args.warmup_steps} warm-up "
        f"(graph captured: {result['graph_captured']}), uniform random actions in [-1, 1]"
        + (f"; env options {env_cfg}" if env_cfg else "")
    )
    length = result["mean_episode_length"]
    print(
        f"  ours: {result['env_steps_per_s']:,.0f} env steps/s ({result['ms_per_step']:.1f} ms per step, "
        f"{result['episodes_ended']} episodes ended, mean length {length or float('nan'):.1f}); "
        f"build {result['build_s']:.1f} s, warm-up {result['warmup_s']:.1f} s"
    )
    print(
        "    includes: PD targets, physics substeps, reference sampling, reward/termination/metrics, resets of "
        "finished episodes, observations"
    )
    if "c_env_steps_per_s" in result:
        c = result["c_settings"]
        print(
            f"  MuJoCo C (mujoco.rollout, 1 thread): {result['c_env_steps_per_s']:,.0f} env steps/s; same model, "
            f"{num_envs} worlds, dt {c['timestep']:.5f} s x {result['substeps']} substeps, {c['integrator']}, "
            f"{c['solver']} {c['iterations']}/{c['ls_iterations']} iterations, tolerance {c['tolerance']:.0e}, "
            f"{c['cone']}; episodes of {result['c_episode_length']} control steps from the env's "
            f"reference-state starts"
        )
        print("    physics only: no rewards, observations, resets or reference sampling")
        print(f"  ours / MuJoCo C: {result['ours_over_c']:.2f}")
