#!/usr/bin/env python
"""Report of a sweep: python tools/report.py <sweep dir> [options]

Reads every run's eval.json and progress.jsonl (the runs listed in <sweep dir>/sweep.yaml, written by
tools/sweep.py; without it, every <task>/<label>/seed<k> dir) and writes <sweep dir>/report/: report.md (the
paper's DMC table, the per-task table, the Appendix C table, figures, missing runs), main.csv, per_task.csv,
appendix_c.csv, runs.csv, fig3_reward_curves.png, fig4_ratio_spikes.png and, with a latency JSON,
fig5b_latency.png.

Options:
    --out DIR               write there instead of <sweep dir>/report
    --latency PATH          latency JSON of `tools/bench.py latency --json PATH` (default <sweep dir>/latency.json)
    --curve-methods a,b     method labels in Figure 3 (default: the sweep's report.curve_methods, else all)
    --ratio-tasks a,b       tasks of Figure 4 (default: the sweep's report.ratio_tasks, else the first three)
    --ratio-methods a,b     method labels of Figure 4 (default: the sweep's report.ratio_methods, else all)
    --seed K                seed shown in Figure 4 (default: the lowest seed every chosen run finished)

Example: python tools/sweep.py cpu_dmc && python tools/report.py runs/sweeps/cpu_dmc
"""

import argparse
import sys


def _names(text):
    return [t.strip() for t in text.split(",") if t.strip()] if text else None


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="tools/report.py", add_help=False)
    parser.add_argument("sweep_dir", nargs="?")
    parser.add_argument("--out")
    parser.add_argument("--latency")
    parser.add_argument("--curve-methods")
    parser.add_argument("--ratio-tasks")
    parser.add_argument("--ratio-methods")
    parser.add_argument("--seed", type=int)
    parser.add_argument("-h", "--help", action="store_true")
    args = parser.parse_args(argv)
    if args.help or not args.sweep_dir:
        print(__doc__)
        return 0 if args.help else 2
    from refpo_warp.sweeps.report import write_report
    from refpo_warp.utils.errors import ConfigError

    try:
        written = write_report(args.sweep_dir, args.out, args.latency, _names(args.curve_methods),
                               _names(args.ratio_tasks), _names(args.ratio_methods), args.seed)  # fmt: skip
    except (FileNotFoundError, ValueError, ConfigError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    text = written[0].read_text()  # report.md: print its title and the DMC table, then the files
    print(text[: text.index("Each method cell")].rstrip() if "Each method cell" in text else text)
    print("\nwritten:\n" + "\n".join(f"  {path}" for path in written))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
