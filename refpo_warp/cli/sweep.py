"""``refpo sweep``: a grid of training runs, each a ``python -m refpo_warp train`` process of the installed package."""

from __future__ import annotations

import signal

from refpo_warp.cli.backend_flags import BACKEND_FLAGS, BACKEND_HELP, BACKEND_USAGE, backend_arguments
from refpo_warp.config.command_options import EXPLAIN, explain_options, named_files, options_help
from refpo_warp.studies.grid.spec import SweepOptions
from refpo_warp.utils.command_line import Arguments, Flag
from refpo_warp.utils.errors import EXIT_INTERRUPTED, EXIT_UNEXPECTED, ConfigError

SUMMARY = "a grid of tasks x methods x seeds, each run a training process (local or on a Ray cluster)"
USAGE = f"""Run a sweep: refpo sweep <sweep name or file> [key=value ...] [--jobs N] [--dry-run]
      {BACKEND_USAGE}

A grid of tasks x methods x seeds (x list-valued overrides), each run a separate `python -m refpo_warp train`
process in <sweep dir>/<task>/<label>/seed<k> (default sweep dir: runs/sweeps/<name>). Every run's config is
resolved before anything starts. Finished runs are skipped; a failed run is reported with its log and retried once
from scratch. A run stopped by a non-finite loss (exit 3) is not retried, by this sweep or the next: a retry repeats
it, so it is kept as it stopped (its stopped.json says where; delete its run dir to train it again).

Named sweeps: configs/sweep/, and sweep/ of your config_dir=DIR or REFPO_CONFIG_PATH folders; `refpo sweep --list
[config_dir=DIR]` lists them with their descriptions.

Examples:
    refpo sweep cpu_dmc                                  # then: refpo report runs/sweeps/cpu_dmc
    refpo sweep cpu_dmc tasks=dmc_point_mass seeds=[1]   # a subset of the grid
    refpo sweep cpu_dmc methods=refpo algorithm.reflow_coef=[0.02,0.08] out=runs/sweeps/lambda
    refpo sweep paper_dmc --dry-run                      # list the runs and their states, train nothing
    taskset -c 0,1 refpo sweep cpu_dmc --launcher "taskset -c 1"   # keep the sweep and its runs on chosen cores
    refpo sweep paper_dmc --backend ray --ray-address auto  # on the head of a Ray cluster: a GPU per run

Sweep-level options (key=value; lists as key=[a,b]):
{options_help(SweepOptions)}
Any other key=value is a run option for every run (refpo train's keys, config_dir= included); a list expands the
grid unless the option itself takes a list.
Flags: --list, --explain [KEYS] (the sweep-level options' values and where they come from), --jobs N runs at a time
(default: the CPU cores; on CUDA one per GPU; more share the GPUs round-robin), --dry-run.
{BACKEND_HELP}
Exit code 1: some run failed (the summary names it and its log).
"""
FLAGS = (
    Flag("--jobs", int, "runs at a time"),
    Flag("--dry-run", doc="list the runs and their states, train nothing"),
    Flag("--list", doc="list the named sweeps with their descriptions"),
    EXPLAIN,
    *BACKEND_FLAGS,
)
SUBJECTS = 1


def run(args: Arguments) -> int | None:
    if args.flag("--list"):
        print(named_files("sweep", args.options))
        return None
    if "--explain" in args.flags:
        every = lambda key: True  # noqa: E731  (every other key: a run option, passed on)
        print(explain_options("sweep", SweepOptions, args.options, args.flag("--explain") or "", every))
        return None
    if not args.subjects:
        raise ConfigError(
            "refpo sweep needs a sweep: a name (configs/sweep/<name>.yaml) or a YAML file; see refpo sweep --help"
        )
    from refpo_warp.studies.grid.spec import load_sweep
    from refpo_warp.studies.sweep import run_sweep

    signal.signal(signal.SIGTERM, signal.default_int_handler)  # stop the runs cleanly on SIGTERM too
    summary = run_sweep(
        load_sweep(args.subjects[0], args.options),
        jobs=args.flag("--jobs"),
        dry_run=args.flag("--dry-run", False),
        **backend_arguments(args),
    )
    if summary.interrupted:
        return EXIT_INTERRUPTED
    return 0 if summary.ok else EXIT_UNEXPECTED
