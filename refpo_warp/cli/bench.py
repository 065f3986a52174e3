"""``refpo bench``: the benchmarks of the task families and of the algorithms."""

from __future__ import annotations

import importlib
import importlib.util

from refpo_warp.utils.command_line import Arguments, wants_help
from refpo_warp.utils.errors import ConfigError, unknown

SUMMARY = "env speed vs gymnasium, action latency, update cost of every algorithm, rendering speed, training speed"
USAGE = """Benchmarks: refpo bench <gridworld|dmc|humanoid|all|latency|algorithms|render|train> [its flags or options]

Each task family with a benchmark has it in tasks/<family>/bench.py (found there, not listed here);
`refpo bench dmc --help` shows its flags, read by the convention of every refpo command. `all` runs every
family's benchmark. `latency` (refpo_warp/benchmarks/latency.py) times action generation at N = 10 vs N = 1 for
chosen tasks and algorithms; `--json PATH` writes the rows for `refpo report` (its latency=). `algorithms`
(refpo_warp/benchmarks/update_time.py) times the update of every algorithm on one batch size, as ratios to FPO.
`render` (refpo_warp/benchmarks/rendering.py): frames per second of each family's frames and the cost of a video.
`train` (refpo_warp/benchmarks/train_throughput.py): training env steps/s of a task x algos, split into the
iteration's and the update's parts, as ratios to PPO; key=value options (refpo bench train --help).
"""
FLAGS = ()
SUBJECTS = 1
PASSES_ON = True  # the flags after the benchmark's name are the benchmark's own (its --help included)
OTHERS = {
    "latency": "refpo_warp.benchmarks.latency",
    "algorithms": "refpo_warp.benchmarks.update_time",
    "render": "refpo_warp.benchmarks.rendering",
    "train": "refpo_warp.benchmarks.train_throughput",
}  # not one family's


def benchmarked_families() -> list[str]:
    """The task families (found by the registry) that have a ``bench.py``."""
    from refpo_warp.envs.registry import TASK_ROOT, task_families

    return [f for f in task_families() if importlib.util.find_spec(f"{TASK_ROOT}.{f}.bench") is not None]


def run(args: Arguments) -> None:
    families = benchmarked_families()
    choices = (*families, "all", *OTHERS)
    if not args.subjects:
        raise ConfigError(f"refpo bench needs a benchmark: {', '.join(choices)}; see refpo bench --help")
    name, rest = args.subjects[0], args.options
    if name not in choices:
        raise unknown("benchmark", name, choices)
    modules = (
        [OTHERS[name]]
        if name in OTHERS
        else [f"refpo_warp.tasks.{f}.bench" for f in (families if name == "all" else (name,))]
    )
    if wants_help(rest):  # a benchmark's own flags, from the same convention as every command
        print("\n\n".join(importlib.import_module(m).USAGE for m in modules))
        return
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads()
    for module in modules:
        if name not in OTHERS:
            print(f"\n## {module.split('.')[-2]}", flush=True)  # each family's tables follow as ### blocks
        importlib.import_module(module).main(rest)
