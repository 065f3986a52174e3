#!/usr/bin/env python
"""``README.md`` in this folder, written whole from ``README.template.md`` and the values this script computes from
the committed data files (nothing typed in by hand):

    python docs/results/tuning/make_page.py [--check] [--sync runs/tune/cpu_dmc] [--sync-fresh DIR] [--sync-budget DIR]

``--sync`` first copies a study's small files here (``study/``: the Optuna journal, trials.csv, chosen.yaml,
evaluate.yaml, and each trial run's config.yaml, eval.json and periodic-evaluation rows); ``--sync-fresh`` the
fresh-seed sweep's report (``fresh/runs.csv``, from ``refpo report``) and its runs' small files; ``--sync-budget``
the budget sweep's runs' small files (``budget/``). Then it writes README.md
(``refpo_warp/studies/reports/results_page.py``) and ``budget_curves.png``; ``--check`` only compares the page with
what the data says (exit 1 if it differs).

What it reads: ``configs/tune/cpu_dmc.yaml`` (the search), ``study/`` (trials, chosen values, journal times, trial run
configs), ``fresh/runs.csv`` and ``fresh/runs/`` (the chosen values on fresh seeds: every seed the file holds), the
committed rows at the paper's values (``COMMITTED``: every seed those files hold), ``budget.yaml`` and ``budget/``
(the budget curves), ``configs/task/_dmc.yaml`` (the paper's and the CPU profile's budgets and passes) and
``criteria.yaml`` (the thresholds the verdicts test). Every sentence whose verdict depends on the data is written here.
"""

from __future__ import annotations

import csv
import json
import math
import re
import shutil
import statistics
import sys
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

import numpy as np
import yaml

from refpo_warp.studies.reports.committed_runs import copy_run, seeds_text
from refpo_warp.utils.errors import DataFileError

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
REPO = RESULTS.parents[1]
TEMPLATE = HERE / "README.template.md"
STUDY = HERE / "study"
FRESH = HERE / "fresh"
BUDGET = HERE / "budget"
BUDGET_FILE = HERE / "budget.yaml"
CRITERIA = HERE / "criteria.yaml"
TUNING_FILE = REPO / "configs" / "tune" / "cpu_dmc.yaml"
DMC_PROFILE = REPO / "configs" / "task" / "_dmc.yaml"
TASKS = ("dmc_cartpole_balance", "dmc_point_mass", "dmc_reacher_easy")
# The committed rows at the paper's (or the authors') values: (runs.csv, label, where) per method; every seed the
# file holds is read.
COMMITTED = {
    "ppo": (RESULTS / "cpu_dmc" / "runs.csv", "ppo", "`cpu_dmc`"),
    "refpo": (RESULTS / "cpu_dmc" / "runs.csv", "refpo", "`cpu_dmc`"),
    "refpo_onestep": (
        RESULTS / "one_step" / "search" / "report" / "runs.csv",
        "onestep_c03",
        "the one-step search's `onestep_c03`",
    ),
    "fpo_pp": (RESULTS / "fpo_pp" / "report" / "runs.csv", "fpo_pp", "FPO++'s grid"),
}
LABELS = ("ppo", "refpo", "refpo_onestep", "fpo_pp")
FLOWS = ("refpo", "refpo_onestep", "fpo_pp")
NAMES = {"ppo": "PPO", "refpo": "ReFPO", "refpo_onestep": "ReFPO one-step", "fpo_pp": "FPO++"}
CODE_NAMES = {"ppo": "PPO", "refpo": "ReFPO", "refpo_onestep": "`refpo_onestep`", "fpo_pp": "FPO++"}


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
    FRESH.mkdir(exist_ok=True)
    for name in ("runs.csv", "per_task.csv"):
        shutil.copy2(src / "report" / name, FRESH / name)
    print(f"copied {src / 'report'}'s runs.csv and per_task.csv and {copy_runs(src, FRESH / 'runs')} run(s)")


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


# ------------------------------------------------------------------------------------------------ helpers
def _yaml(path: Path) -> dict:
    return yaml.safe_load(Path(path).read_text(encoding="utf-8")) or {}


def _num(text: str | None) -> float | None:
    return float(text) if text not in (None, "") else None


def _fmt(value, digits: int = 3) -> str:
    if value in (None, ""):
        return "--"
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            return value
    if float(value).is_integer() and abs(value) >= 1:
        return str(int(value))
    return f"{value:.{digits}g}"


def and_list(items) -> str:
    items = list(items)
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + " and " + items[-1]


def short(task: str) -> str:
    return task.removeprefix("dmc_")


def steps_text(steps: float) -> str:
    return f"{steps / 1e6:.3g}M"


def times_text(x: float) -> str:
    """A ratio of two values: '4', '0.33', '6.8'."""
    return f"{x:.2g}"


def big_text(x: float) -> str:
    """A value that may be huge: '351', '2.2e10'."""
    return f"{x:.0f}" if abs(x) < 1e4 else re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", f"{x:.2g}")


def share_text(x: float) -> str:
    """0.1 -> '10 %'."""
    return f"{100 * x:g} %"


# ------------------------------------------------------------------------------------------------ the study
def trials() -> list[dict]:
    path = STUDY / "trials.csv"
    return list(csv.DictReader(path.open(encoding="utf-8"))) if path.exists() else []


def own_trial(label: str) -> dict | None:
    """A method's first trial, its own values (enqueued), as trials.csv records it."""
    mine = [r for r in trials() if r["method"] == label]
    return next((r for r in mine if r["enqueued"] == "True"), None) or next(
        (r for r in mine if r["trial"] == "0"), None
    )


def own_values(label: str) -> dict:
    """``own_trial`` where the page needs it: an error naming the file when trials.csv has none."""
    own = own_trial(label)
    if own is None:
        raise DataFileError(f"{STUDY / 'trials.csv'}: no trial of '{label}' at its own values (enqueued or trial 0)")
    return own


def chosen() -> dict:
    path = STUDY / "chosen.yaml"
    return _yaml(path) if path.exists() else {}


def profile_values() -> dict[str, dict]:
    """Each method's values of its searched options at the CPU profile as the configs resolve them today."""
    from refpo_warp.studies.tuning.spec import load_tuning
    from refpo_warp.studies.tuning.values import config_values

    tuning = load_tuning(str(TUNING_FILE))
    return {m.label: config_values(tuning, m) for m in tuning.methods}


def _same(a: dict, b: dict) -> bool:
    return set(a) == set(b) and all(math.isclose(float(a[k]), float(b[k]), rel_tol=1e-9) for k in a)


def spaces_table(profile: dict[str, dict]) -> str:
    spec = _yaml(TUNING_FILE)
    lines = [
        "| method | option | searched | first trial (its own values, `study/trials.csv`) | CPU profile today |",
        "|---|---|---|---|---|",
    ]
    for m in spec["methods"]:
        first = own_trial(m["label"]) or {}
        for key, dim in m["space"].items():
            space = (
                "{" + ", ".join(str(c) for c in dim["choices"]) + "}"
                if "choices" in dim
                else f"[{dim['low']:g}, {dim['high']:g}]" + (" log" if dim.get("log") else "")
            )
            now = profile.get(m["label"], {}).get(key)
            lines.append(f"| {m['name']} | `{key}` | {space} | {_fmt(_num(first.get(key)))} | {_fmt(now)} |")
    return "\n".join(lines)


def trials_table() -> str:
    spec = _yaml(TUNING_FILE)
    rows = trials()
    out = []
    for m in spec["methods"]:
        mine = [r for r in rows if r["method"] == m["label"]]
        keys = list(m["space"])
        head = ["trial", "state", "score", "point_mass N=10 (N=1)", "reacher N=10 (N=1)", "min"]
        head += [k.rsplit(".", 1)[-1] for k in keys]
        lines = [
            f"**{m['name']}** ({len(mine)} of {spec['trials']} trials)",
            "",
            "| " + " | ".join(head) + " |",
            "|" + "---|" * len(head),
        ]
        for r in sorted(mine, key=lambda r: int(r["trial"])):
            cells = [
                r["trial"] + (" (own)" if r["enqueued"] == "True" else ""),
                r["state"] + _why(r),
                _fmt(_num(r["score"])),
            ]
            for task in ("dmc_point_mass", "dmc_reacher_easy"):
                multi, one = _num(r.get(f"{task}/return_multi")), _num(r.get(f"{task}/return_1"))
                cells.append("--" if multi is None else f"{multi:.0f}" + (f" ({one:.0f})" if one is not None else ""))
            cells.append(f"{float(r['seconds']) / 60:.1f}" if r.get("seconds") else "--")
            cells += [_fmt(_num(r.get(k))) for k in keys]
            lines.append("| " + " | ".join(cells) + " |")
        out.append("\n".join(lines))
    return "\n\n".join(out)


def _why(row: dict) -> str:
    match = re.search(r"periodic evaluation (\d+)", row.get("why") or "")
    return f" at eval {match.group(1)}" if match else ""


def budget_table() -> str:
    spec = _yaml(TUNING_FILE)
    rows = trials()
    head = (
        "| method | trials spent | complete / pruned / failed | wall time (min) | best score (trial) "
        "| own values' score |"
    )
    lines = [head, "|---|---|---|---|---|---|"]
    for m in spec["methods"]:
        mine = [r for r in rows if r["method"] == m["label"]]
        states = [sum(r["state"] == s for r in mine) for s in ("complete", "pruned", "fail")]
        done = [r for r in mine if r["state"] == "complete"]
        best = max(done, key=lambda r: float(r["score"])) if done else None
        own = next((r for r in mine if r["enqueued"] == "True" and r["state"] == "complete"), None)
        minutes = sum(float(r["seconds"]) for r in mine if r.get("seconds")) / 60
        best_cell = f"{float(best['score']):.3f} ({best['trial']})" if best else "--"
        own_cell = f"{float(own['score']):.3f}" if own else "--"
        lines.append(
            f"| {m['name']} | {len(mine)} of {spec['trials']} | {' / '.join(map(str, states))} | "
            f"{minutes:.0f} | {best_cell} | {own_cell} |"
        )
    return "\n".join(lines)


def chosen_table() -> str:
    picked = chosen()
    if not picked:
        return "No completed trial yet."
    lines = ["| method | trial | score | values |", "|---|---|---|---|"]
    for label, c in picked.items():
        values = ", ".join(f"`{k}` {_fmt(v)}" for k, v in c["overrides"].items())
        lines.append(f"| {NAMES.get(label, label)} | {c['trial']} | {c['score']:.3f} | {values} |")
    return "\n".join(lines)


def search_times() -> tuple[str, str]:
    """The first trial's start and the last trial's end in the Optuna journal (UTC)."""
    starts, ends = [], []
    path = STUDY / "journal.log"
    for line in path.read_text(encoding="utf-8").splitlines() if path.exists() else []:
        try:
            op = json.loads(line)
        except ValueError:
            continue
        if op.get("datetime_start"):
            starts.append(datetime.fromisoformat(op["datetime_start"]))
        if op.get("datetime_complete"):
            ends.append(datetime.fromisoformat(op["datetime_complete"]))
    if not starts or not ends:
        return "--", "--"
    return min(starts).strftime("%Y-%m-%d %H:%M"), max(ends).strftime("%Y-%m-%d %H:%M")


def trial_returns(row: dict, task: str) -> tuple[float | None, float | None]:
    return _num(row.get(f"{task}/return_multi")), _num(row.get(f"{task}/return_1"))


def chosen_one_step(crit: dict) -> str:
    """What the objective does not see: whether each flow method's chosen and own values keep N = 1 near N = 10 on
    the tuning tasks (from trials.csv)."""
    share, rows, picked, spec = crit["goal"]["one_step"]["share"], trials(), chosen(), _yaml(TUNING_FILE)
    parts = []
    for label in [m["label"] for m in spec["methods"]]:
        if label not in picked:
            continue
        row = next((r for r in rows if r["method"] == label and int(r["trial"]) == picked[label]["trial"]), None)
        own = own_trial(label)
        if row is None or own is None or trial_returns(row, spec["tasks"][0])[1] is None:
            continue  # a Gaussian: no N = 1 return

        def held(r):
            pairs = [trial_returns(r, t) for t in spec["tasks"]]
            ok = sum(one is not None and multi is not None and one >= share * multi for multi, one in pairs)
            text = ", ".join(
                f"{short(t)} {one:.0f} against {multi:.0f}" for t, (multi, one) in zip(spec["tasks"], pairs)
            )
            return ok, text

        (k, text), (j, own_text) = held(row), held(own)
        n = len(spec["tasks"])
        parts.append(
            f"{NAMES[label]}'s chosen values (trial {row['trial']}) hold N = 1 ≥ {share:g} × N = 10 on {k} of {n} "
            f"tuning tasks ({text}), its own values (trial {own['trial']}) on {j} of {n} ({own_text})."
        )
    return " ".join(parts)


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
            out.returns.setdefault(r["task"], {})[int(r["seed"])] = (float(r["return_multi"]), _num(r.get("return_1")))
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
    from refpo_warp.studies.reports.intervals import aggregate, improvement

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
            per_task = [
                aggregate({"x": np.array([[runs.returns[t][s][0]] for s in seeds])})["x"]["mean"] for t in TASKS
            ]
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


# ------------------------------------------------------------------------------------------------ budget
@dataclass
class BudgetRun:
    label: str
    seed: int
    steps: np.ndarray
    values: np.ndarray  # on the common grid; 0 after a stop
    stop: dict | None  # stopped.json
    diagnostics: dict  # eval.json's (flow runs that finished)

    @property
    def peak(self) -> tuple[float, float]:
        i = int(np.argmax(self.values))
        return float(self.values[i]), float(self.steps[i])

    def fell(self, share: float) -> bool:
        return self.stop is not None or self.values[-1] < share * self.peak[0]


def budget_runs() -> list[BudgetRun]:
    raw = []
    grid = None  # every run evaluates at the same iterations; a stopped run's missing points count as 0
    for path in sorted(BUDGET.glob("*/*/seed*/progress_eval.jsonl")):
        rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
        key = next((k for k in ("eval/return_N10", "eval/return") if rows and k in rows[0]), None)
        if key is None:
            continue
        steps, values = np.array([r["env_steps"] for r in rows]), np.array([r[key] for r in rows])
        run = path.parent
        stop = json.loads((run / "stopped.json").read_text()) if (run / "stopped.json").exists() else None
        diag = (
            json.loads((run / "eval.json").read_text()).get("diagnostics", {}) if (run / "eval.json").exists() else {}
        )
        if stop is None and (grid is None or len(steps) > len(grid)):
            grid = steps
        raw.append((run.parent.name, int(run.name.removeprefix("seed")), steps, values, stop, diag))
    out = []
    for label, seed, steps, values, stop, diag in raw:
        if grid is not None and len(values) < len(grid):
            padded = np.concatenate([values, np.zeros(len(grid) - len(values))])
            out.append(BudgetRun(label, seed, grid, padded, stop, diag))
        else:
            out.append(BudgetRun(label, seed, steps, values, stop, diag))
    return out


def budget_scale() -> tuple[int, int, int]:
    """(env steps of the CPU profile's budget, of the budget runs, the budget's multiple of the profile's), from a
    budget run's config.yaml."""
    from refpo_warp.runner.build import env_steps_per_iteration, num_iterations

    cfg = _yaml(next(BUDGET.glob("*/*/seed*/config.yaml")))
    per_iteration = env_steps_per_iteration(cfg)
    profile = math.ceil(cfg["total_env_steps"] / per_iteration)
    return per_iteration * profile, per_iteration * num_iterations(cfg), num_iterations(cfg) // profile


def marks(multiple: int) -> list[int]:
    """1×, 2×, 4× ... up to the budget's multiple."""
    return [2**k for k in range(int(math.log2(multiple)) + 1)]


def curve_at(runs: list[BudgetRun], x: float) -> tuple[float, float, float]:
    values = [np.interp(x, r.steps, r.values) for r in runs]
    return float(np.mean(values)), float(min(values)), float(max(values))


def curves_table(runs: list[BudgetRun], profile: int, multiple: int, plot: str | None) -> str:
    """The mean (min-max) over seeds at each multiple; with ``plot`` (the task's name) also budget_curves.png."""
    if not runs:
        return "Not run yet: it needs the best flow method of the study."
    by_label: dict[str, list[BudgetRun]] = {}
    for r in runs:
        by_label.setdefault(r.label, []).append(r)
    ks = marks(multiple)
    head = "| method | seeds | " + " | ".join(
        f"{k}× ({steps_text(k * profile)} env steps)" if k == 1 else f"{k}×" for k in ks
    )
    lines = [head + " |", "|---|---|" + "---|" * len(ks)]
    for label, series in sorted(by_label.items()):
        cells = [f"{m:.0f} ({lo:.0f}-{hi:.0f})" for m, lo, hi in (curve_at(series, k * profile) for k in ks)]
        lines.append(
            f"| {NAMES.get(label, label)} | {seeds_text(r.seed for r in series)} | " + " | ".join(cells) + " |"
        )
    lines += ["", "Cells: the periodic return's mean over seeds (min-max) at each multiple of the profile's env steps."]
    stops = [
        f"{r.label}/seed{r.seed} at {steps_text(r.stop['env_steps'])} env steps" for r in runs if r.stop is not None
    ]
    if stops:
        lines += ["", f"Stopped on a non-finite loss (counted as 0 from there on): {', '.join(stops)}."]
    if plot:
        plot_curves(by_label, plot)
    return "\n".join(lines) + "\n\n![budget curves](budget_curves.png)"


def plot_curves(by_label: dict[str, list[BudgetRun]], task: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.6))
    for label, series in sorted(by_label.items()):
        steps, values = series[0].steps, np.array([r.values for r in series])
        ax.plot(steps / 1e6, values.mean(axis=0), label=NAMES.get(label, label))
        ax.fill_between(steps / 1e6, values.min(axis=0), values.max(axis=0), alpha=0.2)
    ax.set_xlabel("env steps (M)")
    ax.set_ylabel("periodic return (N = 10 / mean action)")
    ax.set_title(f"{task}: return against budget (mean, min-max over seeds)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(HERE / "budget_curves.png", dpi=120)
    plt.close(fig)


def budget_runs_table(runs: list[BudgetRun], profile: int, multiple: int, fall: float) -> str:
    ks = marks(multiple)
    head = ["method", "seed", "peak (env steps)", *(f"{k}×" for k in ks), "end", "largest ratio", "mean clip fraction"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in sorted(runs, key=lambda r: (r.label, r.seed)):
        peak, at = r.peak
        cells = []
        for k in ks:
            x = k * profile
            stopped = r.stop is not None and x > r.stop["env_steps"]
            cells.append("stopped" if stopped else f"{np.interp(x, r.steps, r.values):.0f}")
        if r.stop is not None:
            reason = r.stop.get("reason", "")
            reason = "non-finite loss" if "Non-finite" in reason else reason
            end = f"stopped at {steps_text(r.stop['env_steps'])} ({reason})"
        else:
            end = f"{r.values[-1]:.0f}" + (f", below {fall:g} × its peak" if r.fell(fall) else "")
        diag = r.diagnostics
        lines.append(
            "| "
            + " | ".join(
                [
                    NAMES.get(r.label, r.label),
                    str(r.seed),
                    f"{peak:.0f} ({steps_text(at)})",
                    *cells,
                    end,
                    big_text(diag["ratio_max"]) if "ratio_max" in diag else "--",
                    f"{diag['clip_fraction']:.2f}" if "clip_fraction" in diag else "--",
                ]
            )
            + " |"
        )
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ the prose
EXIT_NOTE = re.compile(r"exit codes \[([^\]]*)\]")


def exit_text(code: int) -> str:
    from refpo_warp.cli.guard import EXIT_NONFINITE

    if code == EXIT_NONFINITE:
        return f"{code} (training stopped on a non-finite loss)"
    if code < 0:
        return f"{code} (ended by signal {-code})"
    return f"{code} (see `docs/cli.md`)"


def versus(poi, own: str, above: float) -> str:
    """P(a tuned run beats a run at the method's own values), with the verdict its interval gives."""
    text = f"P(tuned > {own}) {poi.text(2)}"
    if poi.low > above:
        return f"{text}, its interval above {above:g}: the tuned values are better"
    if poi.high < above:
        return f"{text}, its interval below {above:g}: the {own} values are better"
    return f"{text}, its interval spanning {above:g}: the seeds do not separate the two"


def means_text(row: Row) -> str:
    return " / ".join(f"{e.point:.0f}" for e in row.per_task)


def against_paper(fresh: Fresh, label: str) -> str:
    """Where the tuned mean is above and where below the mean at the method's own values."""
    tuned, paper = fresh.rows[f"{label}/tuned"].per_task, fresh.rows[f"{label}/paper"].per_task
    higher = [
        f"{short(t)} ({a.point:.0f} against {b.point:.0f})" for t, a, b in zip(TASKS, tuned, paper) if a.point > b.point
    ]
    lower = [
        f"{short(t)} ({a.point:.0f} against {b.point:.0f})"
        for t, a, b in zip(TASKS, tuned, paper)
        if a.point <= b.point
    ]
    parts = ([f"higher on {and_list(higher)}"] if higher else []) + ([f"lower on {and_list(lower)}"] if lower else [])
    return "its mean is " + ", ".join(parts)


def runs_text(row: Row, task: str) -> str:
    out = []
    for seed, multi, one, failed in row.values(task):
        out.append(
            f"seed {seed} failed"
            if failed
            else f"seed {seed} {multi:.0f}" + (f" ({one:.0f})" if one is not None else "")
        )
    return ", ".join(out)


def range_text(row: Row, task: str) -> str:
    values = [multi for _, multi, _, _ in row.values(task)]
    return f"{min(values):.0f}-{max(values):.0f}"


def goal_parts(fresh: Fresh, crit: dict) -> dict:
    need, goal = crit["goal"]["reach_tasks"], crit["goal"]["one_step"]
    flows = [label for label in FLOWS if f"{label}/tuned" in fresh.rows]
    reached = {label: sum(reach(fresh, label)) for label in flows}
    meet_a = [label for label in flows if reached[label] >= need]
    row = fresh.rows.get(f"{goal['method']}/tuned")
    held, near, total, misses = one_step_counts(row, goal["share"], crit["report"]["within"]) if row else (0, 0, 0, [])
    meet_b = row is not None and held == total
    return {
        "reached": reached,
        "meet_a": meet_a,
        "held": held,
        "near": near,
        "total": total,
        "misses": misses,
        "meet_b": meet_b,
        "met": bool(meet_a) and meet_b,
        "need": need,
        "flows": flows,
    }


def goal_text(fresh: Fresh, crit: dict) -> str:
    g, ppo = goal_parts(fresh, crit), fresh.rows["ppo/tuned"]
    n = len(TASKS)
    per = ", ".join(f"{CODE_NAMES[label]} {g['reached'][label]} of {n}" for label in g["flows"])
    a = f"(a) Tasks where the tuned interval reaches tuned PPO's: {per}; "
    a += f"met by {and_list(CODE_NAMES[x] for x in g['meet_a'])}." if g["meet_a"] else "met by none."
    thin = []
    for label in g["meet_a"]:
        row = fresh.rows[f"{label}/tuned"]
        for task, e, q, ok in zip(TASKS, row.per_task, ppo.per_task, reach(fresh, label)):
            if ok and e.point < q.low:
                failed = sum(f for _, _, _, f in row.values(task))
                thin.append(
                    f"{CODE_NAMES[label]} on {short(task)} reaches it only through its interval's spread: its mean "
                    f"{e.point:.0f} lies below PPO's interval {q.text()}, its own interval is {e.text()} and its runs "
                    f"range {range_text(row, task)}"
                    + (f" ({failed} failed run{'s' if failed > 1 else ''} counted as 0)" if failed else "")
                )
    if thin:
        a += " " + "; ".join(thin) + "."
    method = CODE_NAMES[crit["goal"]["one_step"]["method"]]
    share = crit["goal"]["one_step"]["share"]
    b = f"(b) {method}'s N = 1 ≥ {share:g} × N = 10 holds in {g['held']} of {g['total']} runs"
    b += ": met." if g["meet_b"] else f", not in every run ({'; '.join(g['misses'])}): not met."
    verdict = "The goal is met." if g["met"] else "The goal is not met."
    return f"{a} {b} {verdict}"


def goal_summary(fresh: Fresh, crit: dict) -> str:
    g = goal_parts(fresh, crit)
    a = f"(a) is met by {and_list(CODE_NAMES[x] for x in g['meet_a'])}" if g["meet_a"] else "(a) is met by none"
    b = f"(b) {'is met' if g['meet_b'] else 'is not'} ({g['held']} of {g['total']} runs)"
    tail = "the goal is met" if g["met"] else "the goal is not met"
    return f"{a}, {b}: {tail}."


def vs_ppo_summary(fresh: Fresh, above: float) -> str:
    pois = fresh.vs_ppo
    listed = ", ".join(f"{CODE_NAMES[label]} {p.text(2)}" for label, p in pois.items())
    text = f"The probability that a tuned flow run beats a tuned PPO run on the same task: {listed}. "
    reaching = [CODE_NAMES[label] for label, p in pois.items() if p.high >= above]
    seeds = len(fresh.rows["ppo/tuned"].seeds)
    if all(p.high < above for p in pois.values()):
        text += f"Every interval lies below {above:g}: tuned PPO is the better choice at this budget."
    elif all(p.point < above for p in pois.values()):
        text += (
            f"Every point estimate is below {above:g} (PPO leads); the intervals of {and_list(reaching)} reach "
            f"{above:g}, so {seeds} seeds do not separate {'it' if len(reaching) == 1 else 'them'} from PPO."
        )
    else:
        at = [CODE_NAMES[label] for label, p in pois.items() if p.point >= above]
        text += f"The point estimate of {and_list(at)} is at or above {above:g}."
    most = max(sum(passes(fresh, label)) for label in pois)
    who = [CODE_NAMES[label] for label in pois if sum(passes(fresh, label)) == most]
    if most == 0:
        return text + " No tuned flow method's mean passes tuned PPO's on any task."
    return text + (
        f" A tuned flow method's mean passes tuned PPO's on at most {most} of {len(TASKS)} tasks ({and_list(who)})."
    )


def iqm_summary(fresh: Fresh) -> str:
    pairs = [label for label in LABELS if f"{label}/paper" in fresh.rows and f"{label}/tuned" in fresh.rows]
    text = ", ".join(
        f"{CODE_NAMES[label]} {fresh.iqm[f'{label}/paper'].point:.2f} → {fresh.iqm[f'{label}/tuned'].point:.2f}"
        for label in pairs
    )
    gain = max(pairs, key=lambda label: fresh.iqm[f"{label}/tuned"].point - fresh.iqm[f"{label}/paper"].point)
    flows = [label for label in FLOWS if label in pairs]
    best = max(flows, key=lambda label: fresh.iqm[f"{label}/tuned"].point)
    narrow = min(flows, key=lambda label: fresh.iqm[f"{label}/tuned"].high - fresh.iqm[f"{label}/tuned"].low)
    return (
        f"{text}; the largest rise is {CODE_NAMES[gain]}'s. The highest tuned flow IQM is {CODE_NAMES[best]}'s, "
        f"{fresh.iqm[f'{best}/tuned'].text(2)}; the narrowest tuned flow interval is {CODE_NAMES[narrow]}'s"
    )


def adoption(fresh: Fresh, crit: dict, profile: dict[str, dict]) -> tuple[str, str]:
    """(the summary sentence, the paragraph's verdicts) of the adoption rule."""
    above, picked, cpu = crit["adopt"]["above"], chosen(), _yaml(DMC_PROFILE)["by_device"]["cpu"].get("by_algo", {})
    adopted, kept, notes = [], [], []
    for label, poi in fresh.vs_own.items():
        name, passed = CODE_NAMES[label], poi.low > above
        now = profile.get(label)
        if passed:
            adopted.append(label)
            if now is not None and label in picked and _same(now, picked[label]["overrides"]):
                where = (
                    f"`configs/task/_dmc.yaml`, `by_device.cpu.by_algo.{label}`" if label in cpu else "the CPU profile"
                )
                values = ", ".join(f"{k.rsplit('.', 1)[-1]} {_fmt(v)}" for k, v in now.items())
                notes.append(
                    f"{name} passes ({poi.text(2)}): its chosen values are now its CPU profile's ({where}: {values})"
                )
            else:
                notes.append(f"{name} passes ({poi.text(2)}), but its CPU profile does not hold its chosen values yet")
        else:
            kept.append(label)
            own = own_trial(label)
            own_values = {k: float(own[k]) for k in (now or {})} if own and now else None
            if now is not None and own_values is not None and not _same(now, own_values):
                notes.append(
                    f"{name} does not pass ({poi.text(2)}), yet its CPU profile no longer holds its own values"
                )
            else:
                notes.append(f"{name} does not pass ({poi.text(2)}) and keeps its {own_name(label)} values")
    summary = (
        'By the adoption rule (see "Which values became the CPU profile\'s"), '
        + (
            f"{and_list(CODE_NAMES[x] for x in adopted)} now "
            + ("runs its" if len(adopted) == 1 else "run their")
            + " chosen values at the CPU profile"
            if adopted
            else "no method's chosen values replace its own"
        )
        + (f"; {and_list(CODE_NAMES[x] for x in kept)} keep their own." if kept and adopted else ".")
    )
    return summary, "; ".join(notes) + "."


def failures_text(fresh: Fresh) -> str:
    out = []
    for row in fresh.rows.values():
        if row.kind != "tuned":
            continue
        for (task, seed), note in sorted(row.runs.failed.items()):
            match = EXIT_NOTE.search(note)
            codes = [int(c) for c in re.findall(r"-?\d+", match.group(1))] if match else []
            attempts = ", then ".join(exit_text(c) for c in codes) if codes else "no exit code recorded"
            out.append(f"{short(task)}/{row.label}/seed{seed}: {len(codes)} attempt(s), exit code {attempts}")
    if not out:
        return "None."
    return (
        "; ".join(out)
        + ". The sweep's report keeps no more of a failed run than its exit codes and the path of its log, which is "
        "not committed: where training stopped and how large its ratios grew are not recorded here."
    )


def budget_prose(runs: list[BudgetRun], fresh: Fresh | None, profile: int, multiple: int, crit: dict) -> dict:
    fall = crit["report"]["fall"]
    spec = _yaml(BUDGET_FILE)
    flow = next(m["label"] for m in spec["methods"] if m["label"] != "ppo")
    task = spec["tasks"][0]
    by = {label: [r for r in runs if r.label == label] for label in ("ppo", flow)}
    ks = marks(multiple)
    # the difference of the means as the curves table rounds them, so that the two agree
    leads = [round(curve_at(by["ppo"], k * profile)[0]) - round(curve_at(by[flow], k * profile)[0]) for k in ks]
    lead_list = ", ".join(f"{lead} at {k}×" for k, lead in zip(ks, leads))
    later = leads[1:]
    if later and all(x > leads[0] for x in later):
        verdict = "larger at every later multiple than at 1×"
    elif later and all(x < leads[0] for x in later):
        verdict = "smaller at every later multiple than at 1×"
    else:
        verdict = "not consistently larger or smaller than at 1×"
    falls = {label: sum(r.fell(fall) for r in rs) for label, rs in by.items()}
    stopped = sum(r.stop is not None for r in by[flow])
    text = (
        f"PPO's lead over {CODE_NAMES[flow]} (the difference of the means) is {lead_list}: {verdict}. "
        f"{CODE_NAMES[flow]}'s return ends below {fall:g} × its peak in {falls[flow]} of {len(by[flow])} seeds"
        + (f" ({stopped} of them stopped on a non-finite loss)" if stopped else "")
        + f", PPO's in {falls['ppo']} of {len(by['ppo'])}."
    )
    at1 = ", ".join(f"seed {r.seed} {np.interp(profile, r.steps, r.values):.0f}" for r in by[flow])
    fresh_text = ""
    if fresh is not None and f"{flow}/tuned" in fresh.rows:
        row = fresh.rows[f"{flow}/tuned"]
        fresh_text = (
            f"; its fresh {short(task)} runs at the same values and the profile's budget ended at "
            f"{runs_text(row, task)} (N = 10, N = 1 in brackets)"
        )
    best = None
    if fresh is not None:
        flows = [label for label in FLOWS if f"{label}/tuned" in fresh.rows]
        best = max(flows, key=lambda label: fresh.iqm[f"{label}/tuned"].point)
    still = (
        "--"
        if best is None
        else "still the tuned flow method with the highest IQM on the fresh seeds"
        if best == flow
        else f"the tuned flow method with the highest IQM on the fresh seeds is now {CODE_NAMES[best]}"
    )
    ppo_lr = chosen().get("ppo", {}).get("overrides", {}).get("algorithm.learning_rate")
    own_ppo = own_trial("ppo")
    return {
        "budget_flow": CODE_NAMES[flow],
        "budget_flow_still": still,
        "budget_verdict": text,
        "budget_at_one": f"At 1× the budget runs of {CODE_NAMES[flow]} return {at1}{fresh_text}.",
        "budget_ppo_lr": (
            f"{_fmt(ppo_lr)}, {times_text(ppo_lr / float(own_ppo['algorithm.learning_rate']))}× the paper's"
            if ppo_lr and own_ppo
            else "--"
        ),
        "budget_seeds": seeds_text({r.seed for r in runs}),
        "budget_task": short(task),
    }


def page_values(check: bool) -> dict[str, object]:
    """Every field of README.template.md; with ``check`` budget_curves.png is left as it is."""
    from refpo_warp.runner.build import num_iterations

    crit, spec, dmc = _yaml(CRITERIA), _yaml(TUNING_FILE), _yaml(DMC_PROFILE)
    fresh = fresh_analysis()
    profile_now = profile_values()
    above = crit["adopt"]["above"]
    rows = trials()
    v: dict[str, object] = {}

    # the CPU profile and the paper's budget
    trial_cfg = _yaml(next(STUDY.glob("runs/*/trial*/*/config.yaml")))
    v["cpu_steps"] = steps_text(trial_cfg["total_env_steps"])
    v["cpu_iterations"] = num_iterations(trial_cfg)
    v["num_envs"] = trial_cfg["num_envs"]
    paper_steps = dmc["by_device"]["cuda"]["total_env_steps"]
    v["paper_steps"] = steps_text(paper_steps)
    v["paper_multiple"] = _fmt(paper_steps / trial_cfg["total_env_steps"])
    v["paper_passes"] = dmc["_actor_critic"]["num_learning_epochs"]
    v["own_passes"] = _fmt(_num(own_values("refpo")["algorithm.num_learning_epochs"]))

    # the intro: the committed rows at the paper's values
    ppo_c, refpo_c = read_runs(*COMMITTED["ppo"][:2]), read_runs(*COMMITTED["refpo"][:2])
    ppo_mean = [statistics.mean(x[0] for x in ppo_c.returns[t].values()) for t in TASKS]
    refpo_mean = [statistics.mean(x[0] for x in refpo_c.returns[t].values()) for t in TASKS]
    v["intro_tasks"] = " / ".join(short(t) for t in TASKS)
    v["intro_ppo"] = " / ".join(f"{x:.0f}" for x in ppo_mean)
    v["intro_refpo"] = " / ".join(f"{x:.0f}" for x in refpo_mean)
    v["intro_ppo_above"] = f"{sum(a > b for a, b in zip(ppo_mean, refpo_mean))} of {len(TASKS)}"
    v["intro_seeds"] = seeds_text({s for t in TASKS for s in ppo_c.returns[t]})
    v["n_tasks"] = len(TASKS)
    left = [t for t in TASKS if t not in spec["tasks"]]
    v["untuned_tasks"] = and_list(
        f"{short(t)}, where PPO's committed mean is {m:.0f}" for t, m in zip(TASKS, ppo_mean) if t in left
    )

    # the search
    v["trials_budget"] = spec["trials"]
    v["search_spent"] = len(rows)
    v["search_minutes"] = f"{sum(float(r['seconds']) for r in rows if r.get('seconds')) / 60:.0f}"
    v["search_start"], v["search_end"] = search_times()
    v["tune_tasks"] = and_list(short(t) for t in spec["tasks"])
    v["tune_seed"] = spec["seed"]
    v["references"] = and_list(f"{spec['objective']['reference'][t]:g}" for t in spec["tasks"])
    v["sampler_startup"] = spec["sampler"]["startup_trials"]
    pruner = spec["pruner"]
    v["prune_percentile"] = _fmt(pruner["percentile"])
    v["prune_from"] = pruner["warmup_evaluations"] + 1
    v["prune_startup"] = pruner["startup_trials"]
    complete = next(STUDY.glob("runs/*/trial*/*/progress_eval.jsonl"))
    v["tune_evaluations"] = sum(1 for line in complete.read_text().splitlines() if line.strip())
    v["eval_episodes"] = trial_cfg["eval"]["interval_num_envs"]
    lr = next(d for k, d in spec["methods"][0]["space"].items() if k == "algorithm.learning_rate")
    paper_lr = float(own_values("ppo")["algorithm.learning_rate"])
    v["lr_paper"] = _fmt(paper_lr)
    v["lr_below"] = times_text(paper_lr / lr["low"])
    v["lr_above"] = times_text(lr["high"] / paper_lr)

    # the tables of the search
    v["spaces_table"] = spaces_table(profile_now)
    v["budget_table"] = budget_table()
    v["trials_table"] = trials_table()
    v["chosen_table"] = chosen_table()
    v["chosen_one_step"] = chosen_one_step(crit)

    # tuned ReFPO's values against the paper's
    picked, own_refpo = chosen(), own_values("refpo")
    v["refpo_lr_ratio"] = times_text(
        picked["refpo"]["overrides"]["algorithm.learning_rate"] / float(own_refpo["algorithm.learning_rate"])
    )
    v["refpo_lambda_ratio"] = times_text(
        picked["refpo"]["overrides"]["algorithm.reflow_coef"] / float(own_refpo["algorithm.reflow_coef"])
    )
    v["refpo_own_lambda"] = _fmt(_num(own_refpo["algorithm.reflow_coef"]))
    v["refpo_own_lr"] = _fmt(_num(own_refpo["algorithm.learning_rate"]))

    # the fresh seeds
    goal = crit["goal"]["one_step"]
    v["hold_share"] = f"{goal['share']:g}"
    v["within_share"] = share_text(crit["report"]["within"])
    v["goal_tasks"] = crit["goal"]["reach_tasks"]
    v["adopt_above"] = f"{above:g}"
    v["fresh_table"] = fresh_table(fresh, crit)
    fresh_csv = list(csv.DictReader((FRESH / "runs.csv").open(encoding="utf-8"))) if fresh else []
    v["fresh_runs"] = len(fresh_csv)
    v["fresh_failed_count"] = sum(r["status"] == "failed" for r in fresh_csv)
    v["fresh_seeds"] = seeds_text({int(r["seed"]) for r in fresh_csv})
    onestep_cfg = _yaml(next(FRESH.glob("runs/*/refpo_onestep/seed*/config.yaml")))
    v["onestep_coef"] = _fmt(onestep_cfg["algorithm"]["one_step_coef"])
    if fresh is not None:
        committed = []
        for label in LABELS:
            key = f"{label}/paper"
            if key in fresh.rows:
                committed.append(f"{COMMITTED[label][2]}, seeds {seeds_text(fresh.rows[key].seeds)}")
        v["committed_sources"] = "; ".join(dict.fromkeys(committed))
        v["ppo_norm_seeds"] = seeds_text(fresh.rows["ppo/paper"].seeds)
        v["summary_vs_ppo"] = vs_ppo_summary(fresh, above)
        v["summary_iqm"] = iqm_summary(fresh)
        v["summary_adopted"], v["adopt_text"] = adoption(fresh, crit, profile_now)
        row = fresh.rows[f"{goal['method']}/tuned"]
        held, near, total, misses = one_step_counts(row, goal["share"], crit["report"]["within"])
        v["onestep_iqm"] = fresh.iqm[row.key].text(2)
        v["onestep_held"] = f"{held} of {total}"
        v["onestep_within"] = f"{near} of {total}"
        v["goal_summary"] = goal_summary(fresh, crit)
        v["goal_text"] = goal_text(fresh, crit)
        v["failures_text"] = failures_text(fresh)

        refpo = fresh.rows["refpo/tuned"]
        failed = len(refpo.runs.failed)
        r_held, _, r_total, _ = one_step_counts(refpo, goal["share"], crit["report"]["within"])
        v["refpo_summary"] = (
            f"{failed} of its {len(refpo.seeds) * len(TASKS)} runs failed (counted as 0), and its N = 1 ≥ "
            f"{goal['share']:g} × N = 10 holds in {r_held} of {r_total} runs"
        )
        v["ppo_vs_paper"] = (
            f"{against_paper(fresh, 'ppo')}; IQM {fresh.iqm['ppo/tuned'].text(2)} against "
            f"{fresh.iqm['ppo/paper'].text(2)}; {versus(fresh.vs_own['ppo'], own_name('ppo'), above)}"
        )
        v["ppo_tuning_score"] = f"{picked['ppo']['score']:.3f}"
        v["refpo_vs_paper"] = (
            f"{against_paper(fresh, 'refpo')}; {versus(fresh.vs_own['refpo'], own_name('refpo'), above)}. Its runs, "
            "N = 10 (N = 1): " + "; ".join(f"{short(t)} {runs_text(refpo, t)}" for t in TASKS)
        )
        v["onestep_text"] = (
            f"means {means_text(row)}, IQM {fresh.iqm[row.key].text(2)}; N = 1 ≥ {goal['share']:g} × N = 10 in "
            f"{held} of {total} runs"
            + (f" (not in {'; '.join(misses)})" if misses else "")
            + f", |N = 1 − N = 10| ≤ {share_text(crit['report']['within'])} of N = 10 in {near} of {total}; tuned "
            f"ReFPO without the one-step term holds N = 1 ≥ {goal['share']:g} × N = 10 in {r_held} of {r_total}. "
            f"Against the paper-values `onestep_c03`: {versus(fresh.vs_own[row.label], own_name(row.label), above)}"
        )
        fpo = fresh.rows["fpo_pp/tuned"]
        v["fpo_text"] = (
            f"its chosen values take its means from {means_text(fresh.rows['fpo_pp/paper'])} to {means_text(fpo)} "
            f"({versus(fresh.vs_own['fpo_pp'], own_name('fpo_pp'), above)}); its tuned runs range "
            + ", ".join(f"{range_text(fpo, t)} on {short(t)}" for t in TASKS)
        )

    # the budget curves
    runs = budget_runs()
    if runs:
        profile, budget_steps, multiple = budget_scale()
        v["budget_multiple"] = multiple
        v["budget_steps"] = steps_text(budget_steps)
        task = short(_yaml(BUDGET_FILE)["tasks"][0])
        v["curves_table"] = curves_table(runs, profile, multiple, plot=None if check else task)
        v["budget_runs_table"] = budget_runs_table(runs, profile, multiple, crit["report"]["fall"])
        v["fall_share"] = f"{crit['report']['fall']:g}"
        v["budget_eval_episodes"] = _yaml(next(BUDGET.glob("*/*/seed*/config.yaml")))["eval"]["interval_num_envs"]
        v.update(budget_prose(runs, fresh, profile, multiple, crit))
    return v


def main() -> int:
    from refpo_warp.studies.reports.results_page import main_args, write_page

    parser = main_args(__doc__.split("\n\n")[0])
    parser.add_argument("--sync", type=Path, help="a refpo tune out dir, e.g. runs/tune/cpu_dmc")
    parser.add_argument("--sync-fresh", type=Path, help="the fresh-seed sweep dir (with its report/)")
    parser.add_argument("--sync-budget", type=Path, help="the budget sweep dir")
    args = parser.parse_args()
    if args.check and (args.sync or args.sync_fresh or args.sync_budget):
        parser.error("--check compares the page with the committed data: it takes no --sync option")
    for folder, sync in ((args.sync, sync_study), (args.sync_fresh, sync_fresh), (args.sync_budget, sync_budget)):
        if folder is not None:
            sync(folder)
    same = write_page(TEMPLATE, page_values(args.check), check=args.check)
    page = TEMPLATE.with_name("README.md")
    if args.check:
        print(f"{page}: {'as the data says' if same else 'differs from what the data says'}")
        return 0 if same else 1
    print(f"{page}: {'unchanged' if same else 'written'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
