"""``refpo report``: the tables and figures of a sweep."""

from __future__ import annotations

from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError

SUMMARY = "the paper's tables (Markdown, CSV) and figures of a sweep dir"
USAGE = """Report of a sweep: refpo report <sweep dir> [out=DIR] [latency=PATH] [curve_methods=a,b] [ratio_tasks=a,b]
                                       [ratio_methods=a,b] [seed=K]

Reads every run's eval.json and progress.jsonl (the runs listed in <sweep dir>/sweep.yaml, written by
refpo sweep; without it, every <task>/<label>/seed<k> dir) and writes <sweep dir>/report/: report.md (the
paper's DMC table, the per-task table, the Appendix C table, figures, missing runs), main.csv, per_task.csv,
appendix_c.csv, runs.csv, fig3_reward_curves.png, fig4_ratio_spikes.png and, with a latency JSON,
fig5b_latency.png.

Options:
    out=DIR                 write there instead of <sweep dir>/report
    latency=PATH            latency JSON of `refpo bench latency --json PATH` (default <sweep dir>/latency.json)
    curve_methods=a,b       method labels in Figure 3 (default: the sweep's report.curve_methods, else all)
    ratio_tasks=a,b         tasks of Figure 4 (default: the sweep's report.ratio_tasks, else the first three)
    ratio_methods=a,b       method labels of Figure 4 (default: the sweep's report.ratio_methods, else all)
    seed=K                  seed shown in Figure 4 (default: the lowest seed every chosen run finished)

Example: refpo sweep cpu_dmc && refpo report runs/sweeps/cpu_dmc out=docs/results/cpu_dmc
"""
FLAGS = ()
OPTIONS = ("out", "latency", "curve_methods", "ratio_tasks", "ratio_methods", "seed")
RENAMED = {f"--{k.replace('_', '-')}": f"{k}=" for k in OPTIONS}  # the flags refpo report once took
SUBJECTS = 1


def _names(text: str | None) -> list[str] | None:
    return [t.strip() for t in text.split(",") if t.strip()] if text else None


def _option(args: Arguments, key: str) -> str | None:
    values = args.values(key)
    if len(values) > 1:
        raise ConfigError(f"refpo report: {key}= given {len(values)} times")
    return values[0] if values else None


def run(args: Arguments) -> None:
    if not args.subjects:
        raise ConfigError("refpo report needs a sweep dir (written by refpo sweep); see refpo report --help")
    args.only("report", OPTIONS)
    seed = _option(args, "seed")
    if seed is not None and not seed.isdigit():
        raise ConfigError(f"seed={seed!r} is invalid; expected a seed (a non-negative integer)")
    from refpo_warp.sweeps.report import write_report

    written = write_report(
        args.subjects[0],
        _option(args, "out"),
        _option(args, "latency"),
        _names(_option(args, "curve_methods")),
        _names(_option(args, "ratio_tasks")),
        _names(_option(args, "ratio_methods")),
        None if seed is None else int(seed),
    )
    text = written[0].read_text()  # report.md: print its title and the DMC table, then the files
    print(text[: text.index("Each method cell")].rstrip() if "Each method cell" in text else text)
    print("\nwritten:\n" + "\n".join(f"  {path}" for path in written))
