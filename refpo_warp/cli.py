"""Command-line front ends shared by tools/*.py: argument parsing and clear, non-zero exits on bad input."""

from __future__ import annotations

import sys
from pathlib import Path

from refpo_warp.errors import ConfigError, MotionDataError, NonFiniteLossError


def _train(args: list[str]) -> None:
    from refpo_warp.distributed import close_process_group, main_rank_stdout, process_rank
    from refpo_warp.training import train

    # Under torchrun only rank 0 prints progress; every rank leaves the process group when done.
    try:
        with main_rank_stdout(process_rank()):
            train(args)
    finally:
        close_process_group()


def _eval(args: list[str]) -> None:
    from refpo_warp.config import parse_overrides
    from refpo_warp.report import evaluate_run

    overrides = parse_overrides(args)
    run_dir = overrides.pop("run_dir", None)
    if run_dir is None:
        raise ConfigError("tools/eval.py needs run_dir=PATH (a directory written by tools/train.py)")
    checkpoint = overrides.pop("checkpoint", None)
    evaluate_run(Path(run_dir), checkpoint=checkpoint, overrides=overrides)


COMMANDS = {"train": _train, "eval": _eval}


def main(command: str, args: list[str], usage: str) -> int:
    if any(a in ("-h", "--help", "help") for a in args):
        print(usage)
        return 0
    if "--tasks" in args:
        from refpo_warp.registry import get_task, list_tasks

        for task in list_tasks():
            print(f"{task:28s} {get_task(task).description}")
        return 0
    try:
        from refpo_warp.device import set_torch_threads

        set_torch_threads(cuda_cap=4)
        COMMANDS[command](args)
    except (ConfigError, MotionDataError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except NonFiniteLossError as err:
        print(f"error: training stopped: {err}\nThe last good checkpoint in the run dir is intact; resume with "
              f"resume=true after changing the settings.", file=sys.stderr)  # fmt: skip
        return 3
    except KeyboardInterrupt:
        print("interrupted; checkpoints written so far are intact (resume=true continues)", file=sys.stderr)
        return 130
    return 0

