"""Timing helpers shared by the per-family benchmarks behind ``refpo bench``."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

import torch


def synchronize(device: str) -> None:
    if str(device).startswith("cuda"):
        torch.cuda.synchronize()


def time_call(fn: Callable[[], object], device: str = "cpu", repeats: int = 20, warmup: int = 3) -> float:
    """Median wall time of ``fn()`` in seconds (after ``warmup`` calls), synchronising the device each call."""
    for _ in range(warmup):
        fn()
    synchronize(device)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        synchronize(device)
        times.append(time.perf_counter() - start)
    return sorted(times)[len(times) // 2]


def env_steps_per_second(env, steps: int = 200, warmup: int = 5, seed: int = 0) -> float:
    """Env steps per second of ``env`` under uniform random actions in [-1, 1] drawn ahead of time."""
    gen = torch.Generator(device=env.device).manual_seed(seed)
    actions = torch.rand(8, env.num_envs, env.num_actions, device=env.device, generator=gen) * 2 - 1
    for i in range(warmup):  # the first step compiles kernels and captures the graph
        env.step(actions[i % 8])
    synchronize(env.device)
    start = time.perf_counter()
    for i in range(steps):
        env.step(actions[i % 8])
    synchronize(env.device)
    return steps * env.num_envs / (time.perf_counter() - start)


def print_title(title: str) -> None:
    """Start a titled block: a blank line and a Markdown heading, so each table stands apart (pastes as Markdown)."""
    print(f"\n### {title}\n", flush=True)


def print_table(rows: list[dict], columns: list[str], title: str | None = None, notes: tuple[str, ...] = ()) -> None:
    """Print rows as an aligned plain-text table (also valid Markdown), under ``title`` and followed by ``notes``."""
    if title:
        print_title(title)
    widths = {c: max(len(c), *(len(str(r.get(c, ""))) for r in rows)) for c in columns}
    print("| " + " | ".join(c.ljust(widths[c]) for c in columns) + " |")
    print("|" + "|".join("-" * (widths[c] + 2) for c in columns) + "|")
    for r in rows:
        print("| " + " | ".join(str(r.get(c, "")).ljust(widths[c]) for c in columns) + " |")
    if notes:
        print()
        for note in notes:
            print(note)
    sys.stdout.flush()
