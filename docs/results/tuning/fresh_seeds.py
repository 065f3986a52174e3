"""The chosen values on fresh seeds (fresh/runs.csv) against the committed runs at the paper's values: per method and
task the runs, their means and intervals, the probabilities of improvement, and the page's fresh-seed table."""

from __future__ import annotations

import csv
import statistics
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from study_files import COMMITTED, FLOWS, FRESH, LABELS, NAMES, TASKS, number, short

from refpo_warp.studies.reports.committed_runs import seeds_text


# ------------------------------------------------------------------------------------------------ fresh seeds
@dataclass
class Runs:
    """One method's runs in one runs.csv: task -> seed -> (N = 10 return (a Gaussian's mean action), N = 1 return
    or None). A failed run (its training stopped, e.g. on a non-finite loss) counts as return 0 at both: leaving it
    out would flatter its method; ``failed`` holds its note."""

    returns: dict[str, dict[int, tuple[float, float | None]]] = field(default_factory=dict)
    failed: dict[tuple[str, int], str] = field(default_factory=dict)


def read_runs(path: Path, label: str) -> Runs:
    out = Runs()
    if not path.exists():
        return out
    for r in csv.DictReader(path.open(encoding="utf-8")):
        if r["label"] != label:
            continue
        if r["status"] == "ok" and r["return_multi"]:
            out.returns.setdefault(r["task"], {})[int(r["seed"])] = (
                float(r["return_multi"]),
                number(r.get("return_1")),
            )
        elif r["status"] == "failed":
            out.returns.setdefault(r["task"], {})[int(r["seed"])] = (0.0, 0.0)
            out.failed[(r["task"], int(r["seed"]))] = r.get("note") or ""
    return out


@dataclass
class Row:
    label: str
    kind: str  # "paper" (the committed rows) or "tuned" (fresh seeds)
    runs: Runs
    seeds: list[int]  # the seeds every task has: the rows of the score matrix
    left_out: list[str]  # runs of a seed some task lacks (a sweep still under way)
    per_task: list  # Estimate of the mean N = 10 return per task

    @property
    def key(self) -> str:
        return f"{self.label}/{self.kind}"

    def values(self, task: str) -> list[tuple[int, float, float | None, bool]]:
        """(seed, N = 10, N = 1, failed) of the row's runs on the task."""
        return [(s, *self.runs.returns[task][s], (task, s) in self.runs.failed) for s in self.seeds]


@dataclass
class Fresh:
    rows: dict[str, Row]
    iqm: dict
    scale: dict[str, float]
    vs_ppo: dict  # flow label -> P(its tuned run beats a tuned PPO run)
    vs_own: dict  # label -> P(its tuned run beats a run at its own values)


def fresh_analysis() -> Fresh | None:
    from refpo_warp.studies.reports.intervals import aggregate, improvement, mean_estimate

    fresh_csv = FRESH / "runs.csv"
    if not fresh_csv.exists():
        return None
    rows: dict[str, Row] = {}
    for label in LABELS:
        for kind, (path, name) in (("paper", COMMITTED[label][:2]), ("tuned", (fresh_csv, label))):
            runs = read_runs(path, name)
            if not all(runs.returns.get(t) for t in TASKS):
                continue
            seeds = sorted(set.intersection(*(set(runs.returns[t]) for t in TASKS)))
            left = [f"{short(t)}/{name}/seed{s}" for t in TASKS for s in sorted(runs.returns[t]) if s not in seeds]
            per_task = [mean_estimate(runs.returns[t][s][0] for s in seeds) for t in TASKS]
            rows[f"{label}/{kind}"] = Row(label, kind, runs, seeds, left, per_task)
    ppo = rows["ppo/paper"]
    scale = {t: statistics.mean(v for _, v, _, _ in ppo.values(t)) for t in TASKS}
    scores = {
        key: np.array([[r.runs.returns[t][s][0] / scale[t] for t in TASKS] for s in r.seeds]) for key, r in rows.items()
    }
    agg = aggregate(scores)
    vs_ppo = {
        label: improvement(scores[f"{label}/tuned"], scores["ppo/tuned"])
        for label in FLOWS
        if f"{label}/tuned" in rows and "ppo/tuned" in rows
    }
    vs_own = {
        label: improvement(scores[f"{label}/tuned"], scores[f"{label}/paper"])
        for label in LABELS
        if f"{label}/tuned" in rows and f"{label}/paper" in rows
    }
    return Fresh(rows, {k: agg[k]["iqm"] for k in rows}, scale, vs_ppo, vs_own)


def own_name(label: str) -> str:
    return "authors'" if label == "fpo_pp" else "paper's"


def reach(fresh: Fresh, label: str) -> list[bool]:
    """Per task: the tuned method's interval reaches tuned PPO's, or lies above it."""
    mine, ppo = fresh.rows[f"{label}/tuned"].per_task, fresh.rows["ppo/tuned"].per_task
    return [e.overlaps_or_above(q) for e, q in zip(mine, ppo, strict=True)]


def passes(fresh: Fresh, label: str) -> list[bool]:
    """Per task: the tuned method's mean is above tuned PPO's."""
    mine, ppo = fresh.rows[f"{label}/tuned"].per_task, fresh.rows["ppo/tuned"].per_task
    return [e.point > q.point for e, q in zip(mine, ppo, strict=True)]


def one_step_counts(row: Row, share: float, within: float) -> tuple[int, int, int, list[str]]:
    """(held, within, runs, exceptions): runs whose N = 1 ≥ share × N = 10, whose |N = 1 − N = 10| ≤ within × N = 10
    (a failed run counts as neither), and the runs where the first fails, with their returns."""
    held = near = total = 0
    misses = []
    for task in TASKS:
        for seed, multi, one, failed in row.values(task):
            total += 1
            ok = not failed and one is not None and one >= share * multi
            held += ok
            near += not failed and one is not None and abs(one - multi) <= within * multi
            if not ok:
                misses.append(
                    f"{short(task)} seed {seed} failed"
                    if failed
                    else f"{short(task)} seed {seed}: no N = 1 return"
                    if one is None
                    else f"{short(task)} seed {seed}: {one:.0f} against {multi:.0f}, {one / multi:.2f}"
                )
    return held, near, total, misses


def fresh_table(fresh: Fresh | None, crit: dict) -> str:
    if fresh is None:
        return 'Not run yet: the study has to finish first (see "Reproducing and resuming").'
    head = "| method | values | " + " | ".join(short(t) for t in TASKS) + " | IQM (÷ PPO's) |"
    lines = [head, "|---|---|" + "---|" * (len(TASKS) + 1)]
    for key, row in fresh.rows.items():
        values = own_name(row.label) if row.kind == "paper" else "tuned"
        lines.append(
            f"| {NAMES[row.label]} | {values}, seeds {seeds_text(row.seeds)} | "
            + " | ".join(e.text() for e in row.per_task)
            + f" | {fresh.iqm[key].text(2)} |"
        )
    lines.append("")
    for label, poi in fresh.vs_ppo.items():
        lines.append(
            f"- {NAMES[label]} (tuned) against PPO (tuned): its interval reaches PPO's on {sum(reach(fresh, label))} "
            f"of {len(TASKS)} tasks, its mean passes PPO's on {sum(passes(fresh, label))}; P(improvement) {poi.text(2)}"
        )
    failed = [f"{short(t)}/{row.label}/seed{s}" for row in fresh.rows.values() for (t, s) in row.runs.failed]
    if failed:
        lines.append(f"- Failed runs, counted as return 0 at N = 10 and N = 1: {', '.join(failed)}")
    left = [name for row in fresh.rows.values() for name in row.left_out]
    if left:
        lines.append(f"- Left out until every task has their seed: {', '.join(left)}")
    goal = crit["goal"]["one_step"]
    goal_row = fresh.rows.get(f"{goal['method']}/tuned")
    if goal_row is not None:
        held, near, total, _ = one_step_counts(goal_row, goal["share"], crit["report"]["within"])
        lines.append(
            f"- {NAMES[goal_row.label]} (tuned): N = 1 ≥ {goal['share']:g} × N = 10 in {held} of {total} (task, seed) "
            f"pairs; |N = 1 − N = 10| ≤ {crit['report']['within']:g} × N = 10 in {near} of {total}"
        )
    return "\n".join(lines)
