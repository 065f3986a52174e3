#!/usr/bin/env python
"""Benchmarks: python tools/bench.py <gridworld|dmc|humanoid|all|latency|algorithms|render> [options of that benchmark]

Each task family with a benchmark has it in tasks/<family>/bench.py (found there, not listed here);
`python tools/bench.py dmc --help` shows its options. `all` runs every family's benchmark. `latency`
(refpo_warp/benchmarks/latency.py) times action generation at N = 10 vs N = 1 for
chosen tasks and algorithms; `--json PATH` writes the rows for `tools/report.py` (the latency figure).
`algorithms` (refpo_warp/benchmarks/update_time.py) times the update of every algorithm on one batch size, as ratios to
FPO. `render` (refpo_warp/benchmarks/rendering.py): frames per second of each family's frames and the cost of a video.
"""

import importlib
import importlib.util
import sys

OTHERS = {"latency": "refpo_warp.benchmarks.latency", "algorithms": "refpo_warp.benchmarks.update_time",
          "render": "refpo_warp.benchmarks.rendering"}  # not one family's


def benchmarked_families() -> list[str]:
    """The task families (found by the registry) that have a ``bench.py``."""
    from refpo_warp.envs.registry import TASK_ROOT, task_families

    return [f for f in task_families() if importlib.util.find_spec(f"{TASK_ROOT}.{f}.bench") is not None]


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    family, rest = argv[0], argv[1:]
    families = benchmarked_families()
    if family not in (*families, "all", *OTHERS):
        from refpo_warp.utils.errors import unknown

        print(f"error: {unknown('benchmark', family, (*families, 'all', *OTHERS))}", file=sys.stderr)
        return 2
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads()
    if family in OTHERS:
        importlib.import_module(OTHERS[family]).main(rest)
        return 0
    for name in families if family == "all" else (family,):
        print(f"\n## {name}", flush=True)  # each family's tables follow as ### blocks
        importlib.import_module(f"refpo_warp.tasks.{name}.bench").main(rest)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
