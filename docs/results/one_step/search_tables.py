#!/usr/bin/env python
"""The tables of ``search.md`` that hold numbers, from the committed data files (nothing typed in by hand):

    python docs/results/one_step/search_tables.py

Writes, between ``<!-- search: <name> -->`` and ``<!-- search: end -->`` markers of search.md: ``full_runs``, the
one-step configuration's (``onestep_c03``) final 10-step / 1-step returns per task and seed from
``search/report/runs.csv``, against ReFPO's (``cpu_dmc/runs.csv``), and ``goal``, the per-task gap of its 10-step mean
to ReFPO's.
"""

from __future__ import annotations

import csv
import re
import statistics
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
PAGE = HERE / "search.md"
SEARCH_RUNS = HERE / "search" / "report" / "runs.csv"
CPU_DMC_RUNS = HERE.parent / "cpu_dmc" / "runs.csv"
TASKS = ("dmc_cartpole_balance", "dmc_point_mass", "dmc_reacher_easy")


def returns(path: Path, label: str, task: str) -> dict[int, tuple[float, float]]:
    """seed -> (10-step, 1-step) final returns of a method's finished runs on a task."""
    rows = csv.DictReader(path.open(encoding="utf-8"))
    return {
        int(r["seed"]): (float(r["return_multi"]), float(r["return_1"]))
        for r in rows
        if r["label"] == label and r["task"] == task and r["status"] == "ok"
    }


def ten_step_means(task: str) -> tuple[float, float]:
    """The 10-step return's mean over seeds: the one-step configuration's and ReFPO's."""
    mine = statistics.mean(v[0] for v in returns(SEARCH_RUNS, "onestep_c03", task).values())
    return mine, statistics.mean(v[0] for v in returns(CPU_DMC_RUNS, "refpo", task).values())


def gap(task: str) -> float:
    mine, refpo = ten_step_means(task)
    return mine / refpo - 1.0


def full_runs() -> str:
    lines = [
        "| task | seed 1: 10-step / 1-step | seed 2 | seed 3 | 1-step ≥ 0.9 × 10-step | 10-step mean against ReFPO's |",
        "|---|---|---|---|---|---|",
    ]
    for task in TASKS:
        runs = returns(SEARCH_RUNS, "onestep_c03", task)
        mean, refpo = ten_step_means(task)
        held = sum(one >= 0.9 * multi for multi, one in runs.values())
        cells = [f"{runs[s][0]:.0f} / {runs[s][1]:.0f}" if s in runs else "--" for s in (1, 2, 3)]
        change = mean / refpo - 1.0
        against = f"{mean:.0f} against {refpo:.0f}: {100 * abs(change):.1f} % {'higher' if change > 0 else 'lower'}"
        lines.append(
            f"| {task.removeprefix('dmc_')} | " + " | ".join(cells) + f" | {held} of {len(runs)} | {against} |"
        )
    return "\n".join(lines)


def goal() -> str:
    return ", ".join(f"{100 * gap(task):+.1f} %" for task in TASKS).replace("-", "\u2212")


def main() -> int:
    text = PAGE.read_text(encoding="utf-8")
    for name, make in (("full_runs", full_runs), ("goal", goal)):
        pattern = re.compile(rf"(<!-- search: {name} -->)(.*?)(<!-- search: end -->)", re.DOTALL)
        if not pattern.search(text):
            print(f"{PAGE}: no '<!-- search: {name} -->' ... '<!-- search: end -->' markers", file=sys.stderr)
            return 2
        body = make()
        body = f"\n{body}\n" if "\n" in body else body
        text = pattern.sub(lambda m, body=body: m.group(1) + body + m.group(3), text)
    PAGE.write_text(text, encoding="utf-8")
    print(f"{PAGE}: tables written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
