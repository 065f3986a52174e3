"""``refpo report``: the tables and figures of a sweep."""

from __future__ import annotations

from refpo_warp.cli.arguments import Arguments, Flag
from refpo_warp.utils.errors import ConfigError

SUMMARY = "the paper's tables (Markdown, CSV) and figures of a sweep dir"
USAGE = """Report of a sweep: refpo report <sweep dir> [flags]

Reads every run's eval.json and progress.jsonl (the runs listed in <sweep dir>/sweep.yaml, written by
refpo sweep; without it, every <task>/<label>/seed<k> dir) and writes <sweep dir>/report/: report.md (the
paper's DMC table, the per-task table, the Appendix C table, figures, missing runs), main.csv, per_task.csv,
appendix_c.csv, runs.csv, fig3_reward_curves.png, fig4_ratio_spikes.png and, with a latency JSON,
fig5b_latency.png.

Flags:
    --out DIR               write there instead of <sweep dir>/report
    --latency PATH          latency JSON of `refpo bench latency --json PATH` (default <sweep dir>/latency.json)
    --curve-methods a,b     method labels in Figure 3 (default: the sweep's report.curve_methods, else all)
    --ratio-tasks a,b       tasks of Figure 4 (default: the sweep's report.ratio_tasks, else the first three)
    --ratio-methods a,b     method labels of Figure 4 (default: the sweep's report.ratio_methods, else all)
    --seed K                seed shown in Figure 4 (default: the lowest seed every chosen run finished)

Example: refpo sweep cpu_dmc && refpo report runs/sweeps/cpu_dmc
"""
FLAGS = (
    Flag("--out", str, "the report folder"),
    Flag("--latency", str, "a latency JSON file"),
    Flag("--curve-methods", str, "method labels, comma-separated"),
    Flag("--ratio-tasks", str, "task ids, comma-separated"),
    Flag("--ratio-methods", str, "method labels, comma-separated"),
    Flag("--seed", int, "a seed"),
)
SUBJECTS = 1


def _names(text: str | None) -> list[str] | None:
    return [t.strip() for t in text.split(",") if t.strip()] if text else None


def run(args: Arguments) -> None:
    if args.options:
        raise ConfigError(f"refpo report takes a sweep dir and flags, not {args.options[0]}; see refpo report --help")
    if not args.subjects:
        raise ConfigError("refpo report needs a sweep dir (written by refpo sweep); see refpo report --help")
    from refpo_warp.sweeps.report import write_report

    written = write_report(args.subjects[0], args.flag("--out"), args.flag("--latency"),
                           _names(args.flag("--curve-methods")), _names(args.flag("--ratio-tasks")),
                           _names(args.flag("--ratio-methods")), args.flag("--seed"))  # fmt: skip
    text = written[0].read_text()  # report.md: print its title and the DMC table, then the files
    print(text[: text.index("Each method cell")].rstrip() if "Each method cell" in text else text)
    print("\nwritten:\n" + "\n".join(f"  {path}" for path in written))
