"""Update time of every algorithm on one batch size: refpo bench algorithms [task=T] [num_envs=E] ...

Each algorithm is built from its config for the task (its own actor, pairs/chain and losses), collects one rollout
of ``num_envs x num_steps_per_env`` transitions and times ``update()`` (median of ``repeats`` fresh rollouts, 5 by
default) with the same number of passes (``num_learning_epochs``) and ``num_mini_batches`` for all, so the ratio to
FPO is the per-transition cost of each method's update. A second ratio scales each time to the paper's settings per
env step (DMC tables (a)-(d): 16 passes for PPO/FPO/ReFPO, 8 for Flow-GRPO and ReinFlow, and ReinFlow's transitions
are chunks of 4 env steps).

``algos=`` also takes ReFPO's options as variants (``VARIANTS``: coupled Reflow pairs, the adaptive coefficient),
built as the algo plus their overrides, as ``configs/sweep/cpu_reflow_pairs.yaml`` runs them.
"""

from __future__ import annotations

import contextlib
import io
import time
from dataclasses import dataclass

import torch

from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.errors import unknown
from refpo_warp.utils.option_rules import DEVICE_DOC, DEVICE_RULE, Int, ListOf, Text
from refpo_warp.utils.options import option
from refpo_warp.utils.timing import print_table, synchronize

# table order; other algos follow, sorted
ORDER = ("fpo", "refpo", "refpo_onestep", "refpo_aw", "fpo_pp", "refpo_pp", "flow_grpo", "reinflow", "ppo")
NAMES = {
    "fpo": "FPO",
    "refpo": "ReFPO",
    "refpo_aw": "ReFPO (adv.-weighted)",
    "flow_grpo": "Flow-GRPO",
    "reinflow": "ReinFlow",
    "ppo": "PPO",
    "fpo_pp": "FPO++",
    "refpo_pp": "ReFPO on FPO++",
    "refpo_onestep": "ReFPO, one-step term",
    "refpo_coupled": "ReFPO, coupled pairs",
    "refpo_adaptive": "ReFPO, adaptive λ",
}
VARIANTS = {
    "refpo_coupled": ("refpo", ["algorithm.reflow_pairs=coupled"]),
    "refpo_adaptive": ("refpo", ["algorithm.reflow_schedule=adaptive"]),
}
"""name -> (algo, overrides): options of an algorithm timed as a row of their own (only when asked: algos=)."""
PAPER_PASSES = {
    "fpo": 16,
    "refpo": 16,
    "refpo_onestep": 16,
    "refpo_aw": 16,
    "fpo_pp": 16,
    "refpo_pp": 16,
    "flow_grpo": 8,
    "reinflow": 8,
    "ppo": 16,
}  # FPO++ at the ReFPO family's passes, as it runs in the grid
"""Passes per batch in the paper's DMC tables; an algorithm not in them is scaled with ``num_learning_epochs``."""


def algorithms() -> list[str]:
    """Every algo file of the config folders (nothing to list here when an algorithm is added)."""
    from refpo_warp.config.config_set import config_set

    found = config_set().algo_names()
    return [a for a in ORDER if a in found] + sorted(set(found) - set(ORDER))


def build(algo: str, task: str, device: str, envs: int, steps: int, minibatches: int, passes: int):
    from refpo_warp.config.resolve import resolve
    from refpo_warp.runner.build import build_runner

    algo, overrides = VARIANTS.get(algo, (algo, []))
    run = resolve(
        [
            f"task={task}",
            f"algo={algo}",
            f"device={device}",
            f"num_envs={envs}",
            f"runner.num_steps_per_env={steps}",
            f"algorithm.num_mini_batches={minibatches}",
            f"algorithm.num_learning_epochs={passes}",
            "eval.interval=0",
            *overrides,
        ]
    )
    with contextlib.redirect_stdout(io.StringIO()):  # rsl_rl prints the model structure
        env, runner = build_runner(run, None)
    return env, runner.alg, run.cfg


def fill_rollout(env, alg) -> None:
    obs = env.get_observations()
    with torch.inference_mode():
        for _ in range(alg.storage.num_transitions_per_env):
            actions = alg.act(obs)
            obs, rewards, dones, extras = env.step(actions)
            alg.process_env_step(obs, rewards, dones, extras)
        alg.compute_returns(obs)


def update_time(alg, env, device: str, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        fill_rollout(env, alg)
        synchronize(device)
        start = time.perf_counter()
        alg.update()
        synchronize(device)
        times.append(time.perf_counter() - start)
    return sorted(times)[len(times) // 2]


@dataclass(frozen=True)
class Options:
    task: str = option("dmc_cheetah_run", Text(), "a task id")
    num_envs: int = option(256, Int(8, 1 << 22, multiple_of=8), "envs, a multiple of 8 (Flow-GRPO's groups)")
    num_steps_per_env: int = option(60, Int(1), "policy steps per env and rollout (runner.num_steps_per_env)")
    num_mini_batches: int = option(8, Int(1), "minibatches per pass (algorithm.num_mini_batches)")
    num_learning_epochs: int = option(2, Int(1), "passes over the rollout (algorithm.num_learning_epochs)")
    repeats: int = option(5, Int(1), "fresh rollouts timed (the median is reported)")
    algos: list[str] | None = option(None, ListOf(Text(), optional=True), "algos and variants (default: every one)")
    device: str = option("auto", DEVICE_RULE, DEVICE_DOC)


def run(options: Options, _: dict | None = None) -> None:
    choices = [*algorithms(), *VARIANTS]
    algos = list(options.algos or algorithms())
    for algo in algos:
        if algo not in choices:
            raise unknown("algorithm of refpo bench algorithms", algo, choices)
    device = resolve_device(options.device)
    envs, steps = options.num_envs, options.num_steps_per_env
    minibatches, passes_given = options.num_mini_batches, options.num_learning_epochs
    if "fpo" not in algos:
        algos = ["fpo", *algos]
    title = (
        f"Update time on {options.task}, {device}, torch threads {torch.get_num_threads()}: {envs} envs x "
        f"{steps} steps = {envs * steps} transitions, {minibatches} minibatches, {passes_given} passes"
    )
    seconds, chunks = {}, {}
    for algo in algos:
        torch.manual_seed(0)
        env, alg, cfg = build(algo, options.task, device, envs, steps, minibatches, passes_given)
        seconds[algo] = update_time(alg, env, device, options.repeats)
        chunks[algo] = cfg["env"].get("action_chunk", 1)
    passes = {a: PAPER_PASSES.get(VARIANTS.get(a, (a,))[0], passes_given) for a in seconds}
    per_env_step = {a: seconds[a] / passes_given * passes[a] / chunks[a] for a in seconds}
    rows = [
        {
            "algorithm": NAMES.get(a, a),
            "update (s)": f"{seconds[a]:.3f}",
            "ratio to FPO": f"{seconds[a] / seconds['fpo']:.2f}",
            "paper passes, per env step, ratio to FPO": f"{per_env_step[a] / per_env_step['fpo']:.2f}",
        }
        for a in seconds
    ]
    print_table(
        rows, ["algorithm", "update (s)", "ratio to FPO", "paper passes, per env step, ratio to FPO"], title=title
    )
