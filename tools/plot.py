#!/usr/bin/env python
"""Training curves: python tools/plot.py run_dir=PATH [run_dir=PATH2 ...] [out=DIR]
                 or: python tools/plot.py sweep=SWEEP_DIR [out=DIR]

Reads progress.jsonl of each run and writes curves.png (evaluation returns at 10 and 1 flow steps with the gap
shaded, or the training return; training episode length; success where the task has it) and curves_diagnostics.png
(max ratio, clip fraction, Explosion Rate, Straightness Error). Several run dirs share one figure, e.g. FPO vs ReFPO
on the same task. With sweep=, one <task>_curves.png per task of a tools/sweep.py dir: a line per method, the mean
over its seeds with their range as a band, and each seed's episode length and return at the start and the end.
"""

import sys
from pathlib import Path

from refpo_warp.cli.guard import EXIT_USAGE, run_guarded
from refpo_warp.utils.errors import DataFileError


def main(argv: list[str]) -> int:
    if not argv or any(a in ("-h", "--help") for a in argv):
        print(__doc__)
        return 0 if argv else EXIT_USAGE
    runs = [a.split("=", 1)[1] for a in argv if a.startswith("run_dir=")]
    sweep = next((a.split("=", 1)[1] for a in argv if a.startswith("sweep=")), None)
    out = next((a.split("=", 1)[1] for a in argv if a.startswith("out=")), None)
    unknown = [a for a in argv if not a.startswith(("run_dir=", "sweep=", "out="))]
    if unknown or bool(runs) == bool(sweep):
        print(f"error: expected run_dir=PATH [run_dir=...] or sweep=DIR, and optionally out=DIR; got {argv}",
              file=sys.stderr)
        return EXIT_USAGE

    def plot() -> None:
        from refpo_warp.evaluation.curves import plot_runs
        from refpo_warp.sweeps.figures import sweep_curves

        if sweep and not Path(sweep).is_dir():
            raise DataFileError(f"sweep={sweep}: no such directory (a tools/sweep.py output dir, e.g. "
                                f"runs/sweeps/cpu_humanoid)")  # fmt: skip
        for path in sweep_curves(sweep, out) if sweep else plot_runs(runs, out):
            print(path)

    return run_guarded(plot)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
