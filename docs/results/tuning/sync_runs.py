"""make_page.py --sync, --sync-fresh and --sync-budget: a study's, a fresh-seed sweep's and a budget sweep's small
files copied here (a run stopped on a non-finite loss: its periodic evaluations read back from its console log)."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

from study_files import BUDGET, FRESH, REPO, STUDY

from refpo_warp.studies.reports.committed_runs import append_runs, copy_run
from refpo_warp.utils.errors import DataFileError


# ------------------------------------------------------------------------------------------------ copying
def copy_runs(src: Path, dst: Path) -> int:
    """Every finished run under ``src`` (a folder with eval.json): its small files into the same place under dst."""
    runs = [evaluation.parent for evaluation in sorted(src.rglob("eval.json"))]
    for run in runs:
        copy_run(run, dst / run.relative_to(src))
    return len(runs)


def sync_study(src: Path) -> None:
    STUDY.mkdir(exist_ok=True)
    for name in ("journal.log", "trials.csv", "chosen.yaml", "evaluate.yaml"):
        if (src / name).exists():
            shutil.copy2(src / name, STUDY / name)
    runs = copy_runs(src, STUDY / "runs")
    print(f"copied the study's records and {runs} finished trial run(s) from {src}")


def sync_fresh(src: Path) -> None:
    """Append the fresh-seed sweep's runs that ``fresh/runs.csv`` lacks (its report's rows, each run's small files):
    seeds run in later calls join the committed ones. The report's per_task.csv is copied once, for the methods'
    names."""
    FRESH.mkdir(exist_ok=True)
    if not (FRESH / "per_task.csv").exists():
        shutil.copy2(src / "report" / "per_task.csv", FRESH / "per_task.csv")
    added = append_runs(src, FRESH / "runs.csv", FRESH / "runs", REPO)
    print(f"appended {added} run(s) of {src / 'report'}'s runs.csv to {FRESH / 'runs.csv'}")


# A console line of a periodic evaluation: "[it  43/263]  steps     675,840 ... return_N10 562.4  return_N1 568.2 ..."
EVAL_LINE = re.compile(r"^\[it +(\d+)/\d+\] +steps +([\d,]+) .*?((?: +return_N\w+ +[-\d.e+]+)+)\s*$")
STOP_LINE = "error: training stopped: Non-finite"


def stopped_run(run: Path, dst: Path) -> bool:
    """A run whose training stopped on a non-finite loss (no eval.json): its periodic evaluations read back from its
    first attempt's console log (a retry from scratch replaces progress.jsonl), and stopped.json with where it stopped.
    Its curve counts as 0 after that point: the run has no policy to deploy past it."""
    logs = sorted(run.glob("train.attempt*.log"))
    if (run / "eval.json").exists() or not logs:
        return False
    lines = logs[0].read_text(encoding="utf-8").splitlines()
    stop = next((line for line in lines if line.startswith(STOP_LINE)), None)
    if stop is None:
        return False
    rows, last = [], None
    for line in lines:
        match = EVAL_LINE.match(line)
        if line.startswith("[it "):
            last = line
        if match:
            pairs = match.group(3).split()
            row: dict[str, float] = {
                "iteration": int(match.group(1)),
                "env_steps": int(match.group(2).replace(",", "")),
            }
            row.update({f"eval/{k}": float(v) for k, v in zip(pairs[::2], pairs[1::2], strict=True)})
            rows.append(row)
    stopped_at = re.match(r"^\[it +(\d+)/\d+\] +steps +([\d,]+)", last or "")
    if stopped_at is None:
        raise DataFileError(f"{logs[0]}: no '[it N/M] steps S' line before its '{STOP_LINE}' line")
    dst.mkdir(parents=True, exist_ok=True)
    if (run / "config.yaml").exists():
        shutil.copy2(run / "config.yaml", dst / "config.yaml")
    (dst / "progress_eval.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    where = {"iteration": int(stopped_at.group(1)), "env_steps": int(stopped_at.group(2).replace(",", ""))}
    (dst / "stopped.json").write_text(json.dumps({**where, "reason": stop[len("error: ") :][:160]}) + "\n")
    return True


def sync_budget(src: Path) -> None:
    stopped = sum(stopped_run(run, BUDGET / run.relative_to(src)) for run in sorted(src.glob("*/*/seed*")))
    print(f"copied {copy_runs(src, BUDGET)} finished and {stopped} stopped budget run(s) from {src}")
