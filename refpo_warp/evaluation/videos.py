"""Recording what a policy does: episodes of the task's env drawn frame by frame (``refpo_warp/render``, the family's
``render.py``), one panel per flow-step count N side by side from the same initial states, several envs tiled in each
panel, each env's return so far written on it; saved as MP4 and/or GIF under ``<run dir>/videos/``.

A recording runs on random streams of its own (``refpo_warp.utils.rng``), so the caller's are left as they were (a
recording during training changes nothing in the run): the envs are seeded by ``VideoOptions.seed`` and every panel
samples its noise from the same reseeded stream.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch

from refpo_warp.config.resolve import Resolution
from refpo_warp.envs.registry import family_module, make_env
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.render.frames import overlay, tile
from refpo_warp.render.options import VideoOptions
from refpo_warp.render.video import write_video
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.rng import VIDEO, own_random_streams, stream_seed

MAX_FPS = 30.0
VIDEO_DIR = "videos"


def frame_source(task: str | TaskSpec, env, options: VideoOptions):
    """The task family's frames of ``env`` (its ``render.py``); a clear error for a family that has none."""
    module = family_module(task, "render")
    if module is None:
        task_id = task.task_id if isinstance(task, TaskSpec) else task
        raise ConfigError(f"task {task_id!r} has no frames to record: its family has no render.py")
    inner = getattr(env, "env", env)  # an action-chunk wrapper's env
    return module.frame_source(
        inner,
        options.width,
        options.height,
        camera=options.camera,
        shadows=options.shadows,
        reference=options.reference,
    )


def record_panel(
    task: str | TaskSpec,
    env_options: dict,
    device: str,
    make_policy: Callable,
    label: str,
    options: VideoOptions,
    seed: int,
) -> tuple[list[np.ndarray], float]:
    """(frames, frames per second) of one panel: ``options.num_envs`` envs tiled, from their first reset until each
    ended its first episode (or ``options.length`` env steps), every k-th env step drawn (k from the real-time rate
    and the fps)."""
    env = make_env(task, num_envs=options.num_envs, device=device, seed=seed, **env_options)
    policy = make_policy(env)
    source = frame_source(task, env, options)
    try:
        step_hz = source.control_hz / getattr(env, "env_steps_per_step", 1)
        every = max(1, math.ceil(step_hz / (options.fps or MAX_FPS)))
        limit = options.length or int(env.max_episode_length)
        n = env.num_envs
        returns = torch.zeros(n)
        finished = torch.zeros(n, dtype=torch.bool)
        last: list[np.ndarray | None] = [None] * n
        frames = []
        torch.manual_seed(seed)
        obs = env.reset()
        for step in range(limit):
            if step % every == 0:
                for i in range(n):
                    if not finished[i]:
                        image, lines = source.frame(i)
                        last[i] = overlay(image, [f"{label}  return {float(returns[i]):.1f}", *lines])
                frames.append(tile([f for f in last if f is not None]))
            with torch.inference_mode():
                obs, rewards, dones, _ = env.step(policy(obs))
            returns += torch.where(finished, 0.0, rewards.cpu())
            finished |= dones.cpu()
            if options.length is None and bool(finished.all()):
                break
        for i in range(n):  # the last frame of each env shows its final return
            frame = last[i]
            if frame is not None:
                lines = [f"{label}  return {float(returns[i]):.1f}"]
                last[i] = overlay(frame, lines)
        frames.append(tile([f for f in last if f is not None]))
        return frames, step_hz / every
    finally:
        source.close()


def side_by_side(panels: list[list[np.ndarray]]) -> list[np.ndarray]:
    """One frame per time step with the panels next to each other; a panel that ended holds its last frame."""
    length = max(len(p) for p in panels)
    return [tile([p[min(t, len(p) - 1)] for p in panels], columns=len(panels)) for t in range(length)]


def record(
    task: str | TaskSpec,
    env_options: dict,
    device: str,
    policies: dict[str, Callable],
    options: VideoOptions,
    out_dir: Path,
    name: str,
    seed: int,
) -> list[Path]:
    """Record one panel per policy (label -> a function of the env giving the obs -> actions function), side by
    side; returns the files written."""
    with own_random_streams(stream_seed(seed, VIDEO), device):
        recorded = [
            record_panel(task, env_options, device, policy, label, options, seed) for label, policy in policies.items()
        ]
    frames = side_by_side([panel for panel, _ in recorded])
    fps = recorded[0][1]
    name = options.name or name
    return [write_video(frames, Path(out_dir) / f"{name}.{fmt}", fps) for fmt in options.formats()]


def policy_panels(cfg: dict, actor: Any, options: VideoOptions) -> tuple[dict[str, Callable], str]:
    """The panels of a run's policy under its evaluation protocol (label -> env -> policy) and a name tag: one per
    flow-step count N (``options.flow_steps``, else the first of ``eval.flow_steps``) and initial-noise protocol
    (``eval.initial_noise``), or the Gaussian's mean action."""
    from refpo_warp.evaluation.evaluate_policy import is_flow, make_policy, setting_name

    if not is_flow(actor):
        return {"mean action": lambda env: make_policy(actor, None)}, "mean"
    steps = options.flow_steps or [cfg["eval"]["flow_steps"][0]]
    protocols, perturbation = cfg["eval"]["initial_noise"], cfg["eval"]["perturbation"]
    panels = {
        setting_name(n, noise): (lambda env, n=n, noise=noise: make_policy(actor, n, noise, perturbation))
        for noise in protocols
        for n in steps
    }
    tag = "N" + "-".join(map(str, steps)) + ("" if protocols == ["random"] else "_" + "-".join(protocols))
    return panels, tag


def agent_policy(agent: str, seed: int) -> Callable:
    """A policy without a run, to look at a task: zero actions, or uniform ones in [-1, 1] from its own stream."""
    generator = torch.Generator().manual_seed(seed)

    def make(env) -> Callable:
        shape = (env.num_envs, env.num_actions)
        if agent == "zero":
            return lambda obs: torch.zeros(shape, device=env.device)
        return lambda obs: (torch.rand(shape, generator=generator) * 2 - 1).to(env.device)

    return make


def run_video(run: Resolution, runner: Any, run_dir: Path, name: str) -> list[Path]:
    """Record the runner's current policy under the run's evaluation protocol into ``<run dir>/videos/<name>.*``
    (the ``video`` options of the run's config)."""
    from refpo_warp.evaluation.evaluate_policy import eval_env_options

    cfg = run.cfg
    options = VideoOptions.from_dict(cfg["video"])
    actor = runner.alg.get_policy()
    was_training = actor.training
    actor.eval()
    try:
        panels, _ = policy_panels(cfg, actor, options)
        seed = cfg["seed"] if options.seed is None else options.seed
        return record(
            run.task,
            eval_env_options(cfg),
            runner.device,
            panels,
            options,
            Path(run_dir) / VIDEO_DIR,
            name,
            seed,
        )
    finally:
        actor.train(was_training)


def wants_video(cfg: dict) -> bool:
    return bool(cfg["video"].get("at_end") or cfg["video"].get("interval"))
