#!/usr/bin/env python
"""The numbers of ``README.md`` in this folder, from the committed data files (nothing typed in by hand):

    python docs/results/tuning/make_page.py [--sync runs/tune/cpu_dmc] [--sync-fresh DIR] [--sync-budget DIR]

``--sync`` first copies a study's small files here (``study/``: the Optuna journal, trials.csv, chosen.yaml,
evaluate.yaml, and each trial run's config.yaml, eval.json and periodic-evaluation rows); ``--sync-fresh`` the
fresh-seed sweep's report (``fresh/runs.csv``, from ``refpo report``) and its runs' small files; ``--sync-budget``
the budget sweep's runs' small files (``budget/``). Then it writes the tables between ``<!-- tuning: <name> -->``
and ``<!-- tuning: end -->`` markers of README.md, and ``budget_curves.png``.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import shutil
import statistics
import sys
from pathlib import Path

import numpy as np
import yaml

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
PAGE = HERE / "README.md"
STUDY = HERE / "study"
FRESH = HERE / "fresh"
BUDGET = HERE / "budget"
TUNING_FILE = RESULTS.parents[1] / "configs" / "tune" / "cpu_dmc.yaml"
TASKS = ("dmc_cartpole_balance", "dmc_point_mass", "dmc_reacher_easy")
# The committed rows at the paper's (or the authors') values, seeds 1-3: (runs.csv, label) per method.
COMMITTED = {
    "ppo": (RESULTS / "cpu_dmc" / "runs.csv", "ppo"),
    "refpo": (RESULTS / "cpu_dmc" / "runs.csv", "refpo"),
    "refpo_onestep": (RESULTS / "one_step" / "search" / "report" / "runs.csv", "onestep_c03"),
    "fpo_pp": (RESULTS / "fpo_pp" / "report" / "runs.csv", "fpo_pp"),
}
NAMES = {"ppo": "PPO", "refpo": "ReFPO", "refpo_onestep": "ReFPO one-step", "fpo_pp": "FPO++"}
RUN_FILES = ("config.yaml", "eval.json")


# ------------------------------------------------------------------------------------------------ copying
def _eval_rows(src: Path) -> str:
    """The progress rows that hold a periodic evaluation (the curves a page needs), not the per-update rows."""
    keep = []
    for line in src.read_text().splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        if any(k.startswith("eval/return") for k in row):
            keep.append(
                json.dumps(
                    {
                        k: v
                        for k, v in row.items()
                        if k in ("iteration", "env_steps", "time_s")
                        or k.startswith("eval/return")
                        or k == "reward_mean"
                    }
                )
            )
    return "\n".join(keep) + ("\n" if keep else "")


def copy_runs(src: Path, dst: Path) -> int:
    """Every finished run under ``src`` (a folder with eval.json): its small files into the same place under dst."""
    count = 0
    for evaluation in sorted(src.rglob("eval.json")):
        run = evaluation.parent
        target = dst / run.relative_to(src)
        target.mkdir(parents=True, exist_ok=True)
        for name in RUN_FILES:
            if (run / name).exists():
                shutil.copy2(run / name, target / name)
        if (run / "progress.jsonl").exists():
            (target / "progress_eval.jsonl").write_text(_eval_rows(run / "progress.jsonl"))
        count += 1
    return count


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
            row = {"iteration": int(match.group(1)), "env_steps": int(match.group(2).replace(",", ""))}
            row.update({f"eval/{k}": float(v) for k, v in zip(pairs[::2], pairs[1::2], strict=True)})
            rows.append(row)
    stopped_at = re.match(r"^\[it +(\d+)/\d+\] +steps +([\d,]+)", last or "")
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


# ------------------------------------------------------------------------------------------------ the study
def trials() -> list[dict]:
    path = STUDY / "trials.csv"
    return list(csv.DictReader(path.open(encoding="utf-8"))) if path.exists() else []


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


def spaces_table() -> str:
    from refpo_warp.sweeps.tune import config_values
    from refpo_warp.sweeps.tune_spec import load_tuning

    spec = yaml.safe_load(TUNING_FILE.read_text())
    tuning = load_tuning(str(TUNING_FILE))
    first = {(m.label, k): v for m in tuning.methods for k, v in config_values(tuning, m).items()}
    lines = ["| method | option | searched | first trial (its own config) |", "|---|---|---|---|"]
    for m in spec["methods"]:
        for key, dim in m["space"].items():
            space = (
                "{" + ", ".join(str(c) for c in dim["choices"]) + "}"
                if "choices" in dim
                else f"[{dim['low']:g}, {dim['high']:g}]" + (" log" if dim.get("log") else "")
            )
            lines.append(f"| {m['name']} | `{key}` | {space} | {_fmt(first.get((m['label'], key)))} |")
    return "\n".join(lines)


def trials_table() -> str:
    spec = yaml.safe_load(TUNING_FILE.read_text())
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
    spec = yaml.safe_load(TUNING_FILE.read_text())
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
    path = STUDY / "chosen.yaml"
    if not path.exists():
        return "No completed trial yet."
    chosen = yaml.safe_load(path.read_text()) or {}
    lines = ["| method | trial | score | values |", "|---|---|---|---|"]
    for label, c in chosen.items():
        values = ", ".join(f"`{k}` {_fmt(v)}" for k, v in c["overrides"].items())
        lines.append(f"| {NAMES.get(label, label)} | {c['trial']} | {c['score']:.3f} | {values} |")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ fresh seeds
def run_returns(path: Path, label: str) -> dict[str, dict[int, tuple[float, float | None]]]:
    """task -> seed -> (N = 10 return (a Gaussian's mean action), N = 1 return or None) of a method's runs. A run that
    failed (its training stopped, e.g. on a non-finite loss) counts as return 0 at both: leaving it out would flatter
    its method."""
    out: dict[str, dict[int, tuple[float, float | None]]] = {}
    if not path.exists():
        return out
    for r in csv.DictReader(path.open(encoding="utf-8")):
        if r["label"] != label:
            continue
        if r["status"] == "ok" and r["return_multi"]:
            out.setdefault(r["task"], {})[int(r["seed"])] = (float(r["return_multi"]), _num(r.get("return_1")))
        elif r["status"] == "failed":
            out.setdefault(r["task"], {})[int(r["seed"])] = (0.0, 0.0)
    return out


def failed_runs(path: Path) -> list[str]:
    """'task/label/seed' of the runs that failed (counted as return 0)."""
    if not path.exists():
        return []
    rows = csv.DictReader(path.open(encoding="utf-8"))
    return [f"{r['task']}/{r['label']}/seed{r['seed']}" for r in rows if r["status"] == "failed"]


def fresh_table() -> str:
    from refpo_warp.sweeps.intervals import aggregate, improvement

    fresh_csv = FRESH / "runs.csv"
    if not fresh_csv.exists():
        return 'Not run yet: the study has to finish first (see "Resuming").'
    reference = yaml.safe_load(TUNING_FILE.read_text())["objective"]["reference"]
    ppo_committed = run_returns(COMMITTED["ppo"][0], "ppo")
    scale = {t: reference.get(t) or statistics.mean(v[0] for v in ppo_committed[t].values()) for t in TASKS}
    rows, scores = [], {}
    for label in ("ppo", "refpo", "refpo_onestep", "fpo_pp"):
        for kind, (path, name) in (("paper", COMMITTED[label]), ("tuned", (fresh_csv, label))):
            runs = run_returns(path, name)
            if not all(runs.get(t) for t in TASKS):
                continue
            n = min(len(runs[t]) for t in TASKS)
            matrix = np.array([[runs[t][s][0] for t in TASKS for s in [sorted(runs[t])[i]]] for i in range(n)])
            key = f"{label}/{kind}"
            scores[key] = matrix / np.array([scale[t] for t in TASKS])
            per_task = [aggregate({"x": np.array([[v[0]] for v in runs[t].values()])})["x"]["mean"] for t in TASKS]
            rows.append((key, runs, per_task))
    agg = aggregate(scores)
    head = "| method | values | " + " | ".join(t.removeprefix("dmc_") for t in TASKS) + " | IQM (÷ PPO's) |"
    lines = [head, "|---|---|" + "---|" * (len(TASKS) + 1)]
    for key, runs, per_task in rows:
        label, kind = key.split("/")
        seeds = sorted({s for t in TASKS for s in runs[t]})
        cells = [f"{e.point:.0f} [{e.low:.0f}, {e.high:.0f}]" for e in per_task]
        iqm = agg[key]["iqm"]
        values = ("paper's" if label != "fpo_pp" else "authors'") if kind == "paper" else "tuned"
        lines.append(
            f"| {NAMES[label]} | {values}, seeds {seeds[0]}-{seeds[-1]} | "
            + " | ".join(cells)
            + f" | {iqm.point:.2f} [{iqm.low:.2f}, {iqm.high:.2f}] |"
        )
    lines.append("")
    ppo = next(((k, p) for k, _, p in rows if k == "ppo/tuned"), None)
    for key, _, per_task in rows:
        if key.endswith("/tuned") and ppo is not None and key != ppo[0]:
            reach = sum(e.overlaps_or_above(q) for e, q in zip(per_task, ppo[1]))
            poi = improvement(scores[key], scores[ppo[0]])
            lines.append(
                f"- {NAMES[key.split('/')[0]]} (tuned) against PPO (tuned): its interval reaches PPO's on "
                f"{reach} of {len(TASKS)} tasks; P(improvement) {poi.point:.2f} [{poi.low:.2f}, "
                f"{poi.high:.2f}]"
            )
    failed = failed_runs(fresh_csv)
    if failed:
        lines.append(f"- Failed runs, counted as return 0 at N = 10 and N = 1: {', '.join(failed)}")
    onestep = run_returns(fresh_csv, "refpo_onestep")
    pairs = [(t, s, v) for t in TASKS for s, v in sorted(onestep.get(t, {}).items())]
    held = sum(v[1] is not None and v[1] >= 0.9 * v[0] for _, _, v in pairs)
    if pairs:
        lines.append(f"- ReFPO one-step (tuned): N = 1 ≥ 0.9 × N = 10 in {held} of {len(pairs)} (task, seed) pairs")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ budget
def budget_curves() -> str:
    runs = sorted(BUDGET.glob("*/*/seed*/progress_eval.jsonl"))
    if not runs:
        return "Not run yet: it needs the best flow method of the study."
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    curves: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    stops = []
    grid = None  # every run evaluates at the same iterations; a stopped run's missing points count as 0
    for path in runs:
        rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
        key = next((k for k in ("eval/return_N10", "eval/return") if k in rows[0]), None)
        if key is None:
            continue
        steps, values = np.array([r["env_steps"] for r in rows]), np.array([r[key] for r in rows])
        if (path.parent / "stopped.json").exists():
            stop = json.loads((path.parent / "stopped.json").read_text())
            stops.append(f"{path.parents[1].name}/{path.parent.name} at {stop['env_steps'] / 1e6:.2f}M env steps")
        elif grid is None or len(steps) > len(grid):
            grid = steps
        curves.setdefault(path.parents[1].name, []).append((steps, values))
    if grid is not None:
        for label, series in curves.items():
            curves[label] = [(grid, np.concatenate([v, np.zeros(len(grid) - len(v))])) for _, v in series]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    lines = ["| method | seeds | 1× (1M env steps) | 2× | 4× |", "|---|---|---|---|---|"]
    for label, series in sorted(curves.items()):
        steps = series[0][0]
        values = np.array([v[: len(steps)] for _, v in series if len(v) >= len(steps)])
        mean = values.mean(axis=0)
        ax.plot(steps / 1e6, mean, label=NAMES.get(label, label))
        ax.fill_between(steps / 1e6, values.min(axis=0), values.max(axis=0), alpha=0.2)
        # the CPU profile's 66 iterations of 15,360 env steps, and two and four times that
        marks = [
            f"{np.interp(x, steps, mean):.0f} ({np.interp(x, steps, values.min(axis=0)):.0f}-"
            f"{np.interp(x, steps, values.max(axis=0)):.0f})"
            for x in (k * 1_013_760 for k in (1, 2, 4))
        ]
        lines.append(f"| {NAMES.get(label, label)} | {len(values)} | " + " | ".join(marks) + " |")
    ax.set_xlabel("env steps (M)")
    ax.set_ylabel("periodic return (N = 10 / mean action)")
    ax.set_title("point_mass: return against budget (mean, min-max over seeds)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(HERE / "budget_curves.png", dpi=120)
    lines += ["", "Cells: the periodic return's mean over seeds (min-max) at 1×, 2× and 4× the profile's env steps."]
    if stops:
        lines.append("")
        lines.append(f"Stopped on a non-finite loss (counted as 0 from there on): {', '.join(stops)}.")
    return "\n".join(lines) + "\n\n![budget curves](budget_curves.png)"


# ------------------------------------------------------------------------------------------------ page
SECTIONS = {
    "spaces": spaces_table,
    "trials": trials_table,
    "budget": budget_table,
    "chosen": chosen_table,
    "fresh": fresh_table,
    "curves": budget_curves,
}


def write_page() -> None:
    text = PAGE.read_text()
    for name, make in SECTIONS.items():
        pattern = re.compile(rf"(<!-- tuning: {name} -->\n)(?:.*?\n)??(<!-- tuning: end -->)", re.DOTALL)
        if not pattern.search(text):
            sys.exit(f"error: {PAGE} lacks the markers <!-- tuning: {name} --> ... <!-- tuning: end -->")
        body = make()
        text = pattern.sub(lambda m, body=body: m.group(1) + body + "\n" + m.group(2), text, count=1)
    PAGE.write_text(text)
    print(f"wrote {PAGE}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sync", type=Path, help="a refpo tune out dir, e.g. runs/tune/cpu_dmc")
    parser.add_argument("--sync-fresh", type=Path, help="the fresh-seed sweep dir (with its report/)")
    parser.add_argument("--sync-budget", type=Path, help="the budget sweep dir")
    args = parser.parse_args()
    for folder, sync in ((args.sync, sync_study), (args.sync_fresh, sync_fresh), (args.sync_budget, sync_budget)):
        if folder is not None:
            sync(folder)
    write_page()
