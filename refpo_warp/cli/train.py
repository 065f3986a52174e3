"""``refpo train``: train a policy (and evaluate it), list the tasks, or explain a run's config."""

from __future__ import annotations

from refpo_warp.cli.explain import EXPLAIN, explain_or_run
from refpo_warp.utils.command_line import Arguments, Flag

SUMMARY = "train a policy and evaluate it; --list-tasks lists the task ids, --explain KEY says who set an option"
USAGE = """Train a policy: refpo train task=<task id> [algo=<algo: refpo, fpo, ppo, ...>] [key=value ...]

Examples:
    refpo train task=gridworld algo=refpo seed=1 run_dir=runs/grid
    refpo train task=dmc_cheetah_run algo=fpo num_envs=2048 device=cuda:0
    refpo train task=humanoid_root
    refpo train run_dir=runs/grid resume=true                   # continue from the last checkpoint
    refpo train task=gridworld algo=fpo --explain algorithm.reflow_coef   # the value and the layer that set it
    refpo train --list-tasks [config_dir=DIR]                   # the task ids (those of your config folder too)

Any config key can be overridden (the run options and their defaults: refpo_warp/config/run_options.py);
config_dir=DIR (or REFPO_CONFIG_PATH) adds your own task, algo and sweep files (docs/cli.md).
Flags: --list-tasks, --explain [KEY,KEY,...] (without keys: every option; nothing is trained).
"""
FLAGS = (Flag("--list-tasks", doc="list the task ids"), EXPLAIN)
SUBJECTS = 0


def run(args: Arguments) -> None:
    if args.flag("--list-tasks"):
        list_tasks(args.options)
    else:
        explain_or_run("train", args, train)


def train(options: list[str]) -> None:
    from refpo_warp.runner.distributed import close_process_group, main_rank_stdout, process_rank
    from refpo_warp.training import train
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads(cuda_cap=4)
    # Under torchrun only rank 0 prints progress; every rank leaves the process group when done.
    try:
        with main_rank_stdout(process_rank()):
            train(options)
    finally:
        close_process_group()


def list_tasks(options: list[str]) -> None:
    """Every task id with its description, those of the config folders the options name included."""
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.config.resolve import run_config_set

    configs = run_config_set(parse_overrides(options))
    for task in configs.task_ids():
        print(f"{task:28s} {configs.task(task).description}")
