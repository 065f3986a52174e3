#!/usr/bin/env python
"""Training curves: python tools/plot.py run_dir=PATH [run_dir=PATH2 ...] [out=DIR]

Reads progress.jsonl of each run and writes curves.png (evaluation returns at 10 and 1 flow steps with the gap
shaded, or the training return; training episode length; success where the task has it) and curves_diagnostics.png
(max ratio, clip fraction, Explosion Rate, Straightness Error). Several run dirs share one figure, e.g. FPO vs ReFPO
on the same task.
"""

import sys

from refpo_warp.cli import EXIT_USAGE, run_guarded


def main(argv: list[str]) -> int:
    if not argv or any(a in ("-h", "--help") for a in argv):
        print(__doc__)
        return 0 if argv else EXIT_USAGE
    runs = [a.split("=", 1)[1] for a in argv if a.startswith("run_dir=")]
    out = next((a.split("=", 1)[1] for a in argv if a.startswith("out=")), None)
    unknown = [a for a in argv if not a.startswith(("run_dir=", "out="))]
    if unknown or not runs:
        print(f"error: expected run_dir=PATH [out=DIR], got {unknown or argv}", file=sys.stderr)
        return EXIT_USAGE

    def plot() -> None:
        from refpo_warp.plots import plot_runs

        for path in plot_runs(runs, out):
            print(path)

    return run_guarded(plot)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
