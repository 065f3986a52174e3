"""``refpo tune``: an equal tuning budget for several methods (Optuna), resumable."""

from __future__ import annotations

import signal

from refpo_warp.cli.backend_flags import BACKEND_FLAGS, BACKEND_HELP, BACKEND_USAGE, backend_arguments
from refpo_warp.config.command_options import EXPLAIN, explain_options, named_files, options_help
from refpo_warp.studies.tuning.spec import TuneOptions
from refpo_warp.utils.command_line import Arguments, Flag
from refpo_warp.utils.errors import EXIT_INTERRUPTED, ConfigError

SUMMARY = "an equal tuning budget for several methods (Optuna studies of training runs), resumable"
USAGE = f"""Tune: refpo tune <tuning name or file> [trials=N] [methods=[a,b]] [out=DIR] [config_dir=DIR] [--jobs N]
      [--dry-run] {BACKEND_USAGE}

One Optuna study per method of the tuning file (configs/tune/<name>.yaml, or tune/ of your config_dir=DIR or
REFPO_CONFIG_PATH folders): methods take turns, one trial each per round, until each has spent `trials`. A trial
trains one run per task on the tuning seed (`refpo train` processes in <out>/<method>/trial<k>/<task>, run as a
sweep's runs are: locally or on Ray, a failed run retried from scratch) and is scored by the file's objective; its
first trials are the enqueued values (the method's own config), then TPE samples the declared space; a trial far
behind earlier ones at a periodic evaluation is pruned. Every config resolves before anything starts. Interrupted
(Ctrl-C, a killed session), it resumes where it stopped: the studies are in <out>/journal.log, and a cut-off trial
is trained again with the same values (its finished runs kept).
Records: <out>/trials.csv (every trial: values, state, score, returns), <out>/chosen.yaml (each method's best).

Named tunings: `refpo tune --list [config_dir=DIR]` lists them with their descriptions.

Examples:
    refpo tune cpu_dmc --dry-run        # validate, show the objective, the enqueued values and the spaces
    refpo tune cpu_dmc --jobs 2         # default out: runs/tune/cpu_dmc
    refpo tune cpu_dmc trials=12        # raise every method's budget; finished trials are kept

Options (key=value; lists as key=[a,b]):
{options_help(TuneOptions)}

Flags: --list, --explain [KEYS] (each option's value and where it comes from), --jobs N runs of a trial at a time
(default: its tasks, at most the CPU cores; one torch thread each on a CPU), --dry-run.
{BACKEND_HELP}
Needs Optuna: pip install "refpo-warp[tune]".
"""
FLAGS = (
    Flag("--jobs", int, "runs of a trial at a time"),
    Flag("--dry-run", doc="validate and list, train nothing"),
    Flag("--list", doc="list the named tunings with their descriptions"),
    EXPLAIN,
    *BACKEND_FLAGS,
)
SUBJECTS = 1


def run(args: Arguments) -> int | None:
    if args.flag("--list"):
        print(named_files("tune", args.options))
        return None
    if "--explain" in args.flags:
        print(explain_options("tune", TuneOptions, args.options, args.flag("--explain") or ""))
        return None
    if not args.subjects:
        raise ConfigError(
            "refpo tune needs a tuning: a name (configs/tune/<name>.yaml) or a YAML file; see refpo tune --help"
        )
    from refpo_warp.studies.tuning.spec import load_tuning
    from refpo_warp.studies.tuning.study import Tuner

    tuner = Tuner(load_tuning(args.subjects[0], args.options), jobs=args.flag("--jobs"), **backend_arguments(args))
    signal.signal(signal.SIGTERM, signal.default_int_handler)  # stop the runs cleanly on SIGTERM too
    return 0 if tuner.run(dry_run=args.flag("--dry-run", False)) else EXIT_INTERRUPTED
