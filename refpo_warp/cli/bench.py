"""``refpo bench``: the benchmarks of the task families and of the algorithms."""

from __future__ import annotations

import importlib
import importlib.util

from refpo_warp.utils.command_line import Arguments, parse_arguments, wants_help
from refpo_warp.utils.errors import ConfigError, unknown

SUMMARY = "env speed vs gymnasium, action latency, update cost of every algorithm, rendering speed, training speed"
USAGE = """Benchmarks: refpo bench <gridworld|dmc|humanoid|all|latency|algorithms|render|train> [key=value ...]

Each task family with a benchmark has it in tasks/<family>/bench.py (found there, not listed here);
`refpo bench dmc --help` shows its options, key=value as in every refpo command (device=, num_envs=, tasks=[...]).
`all` runs every family's benchmark. `latency` (refpo_warp/benchmarks/latency.py) times action generation at N = 10
vs N = 1 for chosen tasks and algorithms; `out=PATH` writes the rows for `refpo report` (its latency=). `algorithms`
(refpo_warp/benchmarks/update_time.py) times the update of every algorithm on one batch size, as ratios to FPO.
`render` (refpo_warp/benchmarks/rendering.py): frames per second of each family's frames and the cost of a video.
`train` (refpo_warp/benchmarks/train_throughput.py): training env steps/s of a task x algos, split into the
iteration's and the update's parts, as ratios to PPO; key=value options (refpo bench train --help).
"""
FLAGS = ()
SUBJECTS = 1
PASSES_ON = True  # the arguments after the benchmark's name are the benchmark's own (its --help included)
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
    names = [name] if name != "all" else families
    modules = {n: OTHERS.get(n, f"refpo_warp.tasks.{n}.bench") for n in names}
    if wants_help(rest):  # a benchmark's own options, from its fields
        print("\n\n".join(bench_help(n, importlib.import_module(m)) for n, m in modules.items()))
        return
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads()
    for bench, path in modules.items():
        module = importlib.import_module(path)
        if not hasattr(module, "Options"):  # a benchmark that reads its own arguments
            module.main(rest)
            continue
        parsed = parse_bench(bench, module, rest)
        if parsed is None:
            continue  # --explain printed
        if name not in OTHERS:
            print(f"\n## {bench}", flush=True)  # each family's tables follow as ### blocks
        module.run(*parsed)


def passed_on(module) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """What a benchmark passes on besides its own options: the keys ``REST_KEYS`` names and those starting with one of
    ``REST_PREFIXES`` (``env.``: a humanoid env option; a run option of refpo train for ``bench train``)."""
    return tuple(getattr(module, "REST_KEYS", ())), tuple(getattr(module, "REST_PREFIXES", ()))


def parse_bench(name: str, module, argv: list[str]):
    """(options, the options passed on) of ``refpo bench <name>``: its ``Options`` fields and what ``passed_on``
    accepts; None after ``--explain``."""
    from refpo_warp.config.command_options import EXPLAIN, options_or_explain

    command = f"bench {name}"
    args = parse_arguments(command, argv, (EXPLAIN,))
    keys, prefixes = passed_on(module)
    rest = (lambda key: key in keys or key.startswith(prefixes)) if keys or prefixes else None
    return options_or_explain(command, module.Options, args, rest, [*keys, *(f"{p}<option>" for p in prefixes)])


def bench_help(name: str, module) -> str:
    """``refpo bench <name> --help``: the first paragraph of the benchmark's docstring and its options' fields."""
    if not hasattr(module, "Options"):
        return module.USAGE
    from refpo_warp.config.command_options import command_help

    summary = module.__doc__.split("\n\n")[0]
    if hasattr(module, "REST_SYNOPSIS"):  # one line for what it passes on
        passed, summary = module.REST_SYNOPSIS, f"{summary}\n{module.REST_DOC}"
    else:
        prefixes = passed_on(module)[1]
        passed = "".join(f" [{p}<option>=VALUE ...]" for p in prefixes)
        summary += "".join(f"\n{p}<option>=VALUE: {module.REST_DOC}" for p in prefixes)
    return command_help(f"refpo bench {name} [key=value ...]{passed}", summary, module.Options)
