"""``refpo plot``: training-curve figures of runs or of a sweep."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from refpo_warp.config.command_options import EXPLAIN, command_help, options_or_explain
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError, DataFileError
from refpo_warp.utils.option_rules import ListOf, Text
from refpo_warp.utils.options import option


@dataclass(frozen=True)
class PlotOptions:
    run_dirs: list[str] | None = option(
        None, ListOf(Text(), optional=True), "runs (refpo train's run dirs) sharing one figure"
    )
    out: str | None = option(
        None, Text(optional=True), "the folder the figures go to (default: the run dir / sweep dir)"
    )


SUMMARY = "training-curve figures of runs (progress.jsonl) or of a sweep"
USAGE = command_help(
    "Training curves: refpo plot run_dirs=[PATH,PATH2,...] [out=DIR]\n"
    "             or: refpo plot <sweep dir> [out=DIR]",
    """Reads progress.jsonl of each run and writes curves.png (evaluation returns at 10 and 1 flow steps with the gap
shaded, or the training return; training episode length; success where the task has it) and curves_diagnostics.png
(max ratio, clip fraction, Explosion Rate, Straightness Error). Several run dirs share one figure, e.g. FPO vs ReFPO
on the same task. With a sweep dir (as refpo report takes it), one <task>_curves.png per task of the sweep: a line
per method, the mean over its seeds with their range as a band, and each seed's episode length and return at the
start and the end.""",
    PlotOptions,
)
FLAGS = (EXPLAIN,)
SUBJECTS = 1


def run(args: Arguments) -> None:
    parsed = options_or_explain("plot", PlotOptions, args)
    if parsed is None:
        return
    options = parsed[0]
    runs = options.run_dirs or []
    sweep = args.subjects[0] if args.subjects else None
    if bool(runs) == bool(sweep):
        raise ConfigError(
            f"refpo plot expects run_dirs=[PATH,...] or a sweep dir, and optionally out=DIR; "
            f"got {' '.join(args.subjects + args.options) or 'nothing'}"
        )
    from refpo_warp.evaluation.curves import plot_runs
    from refpo_warp.studies.reports.figures import sweep_curves

    if sweep and not Path(sweep).is_dir():
        raise DataFileError(f"{sweep}: no such directory (a refpo sweep output dir, e.g. runs/sweeps/cpu_humanoid)")
    for path in sweep_curves(sweep, options.out) if sweep else plot_runs(runs, options.out):
        print(path)
