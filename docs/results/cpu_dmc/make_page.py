#!/usr/bin/env python
"""The paper's DMC comparison at the CPU profiles over every committed seed: ``README.md`` in this folder, written
whole from ``README.template.md`` and the per-run rows (nothing typed in by hand):

    python docs/results/cpu_dmc/make_page.py [--add-runs SWEEP_DIR ...] [--check]

Rows: ``runs.csv`` here (PPO, FPO, ReFPO: ``refpo sweep cpu_dmc``) and ``../one_step/search/report/runs.csv``
(``onestep_c03``, the one-step term 0.3 of ``refpo sweep cpu_onestep``, which is ``algo=refpo_onestep``'s training).
``--add-runs`` appends the rows of a sweep dir's ``refpo report`` (``<dir>/report/runs.csv``) for seeds not yet in
the file and copies each run's small files (config.yaml, eval.json, the periodic-evaluation rows) under ``runs/``.
A failed run counts as return 0, as the tuning page counts it.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import append_runs, seeds_text
from refpo_warp.studies.reports.intervals import aggregate, improvement, mean_estimate
from refpo_warp.studies.reports.results_page import page_main

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
ROOT = RESULTS.parents[1]
SOURCES = {  # label shown -> (runs.csv, label in it)
    "ppo": (HERE / "runs.csv", "ppo"),
    "fpo": (HERE / "runs.csv", "fpo"),
    "refpo": (HERE / "runs.csv", "refpo"),
    "refpo_onestep": (RESULTS / "one_step" / "search" / "report" / "runs.csv", "onestep_c03"),
}
NAMES = {"ppo": "PPO", "fpo": "FPO", "refpo": "ReFPO", "refpo_onestep": "ReFPO one-step"}
FLOWS = ("fpo", "refpo", "refpo_onestep")
TASKS = ("dmc_cartpole_balance", "dmc_point_mass", "dmc_reacher_easy")
# sweep name -> (the runs.csv that holds its rows, the folder its runs' small files go to)
SWEEP_OF = {
    "cpu_dmc": (HERE / "runs.csv", HERE / "runs"),
    "cpu_onestep": (SOURCES["refpo_onestep"][0], RESULTS / "one_step" / "search" / "runs"),
}


# ------------------------------------------------------------------------------------------------ data
def read_rows(path: Path) -> list[dict]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def finals(label: str, setting: str) -> dict[str, dict[int, float]]:
    """task -> seed -> the final return at ``setting`` (return_multi: N = 10, PPO's mean action; return_1: N = 1);
    a failed run counts as 0."""
    path, source = SOURCES[label]
    out: dict[str, dict[int, float]] = {t: {} for t in TASKS}
    for row in read_rows(path):
        if row["label"] != source or row["task"] not in out:
            continue
        if row["status"] == "failed":
            out[row["task"]][int(row["seed"])] = 0.0
        elif row["status"] == "ok" and row.get(setting):
            out[row["task"]][int(row["seed"])] = float(row[setting])
    return out


def matrix(runs: dict[str, dict[int, float]]) -> np.ndarray:
    """(seeds x tasks), the seeds every task has."""
    seeds = sorted(set.intersection(*(set(runs[t]) for t in TASKS)))
    return np.array([[runs[t][s] for t in TASKS] for s in seeds])


# ------------------------------------------------------------------------------------------------ adding runs
def add_runs(sweep_dir: Path) -> None:
    """Append the sweep's new seeds to the runs.csv that holds its rows, copying their small files beside it."""
    target, runs_dir = SWEEP_OF[sweep_dir.name]
    added = append_runs(sweep_dir, target, runs_dir, ROOT)
    print(f"{target.relative_to(ROOT)}: {added} run(s) added from {sweep_dir}")


# ------------------------------------------------------------------------------------------------ the page
def verdict(p, x: str, y: str) -> str:
    """What a probability of improvement's interval says about x against y."""
    if p.side > 0:
        return f"{x} beats {y}: the interval lies above 0.5"
    if p.side < 0:
        return f"{y} beats {x}: the interval lies below 0.5"
    return "the interval holds 0.5: these seeds do not separate them"


def table(returns: dict[str, dict[str, dict[int, float]]], setting: str) -> str:
    lines = ["| method | seeds | " + " | ".join(t.removeprefix("dmc_") for t in TASKS) + " |", "|---|---|---|---|---|"]
    for label, runs in returns.items():
        if not any(runs.values()):
            continue
        cells = []
        for task in TASKS:
            cells.append(mean_estimate(runs[task].values()).text())
        seeds = sorted(set.intersection(*(set(runs[t]) for t in TASKS)))
        lines.append(f"| {NAMES[label]} | {seeds_text(seeds)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def budgets() -> str:
    """Each task's env steps and envs at its CPU profile, as today's configs resolve them."""
    from refpo_warp.config.resolve import resolve_config

    parts = []
    for task in TASKS:
        cfg = resolve_config([f"task={task}", "algo=ppo", "device=cpu"], device_type="cpu")
        parts.append(f"{task.removeprefix('dmc_')} {cfg['total_env_steps']:,} env steps in {cfg['num_envs']} envs")
    return "; ".join(parts)


def values() -> dict[str, object]:
    multi = {label: finals(label, "return_multi") for label in SOURCES}
    one = {label: finals(label, "return_1") for label in FLOWS}
    ppo = matrix(multi["ppo"])
    ppo_mean = ppo.mean(axis=0)
    iqm_rows = ["| method | runs | IQM of N = 10 ÷ PPO's mean | IQM of N = 1 ÷ PPO's mean |", "|---|---|---|---|"]
    for label in SOURCES:
        m = matrix(multi[label]) / ppo_mean
        row = aggregate({"m": m})["m"]["iqm"]
        one_cell = "--"
        if label in FLOWS:
            o = aggregate({"m": matrix(one[label]) / ppo_mean})["m"]["iqm"]
            one_cell = o.text(2)
        iqm_rows.append(f"| {NAMES[label]} | {m.size} | {row.text(2)} | {one_cell} |")
    pairs = [(f, "ppo", "return_multi") for f in FLOWS] + [
        ("refpo", "fpo", "return_multi"),
        ("refpo", "fpo", "return_1"),
        ("refpo_onestep", "refpo", "return_1"),
    ]
    poi = []
    for x, y, setting in pairs:
        source = multi if setting == "return_multi" else one
        p = improvement(matrix(source[x]), matrix(source[y]))
        n = "N = 1" if setting == "return_1" else "N = 10" + (" (PPO: its mean action)" if y == "ppo" else "")
        poi.append(f"| {NAMES[x]} over {NAMES[y]} | {n} | {p.text(2)} | {verdict(p, NAMES[x], NAMES[y])} |")
    seeds = sorted({s for runs in multi.values() for task in runs.values() for s in task})
    failed = [
        f"{r['task']}/{r['label']}/seed{r['seed']}"
        for path in dict.fromkeys(p for p, _ in SOURCES.values())
        for r in read_rows(path)
        if r["status"] == "failed"
    ]
    spec = load_yaml(ROOT / "configs" / "sweep" / "cpu_dmc.yaml")
    refpo = next(m for m in spec["methods"] if m["label"] == "refpo")
    return {
        "reflow_coef": refpo["overrides"]["algorithm.reflow_coef"],
        "budgets": budgets(),
        "seeds": seeds_text(seeds),
        "n_seeds": len(seeds),
        "table_multi": table(multi, "return_multi"),
        "table_one": table(dict(one), "return_1"),
        "iqm_table": "\n".join(iqm_rows),
        "poi_table": "\n".join(
            ["| comparison | setting | P(improvement) [95 %] | what it says |", "|---|---|---|---|", *poi]
        ),
        "failed": ", ".join(failed) if failed else "none",
    }


def main() -> None:
    page_main(__doc__.splitlines()[0], HERE / "README.template.md", values, add_runs)


if __name__ == "__main__":
    main()
