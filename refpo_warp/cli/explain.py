"""``--explain [KEYS]`` of ``refpo train`` and ``refpo eval``: where each option of the run gets its value, instead
of running the command."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from refpo_warp.config.command_options import EXPLAIN
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError

__all__ = ["EXPLAIN", "explain_or_run", "explain_run"]


def explain_or_run(command: str, args: Arguments, action: Callable[[list[str]], None]) -> None:
    """With ``--explain``, print where the options get their values (nothing is built or written); else run."""
    if "--explain" in args.flags:
        explain_run(command, args.options, args.flag("--explain"))
    else:
        action(args.options)


def explain_run(command: str, options: list[str], keys: str) -> None:
    """Print where each option of the run the options describe gets its value (a resumed or evaluated run: its
    saved config with the options over it)."""
    from refpo_warp.config.dotted import flatten, parse_overrides
    from refpo_warp.config.explain import explain
    from refpo_warp.config.resolve import resolve
    from refpo_warp.config.saved import read_saved_config

    flat = parse_overrides(options)
    flat.pop("checkpoint", None)
    if command == "eval" or flat.get("resume") is True:
        if not flat.get("run_dir"):
            raise ConfigError("--explain of a saved run needs run_dir=PATH")
        flat = {**flatten(read_saved_config(Path(str(flat["run_dir"])))), **flat}
    chosen = [k.strip() for k in keys.split(",") if k.strip()]
    print(explain(resolve(flat), chosen or None), flush=True)
