"""``refpo``, the command of the installed package (``python -m refpo_warp`` and the checkout's ``tools/*.py`` are the
same): ``refpo <command> [SUBJECT] [key=value ...] [--flags]`` (``refpo_warp/utils/command_line.py``).

Every command runs through ``refpo_warp/cli/guard.py``: one message and a documented exit code per failure.
"""

from __future__ import annotations

import importlib
import os
import sys

from refpo_warp.cli.guard import run_guarded
from refpo_warp.utils.command_line import HELP, Arguments, parse_arguments, wants_help
from refpo_warp.utils.errors import EXIT_OK, EXIT_USAGE, unknown

# command -> its module (imported when the command runs: `refpo --help` loads none of them)
COMMANDS = {
    "train": "refpo_warp.cli.train",
    "collect": "refpo_warp.cli.collect",
    "pretrain": "refpo_warp.cli.pretrain",
    "eval": "refpo_warp.cli.eval",
    "play": "refpo_warp.cli.play",
    "plot": "refpo_warp.cli.plot",
    "sweep": "refpo_warp.cli.sweep",
    "report": "refpo_warp.cli.report",
    "tune": "refpo_warp.cli.tune",
    "bench": "refpo_warp.cli.bench",
    "convert-amass": "refpo_warp.cli.convert_amass",
    "make-clips": "refpo_warp.cli.make_clips",
}


def overview() -> str:
    lines = ["refpo <command> [SUBJECT] [key=value ...] [--flags]; refpo <command> --help for one command:", ""]
    for name, module in COMMANDS.items():
        lines.append(f"  {name:14s} {importlib.import_module(module).SUMMARY}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run ``refpo <argv>``; returns the exit code."""
    try:
        code = _dispatch(sys.argv[1:] if argv is None else list(argv))
        sys.stdout.flush()  # a reader that stopped early shows here, not in the interpreter's exit
    except BrokenPipeError:  # `refpo train --help | head -1`: the reader has what it wanted; no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    return code


def _dispatch(argv: list[str]) -> int:
    if not argv or argv[0] in HELP:
        print(overview(), file=sys.stdout if argv else sys.stderr)
        return EXIT_OK if argv else EXIT_USAGE
    name, rest = argv[0], argv[1:]
    if name not in COMMANDS:
        print(f"error: {unknown('command', name, COMMANDS)}", file=sys.stderr)
        return EXIT_USAGE
    command = importlib.import_module(COMMANDS[name])
    passes_on = getattr(command, "PASSES_ON", False)  # the flags after the subject belong to it (refpo bench dmc ...)
    if wants_help(rest[:1] if passes_on else rest):
        print(command.USAGE)
        return EXIT_OK

    def run() -> int | None:
        if passes_on:
            args = Arguments(rest[:1], rest[1:]) if rest and not rest[0].startswith("-") else Arguments([], rest)
        else:
            args = parse_arguments(name, rest, command.FLAGS, command.SUBJECTS)
        return command.run(args)

    return run_guarded(run)
