#!/usr/bin/env python
"""One per-task table from several sweeps' reports, for the pages that set new methods beside the committed ones:

    python docs/results/compare.py OUT.md REPORT_DIR[:label,label,...][#note] [REPORT_DIR[:labels][#note] ...]

Each REPORT_DIR is a ``refpo report`` output folder (its ``per_task.csv`` and ``runs.csv``); the labels pick and order
its methods (default: all); a ``#note`` is added to the names of its methods (to tell two grids of one method
apart). Writes the Markdown table between the markers ``<!-- compare: begin -->`` and
``<!-- compare: end -->`` of OUT.md: per task and method, mean ± population std over seeds of the 10-step and 1-step
returns under random and zero initial noise, each method's own headline return (its first protocol at its largest
N: FPO++'s N = 64 from zero noise), Straightness, Explosion, the one-step error, the runs whose training
reward falls off a cliff by FPO++'s rule, the training minutes, and how many (task, seed) pairs keep the 1-step
return at 0.9 × the 10-step one or better. Nothing in the table is typed in by hand.
"""

from __future__ import annotations

import csv
import statistics
import sys
from pathlib import Path

BEGIN, END = "<!-- compare: begin -->", "<!-- compare: end -->"
TASK_ORDER = ("dmc_cartpole_balance", "dmc_point_mass", "dmc_reacher_easy")


def value(row: dict, key: str) -> float | None:
    text = row.get(key, "")
    return float(text) if text not in ("", None) else None


def mean_and_spread(mean: float, spread: float | None) -> str:
    """``mean ± spread`` (no spread: the mean alone), the mean to 3 significant digits below 100."""
    shown = f"{mean:.0f}" if abs(mean) >= 100 else f"{mean:.3g}"
    return shown if spread is None else f"{shown} ± {spread:.0f}"


def stat(row: dict, metric: str, std: bool = True) -> str:
    mean, spread = value(row, f"{metric}_mean"), value(row, f"{metric}_std")
    if mean is None:
        return "--"
    return mean_and_spread(mean, spread if std and value(row, f"{metric}_n") != 1 else None)


def one_step_holds(mine: list[dict]) -> str:
    """(task, seed) pairs of a method whose 1-step return is at least 0.9 x its 10-step one, of its finished runs
    ``mine``."""
    found = [(value(r, "return_1"), value(r, "return_multi")) for r in mine]
    pairs = [(one, multi) for one, multi in found if one is not None and multi is not None]
    return f"{sum(one >= 0.9 * multi for one, multi in pairs)}/{len(pairs)}" if pairs else "--"


def headline_cell(runs: list[dict]) -> str:
    """Mean ± population std of the runs' own headline return (runs.csv ``return_headline``), with its setting
    (``N=64/zero`` for FPO++); ``--`` for a report without the column."""
    values = [float(r["return_headline"]) for r in runs if r.get("return_headline")]
    if not values:
        return "--"
    shown = mean_and_spread(statistics.mean(values), statistics.pstdev(values) if len(values) > 1 else None)
    settings = sorted({r["headline"] for r in runs if r.get("headline")})
    return shown + (f" ({', '.join(settings)})" if settings else "")


def cliff_cell(runs: list[dict]) -> str:
    """Runs whose training reward fell off a cliff by FPO++'s rule / runs long enough for it (``health`` of
    runs.csv); ``n/a`` where no run is long enough, ``--`` for a report without the column."""
    if not runs or "health" not in runs[0]:
        return "--"
    judged = [r for r in runs if r["health"] in ("healthy", "cliff_detected")]
    return f"{sum(r['health'] == 'cliff_detected' for r in judged)}/{len(judged)}" if judged else "n/a"


def rows_of(spec: str) -> list[tuple[dict, list[dict], Path]]:
    spec, _, note = spec.partition("#")
    where, _, labels = spec.partition(":")
    folder = Path(where)
    per_task: list[dict] = list(csv.DictReader((folder / "per_task.csv").open()))
    runs: list[dict] = list(csv.DictReader((folder / "runs.csv").open())) if (folder / "runs.csv").exists() else []
    wanted = labels.split(",") if labels else list(dict.fromkeys(r["label"] for r in per_task))
    rows = [(dict(row), runs, folder) for label in wanted for row in per_task if row["label"] == label]
    for row, _, _ in rows:
        row["method"] += f", {note}" if note else ""
    return rows


def table(specs: list[str]) -> str:
    rows = [entry for spec in specs for entry in rows_of(spec)]
    header = [
        "task",
        "method",
        "runs",
        "10-step",
        "1-step",
        "10-step, zero noise",
        "1-step, zero noise",
        "own headline",
        "1-step ≥ 0.9 × 10-step",
        "Straightness",
        "Explosion",
        "one-step error",
        "cliffs",
        "train min.",
        "source",
    ]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for task in TASK_ORDER:
        for row, runs, folder in (r for r in rows if r[0]["task"] == task):
            mine = [r for r in runs if r["task"] == task and r["label"] == row["label"] and r["status"] == "ok"]
            lines.append(
                "| "
                + " | ".join(
                    [
                        task.removeprefix("dmc_"),
                        row["method"],
                        f"{row['runs_finished']}/{row['runs_total']}",
                        stat(row, "return_multi"),
                        stat(row, "return_1"),
                        stat(row, "return_multi_zero"),
                        stat(row, "return_1_zero"),
                        headline_cell(mine),
                        one_step_holds(mine),
                        stat(row, "straightness", False),
                        stat(row, "explosion", False),
                        stat(row, "one_step", False),
                        cliff_cell(mine),
                        stat(row, "minutes", False),
                        f"`{folder.as_posix()}`",
                    ]
                )
                + " |"
            )
    return "\n".join([BEGIN, *lines, END])


def main(argv: list[str]) -> int:
    if len(argv) < 2:
        print(__doc__)
        return 2
    out = Path(argv[0])
    text = out.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        print(f"{out}: no '{BEGIN}' ... '{END}' markers", file=sys.stderr)
        return 2
    head, rest = text.split(BEGIN, 1)
    out.write_text(head + table(argv[1:]) + rest.split(END, 1)[1], encoding="utf-8")
    print(f"{out}: table written")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
