"""``refpo bench``: the benchmarks of the task families and of the algorithms."""

from __future__ import annotations

import importlib
import importlib.util

from refpo_warp.cli.arguments import Arguments
from refpo_warp.utils.errors import ConfigError, unknown

SUMMARY = "env speed vs gymnasium, action latency, update cost of every algorithm, rendering speed"
USAGE = """Benchmarks: refpo bench <gridworld|dmc|humanoid|all|latency|algorithms|render> [--flags of that benchmark]

Each task family with a benchmark has it in tasks/<family>/bench.py (found there, not listed here);
`refpo bench dmc --help` shows its flags. `all` runs every family's benchmark. `latency`
(refpo_warp/benchmarks/latency.py) times action generation at N = 10 vs N = 1 for chosen tasks and algorithms;
`--json PATH` writes the rows for `refpo report` (the latency figure). `algorithms`
(refpo_warp/benchmarks/update_time.py) times the update of every algorithm on one batch size, as ratios to FPO.
`render` (refpo_warp/benchmarks/rendering.py): frames per second of each family's frames and the cost of a video.
"""
FLAGS = ()
SUBJECTS = 1
PASSES_ON = True  # the flags after the benchmark's name are the benchmark's own (its --help included)
OTHERS = {"latency": "refpo_warp.benchmarks.latency", "algorithms": "refpo_warp.benchmarks.update_time",
          "render": "refpo_warp.benchmarks.rendering"}  # not one family's


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
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads()
    if name in OTHERS:
        importlib.import_module(OTHERS[name]).main(rest)
        return
    for family in families if name == "all" else (name,):
        print(f"\n## {family}", flush=True)  # each family's tables follow as ### blocks
        importlib.import_module(f"refpo_warp.tasks.{family}.bench").main(rest)
