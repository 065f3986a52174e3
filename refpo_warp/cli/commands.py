"""The commands behind ``tools/train.py`` and ``tools/eval.py``: parse ``key=value`` arguments, run, print the summary
block; every failure becomes one message and an exit code (``refpo_warp/cli/guard.py``).

Both take ``--help``, ``--tasks`` (the task ids) and ``--explain [KEY,...]`` (each option's resolved value and the
layer that set it, without training: ``python tools/train.py task=gridworld algo=fpo --explain algorithm.reflow_coef``;
without a key, every option).
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from refpo_warp.cli.guard import EXIT_OK, EXIT_USAGE, run_guarded
from refpo_warp.utils.errors import ConfigError


def _train(args: list[str]) -> None:
    from refpo_warp.runner.distributed import close_process_group, main_rank_stdout, process_rank
    from refpo_warp.training import train

    # Under torchrun only rank 0 prints progress; every rank leaves the process group when done.
    try:
        with main_rank_stdout(process_rank()):
            train(args)
    finally:
        close_process_group()


def _eval(args: list[str]) -> None:
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.evaluation.evaluate_run import evaluate_run
    from refpo_warp.utils.console import headline_numbers, run_outputs, summary_block
    from refpo_warp.utils.errors import tag_run_dir

    overrides = parse_overrides(args)
    run_dir = overrides.pop("run_dir", None)
    if run_dir is None:
        raise ConfigError("tools/eval.py needs run_dir=PATH (a directory written by tools/train.py)")
    checkpoint = overrides.pop("checkpoint", None)
    if checkpoint is not None and not isinstance(checkpoint, str):
        raise ConfigError(f"checkpoint={checkpoint!r} is invalid; expected a path to a model_<iteration>.pt file")
    run_dir = Path(str(run_dir))
    with tag_run_dir(run_dir) if run_dir.is_dir() else contextlib.nullcontext():
        results = evaluate_run(run_dir, checkpoint=checkpoint, overrides=overrides)
    evaluated = checkpoint or run_dir / f"model_{results['checkpoint_iteration']}.pt"
    title = f"Evaluated {results['task']} / {results['algo']} at iteration {results['checkpoint_iteration']}"
    print(summary_block(title, run_outputs(run_dir, evaluated, results), headline_numbers(results)), flush=True)


def _explain(command: str, args: list[str], keys: list[str]) -> None:
    """Print where each option of the run the arguments describe gets its value (a resumed or evaluated run: its
    saved config with the arguments over it)."""
    from refpo_warp.config.dotted import flatten, parse_overrides
    from refpo_warp.config.explain import explain
    from refpo_warp.config.resolve import resolve
    from refpo_warp.config.saved import read_saved_config

    flat = parse_overrides(args)
    flat.pop("checkpoint", None)
    if command == "eval" or flat.get("resume") is True:
        if not flat.get("run_dir"):
            raise ConfigError("--explain of a saved run needs run_dir=PATH")
        flat = {**flatten(read_saved_config(Path(str(flat["run_dir"])))), **flat}
    print(explain(resolve(flat), keys or None), flush=True)


def _play(args: list[str]) -> None:
    from refpo_warp.cli.play import play

    for path in play(args):
        print(f"{path}  ({path.stat().st_size / 1024:.0f} KiB)", flush=True)


def _list_tasks(args: list[str]) -> None:
    """Every task id with its description, those of the config folders the arguments name included."""
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.config.resolve import run_config_path
    from refpo_warp.envs.registry import get_task, list_tasks

    run_config_path(parse_overrides(args))
    for task in list_tasks():
        print(f"{task:28s} {get_task(task).description}")


COMMANDS = {"train": _train, "eval": _eval, "play": _play}


def _explain_keys(args: list[str]) -> tuple[list[str], list[str] | None]:
    """(the arguments without ``--explain [KEYS]``, the keys to explain: [] for all; None without ``--explain``)."""
    for i, arg in enumerate(args):
        if arg == "--explain" or arg.startswith("--explain="):
            value = arg.partition("=")[2]
            rest = args[:i] + args[i + 1 :]
            if not value and i + 1 < len(args) and "=" not in args[i + 1] and not args[i + 1].startswith("-"):
                value, rest = args[i + 1], args[:i] + args[i + 2 :]
            return rest, [k.strip() for k in value.split(",") if k.strip()]
    return args, None


def main(command: str, args: list[str], usage: str) -> int:
    if any(a in ("-h", "--help", "help") for a in args):
        print(usage)
        return EXIT_OK
    if "--tasks" in args:
        return run_guarded(lambda: _list_tasks([a for a in args if a != "--tasks"]))
    args, explain_keys = _explain_keys(args)
    if explain_keys is not None:
        return run_guarded(lambda: _explain(command, args, explain_keys))
    if command not in COMMANDS:
        print(f"error: unknown command {command!r}", flush=True)
        return EXIT_USAGE

    def run() -> None:
        from refpo_warp.utils.device import set_torch_threads

        set_torch_threads(cuda_cap=4)
        COMMANDS[command](args)

    return run_guarded(run)
