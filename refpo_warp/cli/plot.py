"""``refpo plot``: training-curve figures of runs or of a sweep."""

from __future__ import annotations

from pathlib import Path

from refpo_warp.cli.arguments import Arguments
from refpo_warp.utils.errors import ConfigError, DataFileError

SUMMARY = "training-curve figures of runs (progress.jsonl) or of a sweep"
USAGE = """Training curves: refpo plot run_dir=PATH [run_dir=PATH2 ...] [out=DIR]
                 or: refpo plot sweep=SWEEP_DIR [out=DIR]

Reads progress.jsonl of each run and writes curves.png (evaluation returns at 10 and 1 flow steps with the gap
shaded, or the training return; training episode length; success where the task has it) and curves_diagnostics.png
(max ratio, clip fraction, Explosion Rate, Straightness Error). Several run dirs share one figure, e.g. FPO vs ReFPO
on the same task. With sweep=, one <task>_curves.png per task of a refpo sweep dir: a line per method, the mean
over its seeds with their range as a band, and each seed's episode length and return at the start and the end.
"""
FLAGS = ()
SUBJECTS = 0


def run(args: Arguments) -> None:
    pairs = [option.split("=", 1) for option in args.options]
    runs = [value for key, value in pairs if key == "run_dir"]
    sweep = next((value for key, value in pairs if key == "sweep"), None)
    out = next((value for key, value in pairs if key == "out"), None)
    unknown = [f"{key}=" for key, _ in pairs if key not in ("run_dir", "sweep", "out")]
    if unknown or bool(runs) == bool(sweep):
        raise ConfigError(f"refpo plot expects run_dir=PATH [run_dir=...] or sweep=DIR, and optionally out=DIR; got "
                          f"{' '.join(args.options) or 'nothing'}")  # fmt: skip
    from refpo_warp.evaluation.curves import plot_runs
    from refpo_warp.sweeps.figures import sweep_curves

    if sweep and not Path(sweep).is_dir():
        raise DataFileError(f"sweep={sweep}: no such directory (a refpo sweep output dir, e.g. "
                            f"runs/sweeps/cpu_humanoid)")  # fmt: skip
    for path in sweep_curves(sweep, out) if sweep else plot_runs(runs, out):
        print(path)
