"""One trial of a tuning study: its runs (one per task) trained by the grid's executor with the study's launcher (local
processes or Ray tasks, a failed run retried from scratch), the objective reported to Optuna at every periodic
evaluation that all its runs have reached, and its runs stopped when the trial is pruned or a run failed for good.

A trial's folder (``<out>/<method>/trial<k>``) holds its runs and the executor's ``status.json``; a run that had
finished in an earlier attempt of the trial (its ``eval.json`` of the same config) is kept.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from refpo_warp.studies.grid.executor import Launcher, Summary, SweepExecutor
from refpo_warp.studies.grid.run_metrics import run_metrics
from refpo_warp.studies.grid.spec import Run, Sweep, fingerprint
from refpo_warp.studies.grid.state import KEPT_STATES, LOG_FILE, run_state
from refpo_warp.studies.tuning.spec import Tuning
from refpo_warp.studies.tuning.values import run_config

POLL_S = 2.0  # how often the trial reads its runs' periodic evaluations
# The periodic return the pruner reads: a flow's N = 10 (as the objective's 10-step column), else a Gaussian's mean.
CURVE_KEYS = ("eval/return_N10", "eval/return")


def periodic_returns(run_dir: Path) -> list[float]:
    """The periodic evaluation returns logged so far (``progress.jsonl``; a line being written is skipped)."""
    path = run_dir / "progress.jsonl"
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        for key in CURVE_KEYS:
            if key in row:
                out.append(float(row[key]))
                break
    return out


def study_sweep(tuning: Tuning, out_dir: Path, runs: list[Run] | None = None) -> Sweep:
    """The tuning (``out_dir``: its folder) or one trial (its folder and runs) as the grid the executor and its
    launchers run: the tuning's device, tasks and seed."""
    runs = runs or []
    return Sweep(
        name=tuning.name,
        source=tuning.source,
        description=tuning.description,
        device=tuning.device,
        tasks=list(tuning.tasks),
        seeds=[tuning.seed],
        methods=[runs[0].method] if runs else [],
        out_dir=out_dir,
        report={},
        runs=runs,
    )


@dataclass
class TrialResult:
    state: str  # complete | pruned | failed | interrupted
    score: float | None
    values: dict[str, dict[str, float]]  # task -> run metrics (final evaluation)
    seconds: float
    why: str = ""


class TrialWatch:
    """The executor's ``watch`` for one trial: a run failed for good fails the trial; otherwise every periodic
    evaluation all runs have reached is reported, and a pruned trial stops."""

    def __init__(self, tuning: Tuning, runs: list[Run], trial, executor: SweepExecutor) -> None:
        self.tuning, self.runs, self.trial, self.executor = tuning, runs, trial, executor
        self.reported, self.read_at, self.state = 0, 0.0, ""

    def __call__(self, summary: Summary) -> str:
        if summary.failed:
            key = summary.failed[0][0]
            run = next(r for r in self.runs if r.key == key)
            self.state = "failed"
            code = self.executor.status.get(key, {}).get("exit_codes", [None])[-1]
            return f"{run.task} exited {code}; log {run.run_dir / LOG_FILE}"
        ended = len(summary.finished) + len(summary.skipped) == len(self.runs)
        if not ended and time.monotonic() - self.read_at < POLL_S:
            return ""
        self.read_at = time.monotonic()
        curves = {run.task: periodic_returns(run.run_dir) for run in self.runs}
        common = min(len(c) for c in curves.values())
        reference = self.tuning.objective.reference
        while self.reported < common:
            step = self.reported
            self.trial.report(sum(curves[t][step] / reference[t] for t in reference) / len(reference), step)
            self.reported += 1
            if self.trial.should_prune():
                self.state = "pruned"
                return f"at periodic evaluation {self.reported}"
        return ""


class TrialRunner:
    """Trains one trial's runs with ``launcher`` (``retries`` of a failed run) and scores the trial."""

    def __init__(self, tuning: Tuning, launcher: Launcher, retries: int = 1, echo=print) -> None:
        self.tuning, self.launcher, self.retries, self.echo = tuning, launcher, retries, echo

    def run(self, runs: list[Run], trial, origin: str) -> TrialResult:
        """``origin`` heads each run's log (``tune <name>, <method> trial <k>``) and tags the progress lines."""
        started = time.monotonic()
        prints = {run.key: fingerprint(run_config(self.tuning, run)) for run in runs}
        states = {run.key: run_state(run, prints[run.key]) for run in runs}
        kept = [(run, states[run.key]) for run in runs if states[run.key] in KEPT_STATES]
        todo = [run for run in runs if states[run.key] not in KEPT_STATES]
        if kept:
            self.echo("        kept run(s) of an earlier attempt: " + ", ".join(f"{r.task} ({s})" for r, s in kept))
        grid = study_sweep(self.tuning, runs[0].run_dir.parent, runs)
        executor = SweepExecutor(grid, self.launcher, self.retries, self.echo, origin=origin, tag=origin)
        watch = TrialWatch(self.tuning, runs, trial, executor)
        summary = executor.execute(todo, prints, kept, watch)
        seconds = time.monotonic() - started
        if summary.interrupted:
            return TrialResult("interrupted", None, {}, seconds)
        if summary.stopped:
            return TrialResult(watch.state, None, {}, seconds, summary.stopped)
        values: dict[str, dict[str, Any]] = {}
        for run in runs:
            values[run.task] = run_metrics(json.loads((run.run_dir / "eval.json").read_text()))[0]
        metric = self.tuning.objective.metric
        missing = [t for t, v in values.items() if metric not in v]
        if missing:
            return TrialResult("failed", None, values, seconds, f"eval.json of {missing} has no '{metric}'")
        score = self.tuning.objective.score({t: v[metric] for t, v in values.items()})
        return TrialResult("complete", score, values, seconds)
