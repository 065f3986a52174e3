"""``refpo report``: the tables and figures of a sweep."""

from __future__ import annotations

from dataclasses import dataclass

from refpo_warp.config.command_options import EXPLAIN, command_help, options_or_explain
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import Int, ListOf, Text
from refpo_warp.utils.options import option


@dataclass(frozen=True)
class ReportOptions:
    out: str | None = option(None, Text(optional=True), "write there instead of <sweep dir>/report")
    latency: str | None = option(
        None,
        Text(optional=True),
        "latency JSON of `refpo bench latency out=PATH` (default <sweep dir>/latency.json)",
    )
    curve_methods: list[str] | None = option(
        None,
        ListOf(Text(), optional=True),
        "method labels in Figure 3 (default: the sweep's report.curve_methods, else all)",
    )
    ratio_tasks: list[str] | None = option(
        None,
        ListOf(Text(), optional=True),
        "tasks of Figure 4 (default: the sweep's report.ratio_tasks, else the first three)",
    )
    ratio_methods: list[str] | None = option(
        None,
        ListOf(Text(), optional=True),
        "method labels of Figure 4 (default: the sweep's report.ratio_methods, else all)",
    )
    ratio_seed: int | None = option(
        None, Int(0, optional=True), "the seed shown in Figure 4 (default: the lowest seed every chosen run finished)"
    )


SUMMARY = "the paper's tables (Markdown, CSV) and figures of a sweep dir"
USAGE = command_help(
    "Report of a sweep: refpo report <sweep dir> [key=value ...]",
    """Reads every run's eval.json and progress.jsonl (the runs listed in <sweep dir>/sweep.yaml, written by
refpo sweep; without it, every <task>/<label>/seed<k> dir) and writes <sweep dir>/report/: report.md (the
paper's DMC table, the per-task table, the Appendix C table, figures, missing runs), main.csv, per_task.csv,
appendix_c.csv, runs.csv, fig3_reward_curves.png, fig4_ratio_spikes.png and, with a latency JSON,
fig5b_latency.png.

Example: refpo sweep cpu_dmc && refpo report runs/sweeps/cpu_dmc out=docs/results/cpu_dmc curve_methods=[ppo,refpo]""",
    ReportOptions,
)
FLAGS = (EXPLAIN,)
SUBJECTS = 1


def run(args: Arguments) -> None:
    parsed = options_or_explain("report", ReportOptions, args)
    if parsed is None:
        return
    if not args.subjects:
        raise ConfigError("refpo report needs a sweep dir (written by refpo sweep); see refpo report --help")
    options = parsed[0]
    from refpo_warp.studies.reports.report import write_report

    written = write_report(
        args.subjects[0],
        options.out,
        options.latency,
        options.curve_methods,
        options.ratio_tasks,
        options.ratio_methods,
        options.ratio_seed,
    )
    text = written[0].read_text()  # report.md: print its title and the DMC table, then the files
    print(text[: text.index("Each method cell")].rstrip() if "Each method cell" in text else text)
    print("\nwritten:\n" + "\n".join(f"  {path}" for path in written))
