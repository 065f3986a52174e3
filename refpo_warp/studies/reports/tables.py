"""The paper's DMC tables from per-run ``eval.json`` files: which numbers, how they are aggregated and printed.

Per run (``eval.json``, the project's shared format; read by ``grid/run_metrics.py``):
- 10-step reward: ``results["N=10"].return_mean``, or where a run has no N = 10 its largest n > 1 (ReinFlow: N = 4,
  marked in the cell); a Gaussian policy's ``results["mean_action"].return_mean``;
- 1-step reward: ``results["N=1"].return_mean``; both again under zero initial noise (``N=<n>/zero``, ``N=1/zero``)
  where the run evaluated that protocol;
- Straightness: ``diagnostics.straightness_error``; Explosion and Ratio Expl.: ``diagnostics.explosion_rate``
  (per action, the paper's number); Jac. Expl., Mean Jac. Norm, Jac. Norm P95: ``diagnostics.jacobian_*``;
- 1-step Err. (ours): ``diagnostics.one_step_error_eval``, E|T(a_1) - T(a_N)|^2 with shared noise on the final
  policy's evaluation states, and 1-step Ratio its ratio to the policy's spread (``one_step_ratio_eval``).
- Own headline (``runs.csv`` only): the return under the run's first initial-noise protocol at its largest N (FPO++:
  ``N=64/zero``; the mean action for a Gaussian policy), with that setting in the ``headline`` column;
- Train min.: ``train_time_s`` / 60; Cliffs: runs whose training reward falls off a cliff by FPO++'s rule
  (``health.cliff``).
A number a run does not have (e.g. PPO's diagnostics) is left out and prints as ``--``.

Aggregation (``AGGREGATION`` says it in the reports): the method table pools all finished (task, seed) runs of a
method: mean over them and population standard deviation (ddof = 0) over them, so the spread holds task-to-task and
seed-to-seed differences (our reading of the paper's "mean ± std across 10 tasks"). The CSV adds the std over
per-task means and over per-seed means (mean over tasks for each seed). Per-task rows: mean ± std over seeds.
"""

from __future__ import annotations

import csv
import io
import statistics
from dataclasses import dataclass, field
from pathlib import Path

from refpo_warp.evaluation.run_health import CLIFF, HEALTHY, INSUFFICIENT

MISSING = "--"
METRIC_TITLES = {
    "return_multi": "10-step Reward",
    "return_1": "1-step Reward",
    "return_multi_zero": "10-step, zero noise",
    "return_1_zero": "1-step, zero noise",
    "straightness": "Straightness",
    "explosion": "Explosion",
    "one_step": "1-step Err.",
    "one_step_ratio": "1-step Ratio",
    "jac_expl": "Jac. Expl.",
    "ratio_expl": "Ratio Expl.",
    "jac_norm_mean": "Mean Jac. Norm",
    "jac_norm_p95": "Jac. Norm P95",
    "minutes": "Train min.",
    "return_headline": "Own headline",
}
REWARD_METRICS = ("return_multi", "return_1", "return_multi_zero", "return_1_zero")  # printed with their std
MAIN_METRICS = REWARD_METRICS + ("straightness", "explosion", "one_step", "one_step_ratio", "minutes")
APPENDIX_C_METRICS = ("jac_expl", "ratio_expl", "jac_norm_mean", "jac_norm_p95")
AGGREGATION = (
    "Each method cell pools the method's finished (task, seed) runs: mean over them ± population standard deviation "
    "(ddof = 0) over them, so the spread includes task-to-task and seed-to-seed differences; diagnostics show the mean "
    "only, as the paper does (their std is in the CSV). The CSV also gives the std over per-task means (`_std_tasks`) "
    "and over per-seed means across tasks (`_std_seeds`). Per-task cells: mean ± population std over seeds. "
    "`Runs` counts finished runs / runs in the sweep; `--`: no run of that method has the number."
)

SOURCES_MAIN = (
    'Sources per run (`eval.json`): 10-step Reward = `results["N=<largest N>"].return_mean` (Gaussian policies: '
    '`results["mean_action"]`; `(N=4)` marks a multi-step N other than 10), 1-step Reward = '
    '`results["N=1"].return_mean`, the same under zero initial noise = `results["N=<n>/zero"]` (where the run '
    "evaluated it), Straightness = `diagnostics.straightness_error`, Explosion = "
    "`diagnostics.explosion_rate`; 1-step Err. (ours, not in the paper) = `diagnostics.one_step_error_eval`, the "
    "mean squared gap between the 1-step and the N-step action from the same noise in the env's action space on the "
    "final policy's states, and 1-step Ratio = that gap over the policy's spread (`one_step_ratio_eval`). Train min. "
    "= `train_time_s` / 60 (training only; shared machines run slower); Cliffs = runs whose training reward falls off "
    "a cliff by FPO++'s rule (`health.cliff`: a 50-iteration mean, 100 or more iterations after the peak, 30 % or "
    "more below it), of the finished runs long enough for the rule (150 iterations)."
)
SOURCES_APPENDIX_C = (
    "Means over the same runs as above (std in `appendix_c.csv`). Sources: `diagnostics.jacobian_explosion_rate`, "
    "`explosion_rate`, `jacobian_norm_mean`, `jacobian_norm_p95`."
)


@dataclass
class RunRecord:
    """One run of the grid: its eval.json numbers, or why it has none (``status`` other than ``ok``)."""

    task: str
    label: str
    seed: int
    run_dir: Path
    status: str = "ok"  # ok | missing | failed | stale | unreadable
    note: str = ""
    metrics: dict[str, float] = field(default_factory=dict)
    multi_n: int | None = None  # the multi-step N of the 10-step column (None: Gaussian mean action)
    headline: str = ""  # the setting of the run's own headline (grid/run_metrics.py's headline_setting)
    health: str = ""  # the cliff rule's verdict on its training reward (run_health): healthy | cliff_detected | ...


@dataclass
class Stat:
    mean: float | None = None
    std: float | None = None
    n: int = 0
    std_tasks: float | None = None
    std_seeds: float | None = None


def aggregate(points: list[tuple[str, int, float]]) -> Stat:
    """Mean and population stds of (task, seed, value) points: over all points, per-task means, per-seed means."""
    if not points:
        return Stat()
    values = [v for _, _, v in points]
    by_task: dict[str, list[float]] = {}
    by_seed: dict[int, list[float]] = {}
    for task, seed, value in points:
        by_task.setdefault(task, []).append(value)
        by_seed.setdefault(seed, []).append(value)
    task_means = [statistics.fmean(v) for v in by_task.values()]
    seed_means = [statistics.fmean(v) for v in by_seed.values()]
    return Stat(
        statistics.fmean(values),
        statistics.pstdev(values),
        len(values),
        statistics.pstdev(task_means),
        statistics.pstdev(seed_means),
    )


def fmt_number(x: float | None) -> str:
    if x is None:
        return MISSING
    if abs(x) >= 100:
        return f"{x:.0f}"
    return "0" if x == 0 else f"{x:.3g}"


def fmt_stat(stat: Stat, with_std: bool = True) -> str:
    if stat.n == 0:
        return MISSING
    if not with_std or stat.n == 1:
        return fmt_number(stat.mean)
    return f"{fmt_number(stat.mean)} ± {fmt_number(stat.std)}"


def _points(records: list[RunRecord], metric: str) -> list[tuple[str, int, float]]:
    return [(r.task, r.seed, r.metrics[metric]) for r in records if r.status == "ok" and metric in r.metrics]


def _multi_note(records: list[RunRecord]) -> str:
    steps = sorted({r.multi_n for r in records if r.status == "ok" and r.multi_n is not None})
    return "" if not steps or steps == [10] else f" (N={','.join(map(str, steps))})"


def _runs_cell(records: list[RunRecord]) -> str:
    return f"{sum(r.status == 'ok' for r in records)}/{len(records)}"


def cliff_count(records: list[RunRecord]) -> str:
    """Runs whose training reward fell off a cliff / finished runs long enough to tell (``n/a``: none is)."""
    judged = [r for r in records if r.status == "ok" and r.health in (HEALTHY, CLIFF)]
    return f"{sum(r.health == CLIFF for r in judged)}/{len(judged)}" if judged else "n/a"


def cliffs_markdown(records: list[RunRecord]) -> str:
    """One line per run that fell off a cliff, and how many runs were too short for the rule."""
    ok = [r for r in records if r.status == "ok"]
    lines = [f"- {r.task} / {r.label} / seed {r.seed}: cliff" for r in ok if r.health == CLIFF]
    short = sum(r.health == INSUFFICIENT for r in ok)
    judged = sum(r.health in (HEALTHY, CLIFF) for r in ok)
    if judged and not lines:
        lines = [f"No cliff in the {judged} runs long enough for the rule."]
    if short:
        lines.append(
            f"{short} of {len(ok)} finished runs are too short for the rule, or peak under its minimum "
            f"(insufficient data)."
        )
    return "\n".join(lines) + "\n" if lines else "None.\n"


def method_rows(records: list[RunRecord], methods: list[tuple[str, str]], metrics=MAIN_METRICS) -> list[dict]:
    """One row per method (label, display name): a Stat per metric over all its runs."""
    rows = []
    for label, name in methods:
        mine = [r for r in records if r.label == label]
        stats = {m: aggregate(_points(mine, m)) for m in metrics}
        rows.append({"label": label, "name": name, "records": mine, "stats": stats})
    return rows


def task_rows(records: list[RunRecord], methods: list[tuple[str, str]], tasks: list[str]) -> list[dict]:
    """One row per (task, method): a Stat over seeds per metric of the main table."""
    rows = []
    for task in tasks:
        for row in method_rows([r for r in records if r.task == task], methods):
            if row["records"]:
                rows.append({**row, "task": task})
    return rows


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    return "\n".join(lines) + "\n"


def main_markdown(rows: list[dict]) -> str:
    """The paper's DMC table: rewards as mean ± std, diagnostics as means."""
    header = ["Method", "Runs"] + [METRIC_TITLES[m] for m in MAIN_METRICS] + ["Cliffs"]
    body = []
    for row in rows:
        s = row["stats"]
        body.append(
            [
                row["name"],
                _runs_cell(row["records"]),
                fmt_stat(s["return_multi"]) + (_multi_note(row["records"]) if s["return_multi"].n else ""),
            ]
            + [fmt_stat(s[m]) for m in REWARD_METRICS[1:]]
            + [fmt_stat(s[m], False) for m in MAIN_METRICS[len(REWARD_METRICS) :]]
            + [cliff_count(row["records"])]
        )
    return markdown_table(header, body)


def task_markdown(rows: list[dict]) -> str:
    header = ["Task", "Method", "Runs"] + [METRIC_TITLES[m] for m in MAIN_METRICS] + ["Cliffs"]
    body = [
        [row["task"], row["name"], _runs_cell(row["records"])]
        + [fmt_stat(row["stats"][m]) for m in MAIN_METRICS]
        + [cliff_count(row["records"])]
        for row in rows
    ]
    return markdown_table(header, body)


def appendix_c_markdown(rows: list[dict]) -> str:
    header = ["Method", "Runs"] + [METRIC_TITLES[m] for m in APPENDIX_C_METRICS]
    body = [
        [row["name"], _runs_cell(row["records"])] + [fmt_stat(row["stats"][m], False) for m in APPENDIX_C_METRICS]
        for row in rows
    ]
    return markdown_table(header, body)


def to_csv(rows: list[dict], metrics, per_task: bool = False) -> str:
    """Full-precision CSV: per metric ``_mean``, ``_std``, ``_n`` (and ``_std_tasks``, ``_std_seeds`` per method)."""
    extra = ("std_tasks", "std_seeds") if not per_task else ()
    fields = (["task"] if per_task else []) + ["method", "label", "runs_finished", "runs_total"]
    fields += [f"{m}_{part}" for m in metrics for part in ("mean", "std", "n", *extra)]
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        line = {
            "method": row["name"],
            "label": row["label"],
            "runs_total": len(row["records"]),
            "runs_finished": sum(r.status == "ok" for r in row["records"]),
        }
        if per_task:
            line["task"] = row["task"]
        for m in metrics:
            stat = row["stats"][m]
            for part in ("mean", "std", "n", *extra):
                value = getattr(stat, part)
                line[f"{m}_{part}"] = "" if value is None else (value if part == "n" else repr(value))
        writer.writerow(line)
    return out.getvalue()
