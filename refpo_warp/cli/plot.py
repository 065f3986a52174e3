"""``refpo plot``: training-curve figures of runs or of a sweep."""

from __future__ import annotations

from pathlib import Path

from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError, DataFileError

SUMMARY = "training-curve figures of runs (progress.jsonl) or of a sweep"
USAGE = """Training curves: refpo plot run_dir=PATH [run_dir=PATH2 ...] [out=DIR]
                 or: refpo plot <sweep dir> [out=DIR]

Reads progress.jsonl of each run and writes curves.png (evaluation returns at 10 and 1 flow steps with the gap
shaded, or the training return; training episode length; success where the task has it) and curves_diagnostics.png
(max ratio, clip fraction, Explosion Rate, Straightness Error). Several run dirs share one figure, e.g. FPO vs ReFPO
on the same task. With a sweep dir (as refpo report takes it), one <task>_curves.png per task of the sweep: a line
per method, the mean over its seeds with their range as a band, and each seed's episode length and return at the
start and the end.
"""
FLAGS = ()
SUBJECTS = 1
RENAMED = {"sweep=": "refpo plot <sweep dir>"}  # the spelling refpo plot once took


def run(args: Arguments) -> None:
    args.only("plot", ("run_dir", "out"))
    runs, outs = args.values("run_dir"), args.values("out")
    sweep = args.subjects[0] if args.subjects else None
    if bool(runs) == bool(sweep) or len(outs) > 1:
        raise ConfigError(
            f"refpo plot expects run_dir=PATH [run_dir=...] or a sweep dir, and optionally one out=DIR; "
            f"got {' '.join(args.subjects + args.options) or 'nothing'}"
        )
    out = outs[0] if outs else None
    from refpo_warp.evaluation.curves import plot_runs
    from refpo_warp.sweeps.figures import sweep_curves

    if sweep and not Path(sweep).is_dir():
        raise DataFileError(f"{sweep}: no such directory (a refpo sweep output dir, e.g. runs/sweeps/cpu_humanoid)")
    for path in sweep_curves(sweep, out) if sweep else plot_runs(runs, out):
        print(path)
