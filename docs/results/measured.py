#!/usr/bin/env python
"""The README's measured parts, written from the committed data files: python docs/results/measured.py [--check]

Rewrites each block of README.md between ``<!-- measured: NAME ... -->`` and ``<!-- measured: end -->``:

- ``gif``: the returns of the committed run of the cartpole GIF's command (seed 1 of ``cpu_dmc/runs.csv``) and the
  env steps and iterations of the CPU profiles the two GIFs' runs train (``configs/``);
- ``budget``: "which method at your budget", from the equal-budget tuning study's fresh seeds
  (``tuning/fresh/runs.csv``: each method's per-task interval against tuned PPO's and its probability of
  improvement) and its budget runs (``tuning/budget/``: each run's last periodic return against its peak, by the fall
  share of ``tuning/criteria.yaml``, whose one-step share also judges the fine-tuned runs below);
- ``trend``: the trend to 8x the CPU profile's env steps (``trend/runs.csv`` and its runs, read by the trend page's
  own functions): ReFPO against PPO and against FPO at the smallest and the largest budget, the flows' straightness
  error at each run's end and the runs stopped on a non-finite loss;
- ``demonstrations``: the fine-tuning study's GridWorld clones (``finetuning/gridworld/*/eval.json``) and DMC runs
  (``finetuning/dmc/``, ``finetuning/scratch/``: each run's eval.json);
- ``table``: what the methods learn at the shipped CPU profiles, from
  ``learning_checks/records/gridworld_refpo.jsonl`` (ReFPO on GridWorld), the per-run rows (``runs.csv``) of the DMC
  sweeps listed in ``SWEEPS`` (each cell the mean over the seeds the file holds with its 95 % stratified-bootstrap
  interval, ``refpo_warp/studies/reports/intervals.py``; a failed run counts as return 0, as the tuning page counts
  it) and the fine-tuning runs.

Nothing in a block is typed in by hand: every number is read from the file the block names, and where a verdict
depends on the data the words are chosen here from the numbers. ``--check`` writes nothing and exits 1 with the
difference when README.md is not what the data says (``tests/docs/test_readme_measured.py``).

The helpers it shares with ``index_page.py`` and ``learning_checks_page.py`` (runs.csv rows, intervals, profiles, task
names and env steps) are in ``results_reading.py``.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import json
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from results_reading import (
    RESULTS,
    ROOT,
    count_text,
    estimate,
    eval_results,
    fall_share,
    final_returns,
    interval,
    method_names,
    one_step_share,
    profile_iterations,
    profile_steps,
    read_csv,
    relative,
    short,
    steps_text,
    task_runs,
)

from refpo_warp.studies.reports.committed_runs import read_jsonl, seeds_text
from refpo_warp.studies.reports.intervals import improvement_of
from refpo_warp.studies.reports.phrases import and_list, value_range

if TYPE_CHECKING:  # imported where used: numpy's import is the cost of a page that needs no interval
    from refpo_warp.studies.reports.intervals import Estimate


README = ROOT / "README.md"
BLOCK = re.compile(r"(<!--\s+measured:\s+(\w+)[^>]*-->)(.*?)(<!--\s+measured:\s+end\s+-->)", re.DOTALL)
# (runs.csv of a DMC sweep, the labels shown in this order: None for all, a note on the values)
SWEEPS = [
    ("cpu_dmc/runs.csv", ["ppo", "fpo", "refpo"], ""),
    ("fpo_pp/report/runs.csv", ["fpo_pp", "refpo_pp"], ""),
    ("one_step/search/report/runs.csv", ["onestep_c03"], ""),
    (
        "tuning/fresh/runs.csv",
        ["ppo", "refpo", "refpo_onestep", "fpo_pp"],
        "each method at its values chosen by the equal-budget tuning study (`docs/results/tuning/`)",
    ),
]


# ------------------------------------------------------------------------------------------------ the table
def gridworld_row() -> str | None:
    path = RESULTS / "learning_checks" / "records" / "gridworld_refpo.jsonl"
    if not path.exists():
        return None
    runs = [r for r in read_jsonl(path) if not r["null"] and r["threads"] == 1]
    final = [r["final"] for r in runs]
    success = [min(f[s]["success_rate"] for s in ("N=1", "N=10")) for f in final]
    length = {s: sum(f[s]["length_mean"] for f in final) / len(final) for s in ("N=1", "N=10")}
    share = [min(f[s]["top_share"], f[s]["bottom_share"]) for f in final for s in ("N=1", "N=10")]
    steps = max(r["rows"][-1]["env_steps"] for r in runs)
    return (
        f"| ReFPO on GridWorld, {steps_text(steps)} env steps, seeds "
        f"{seeds_text(r['seed'] for r in runs)} (`{relative(path)}`) | success ≥ {min(success):.3f} at N = 1 and 10; "
        f"episode length {length['N=1']:.1f} / {length['N=10']:.1f} (N = 1 / 10, mean over seeds); the smaller goal "
        f"band's share of successes {min(share):.2f}-{max(share):.2f} |"
    )


def method_cell(name: str, runs: dict[int, dict], all_seeds: set[int]) -> str:
    seeds = sorted(runs)
    cell = f"{name} {estimate([runs[s]['multi'] for s in seeds])}"
    if all(runs[s]["one"] is not None for s in seeds):
        cell += f" / {estimate([runs[s]['one'] for s in seeds])}"
    notes = []
    if set(seeds) != all_seeds:
        notes.append(f"seeds {seeds_text(seeds)}")
    failed = [s for s in seeds if runs[s]["failed"]]
    if failed:
        notes.append(f"seed {seeds_text(failed)} failed: counted as return 0")
    return cell + (f" ({'; '.join(notes)})" if notes else "")


def sweep_rows(relative_csv: str, labels: list[str] | None, note: str) -> list[str]:
    path = RESULTS / relative_csv
    rows = read_csv(path)
    if not rows:
        return []
    names = method_names(path)
    labels = labels or list(dict.fromkeys(r["label"] for r in rows))
    per_label = {label: task_runs(rows, label) for label in labels}
    out = []
    for task in sorted({r["task"] for r in rows}):
        shown = [(label, per_label[label][task]) for label in labels if per_label[label].get(task)]
        if not shown:
            continue
        seeds = set().union(*(set(runs) for _, runs in shown))
        cells = [method_cell(names.get(label, label), runs, seeds) for label, runs in shown]
        out.append(
            f"| {short(task)} ({steps_text(profile_steps(task))} env steps), N = 10 / N = 1 return, mean [95 % "
            f"interval] over seeds {seeds_text(seeds)} (`{relative(path)}`{'; ' + note if note else ''}) | "
            + "; ".join(cells)
            + " |"
        )
    return out


def finetuning_gridworld_row() -> str | None:
    """Success and the bands' shares of the clones and the fine-tuned flows on GridWorld's two-mode demonstrations."""
    folder = RESULTS / "finetuning" / "gridworld"
    names = ("clone_flow", "clone_gauss", "refpo_from_flow", "fpo_from_flow", "ppo_from_gauss")
    found = {name: eval_results(folder / name / "eval.json") for name in names}
    runs = {name: r for name, r in found.items() if r is not None}
    if len(runs) < len(names):
        return None
    seed = json.loads((folder / "clone_flow" / "eval.json").read_text())["seed"]

    def flow(r: dict) -> str:
        return " / ".join(f"{r[s]['success_rate']:.2f} ({r[s]['top_share']:.2f} top)" for s in ("N=10", "N=1"))

    gauss, ppo = runs["clone_gauss"]["mean_action"], runs["ppo_from_gauss"]["mean_action"]
    return (
        f"| GridWorld from scripted two-mode demonstrations, seed {seed} (`{relative(folder)}`), success at N = 10 / "
        f"N = 1 (the top band's share) | flow clone {flow(runs['clone_flow'])}; Gaussian clone "
        f"{gauss['success_rate']:.2f}; fine-tuned: ReFPO {flow(runs['refpo_from_flow'])}, FPO "
        f"{flow(runs['fpo_from_flow'])}, PPO from its clone {ppo['success_rate']:.2f} |"
    )


def seed_returns(folder: Path) -> dict[int, tuple[float, float | None]]:
    """seed -> final (N = 10 or mean-action, N = 1) return of ``folder``'s seed runs (seed<k>/eval.json)."""
    return {int(p.parent.name[4:]): final_returns(p) for p in sorted(folder.glob("seed*/eval.json"))}


def returns_cell(runs: dict[int, tuple[float, float | None]]) -> str:
    cell = estimate([v[0] for v in runs.values()])
    if all(v[1] is not None for v in runs.values()):
        cell += f" / {estimate([v[1] for v in runs.values()])}"
    return cell + f" (seeds {seeds_text(runs)})"


FINETUNED = RESULTS / "finetuning" / "dmc"
SCRATCH = RESULTS / "finetuning" / "scratch"
UPDATED = RESULTS / "finetuning" / "normalizers_updated"
FT_METHODS = ("ppo", "refpo_onestep", "refpo")


def demonstrator(task_dir: Path) -> tuple[float, int, float]:
    """(the demonstrations' policy's periodic return at its checkpoint, that iteration, their action noise std)."""
    meta = json.loads((task_dir / "data" / "metadata.json").read_text())["refpo"]["policy"]
    rows = read_jsonl(task_dir / "demonstrator" / "progress.jsonl")
    value = next(r["eval/return"] for r in rows if r.get("iteration") == meta["iteration"] and "eval/return" in r)
    return value, meta["iteration"], meta["action_noise_std"]


def finetuning_dmc_rows() -> list[str]:
    """Per task: each method's final N = 10 / N = 1 return over its seeds, fine-tuned, fine-tuned with the
    normalisers updated, and from scratch at the same env steps."""
    out = []
    for task_dir in sorted(FINETUNED.glob("dmc_*")):
        cells = []
        for method in FT_METHODS:
            tuned = seed_returns(task_dir / method)
            if not tuned:
                continue
            others = [
                (what, seed_returns(folder / task_dir.name / method))
                for what, folder in (("normalisers updated", UPDATED), ("from scratch", SCRATCH))
            ]
            cells.append(
                f"{method} {returns_cell(tuned)}" + "".join(f", {what} {returns_cell(r)}" for what, r in others if r)
            )
        if cells:
            steps = json.loads(next(task_dir.glob("*/seed*/eval.json")).read_text())["env_steps"]
            value, iteration, noise = demonstrator(task_dir)
            out.append(
                f"| {short(task_dir.name)} fine-tuned for {steps_text(steps)} env steps from the demonstrations "
                f"(action noise std {noise:g}) of a PPO checkpoint returning {value:.0f} (iteration {iteration}; "
                f"`{relative(task_dir)}`; with the normalisers updated from the rollouts: `{relative(UPDATED)}`; "
                f"from scratch at the same env steps: `{relative(SCRATCH)}`), final N = 10 / N = 1 return, mean "
                "[95 % interval] | " + "; ".join(cells) + " |"
            )
    return out


def table() -> str:
    rows = [r for r in [gridworld_row()] if r]
    for relative_csv, labels, note in SWEEPS:
        rows += sweep_rows(relative_csv, labels, note)
    rows += [r for r in [finetuning_gridworld_row()] if r] + finetuning_dmc_rows() + two_way_rows()
    return "\n".join(["", "| Learning result (data file) | Measured |", "|---|---|", *rows, ""])


def two_way_rows() -> list[str]:
    """The two-way task: its clones, fine-tuned from them, and from scratch; success at N = 10 / N = 1 (PPO: its
    mean action), mean [95 % interval] over the committed seeds, from the multimodal pages' files."""
    page = multimodal_page()
    flow, gauss = two_way_clones(page)
    clones = (
        f"| point_mass_wall behaviour cloning of the scripted two-way demonstrator (`docs/results/multimodal/"
        f"clones.json`), success over {flow['episodes']} episodes | flow clone {100 * flow['success']:.0f} % (rarer "
        f"way {100 * flow['rarer']:.0f} % of its passes); Gaussian clone's mean action {100 * gauss['success']:.0f} % |"
    )
    rows = [clones]
    scratch = multimodal_page("scratch")
    two_way = importlib.import_module(type(page.RUNS).__module__)  # two_way_runs.py, beside the page scripts
    for what, runs_of in (("fine-tuned from the clones", page.RUNS), ("from scratch", scratch.RUNS)):
        cells = []
        for method in runs_of.methods():
            label, results = method["label"], runs_of.run_results(method["label"])
            if not results:
                continue
            found = [
                two_way.percent(interval([p["success"] for p in runs_of.numbers_at(label, n).values()]))
                for n in (10, 1)
                if two_way.setting_of(label, n)
            ]
            cells.append(f"{method['name']} {' / '.join(found)}")
        if cells:
            steps = steps_text(runs_of.first_config()["total_env_steps"])
            rows.append(
                f"| point_mass_wall {what} ({steps} env steps), success at N = 10 / N = 1 (PPO: its mean action), "
                f"mean [95 % interval] over seeds {seeds_text(runs_of.seeds())} "
                f"(`{runs_of.runs_csv.relative_to(ROOT)}`) | {'; '.join(cells)} |"
            )
    return rows


# ------------------------------------------------------------------------------------------------ the GIFs
def gif() -> str:
    path = RESULTS / "cpu_dmc" / "runs.csv"
    run = next(
        r for r in read_csv(path) if (r["task"], r["label"], r["seed"]) == ("dmc_cartpole_balance", "refpo", "1")
    )
    return (
        f"{steps_text(profile_steps('dmc_cartpole_balance', 'refpo'))} env steps; the same command's committed run, "
        f"seed 1 of `{relative(path)}`, evaluates at N = 10: {float(run['return_multi']):.0f}, N = 1: "
        f"{float(run['return_1']):.0f}"
    )


def humanoid_gif() -> str:
    task = "humanoid_all_residual"
    return (
        f"{profile_iterations(task, 'refpo')} iterations, {steps_text(profile_steps(task, 'refpo'))} env steps, "
        "the task's CPU profile"
    )


# ------------------------------------------------------------------------------------------------ budget
TUNING = RESULTS / "tuning"
FLOW_NAMES = {"refpo": "ReFPO", "refpo_onestep": "`refpo_onestep`", "fpo_pp": "FPO++"}


def _matrix(runs: dict[str, dict[int, dict]], tasks: list[str]):
    """(seeds x tasks) final N = 10 returns, the i-th seed of each task in a row (the tuning page's matrix)."""
    import numpy as np

    n = min(len(runs[t]) for t in tasks)
    return np.array([[runs[t][sorted(runs[t])[i]]["multi"] for t in tasks] for i in range(n)])


def fresh_standing() -> dict | None:
    """Each tuned flow method against tuned PPO on the fresh seeds: the tasks where its interval reaches PPO's, and
    P(improvement) with its interval (``intervals.improvement``, as the tuning page computes it)."""
    from refpo_warp.studies.reports.intervals import improvement

    path = TUNING / "fresh" / "runs.csv"
    rows = read_csv(path)
    if not rows:
        return None
    tasks = sorted({r["task"] for r in rows})
    ppo = task_runs(rows, "ppo")
    if not all(ppo.get(t) for t in tasks):
        return None
    seeds: set[int] = set()
    flows: dict[str, dict] = {}
    for label in FLOW_NAMES:
        runs = task_runs(rows, label)
        if not all(runs.get(t) for t in tasks):
            continue
        reach = sum(
            interval([v["multi"] for v in runs[t].values()]).overlaps_or_above(
                interval([v["multi"] for v in ppo[t].values()])
            )
            for t in tasks
        )
        poi = improvement(_matrix(runs, tasks), _matrix(ppo, tasks))
        flows[label] = {"reach": reach, "poi": poi}
        seeds |= {s for t in tasks for s in runs[t]}
    seeds |= {s for t in tasks for s in ppo[t]}
    return {"path": path, "tasks": tasks, "seeds": seeds, "flows": flows}


def budget_runs() -> dict[str, list[dict]]:
    """label -> per seed {seed, peak, last, stopped} of the budget runs' periodic N = 10 (or mean-action) return; a
    run stopped on a non-finite loss counts as 0 from its stop on (its last return is 0)."""
    out: dict[str, list[dict]] = {}
    for path in sorted((TUNING / "budget").glob("*/*/seed*/progress_eval.jsonl")):
        rows = read_jsonl(path)
        key = next((k for k in ("eval/return_N10", "eval/return") if k in rows[0]), None)
        if key is None:
            continue
        stopped = (path.parent / "stopped.json").exists()
        values = [r[key] for r in rows]
        out.setdefault(path.parents[1].name, []).append(
            {
                "seed": int(path.parent.name[4:]),
                "task": path.parents[2].name,
                "peak": max(values),
                "last": 0.0 if stopped else values[-1],
                "steps": rows[-1]["env_steps"],
                "stopped": stopped,
            }
        )
    return out


def budget() -> str:
    fresh = fresh_standing()
    if fresh is None or not fresh["flows"]:
        return "the equal-budget study has no fresh-seed runs of every method yet (`docs/results/tuning/`)"
    flows = fresh["flows"]
    best = max(flows, key=lambda k: flows[k]["poi"].point)
    poi = flows[best]["poi"]
    ntasks = len(fresh["tasks"])
    steps = sorted({profile_steps(t) for t in fresh["tasks"]})
    where = (
        f"Measured on a CPU at the DMC tasks' CPU profiles ({'-'.join(steps_text(s) for s in (steps[0], steps[-1]))} "
        f"env steps), seeds {seeds_text(fresh['seeds'])} of `{relative(fresh['path'])}`: "
    )
    best_text = (
        f"{FLOW_NAMES[best]}, reaches tuned PPO's 95 % interval on {flows[best]['reach']} of {ntasks} tasks, with a "
        f"probability of improvement over PPO of {poi.text(2)}"
    )
    ppo_leads = all(f["poi"].point < 0.5 for f in flows.values())
    if all(f["poi"].side < 0 for f in flows.values()):
        verdict = f"with equal tuning, Gaussian PPO leads (the best tuned flow method, {best_text})"
    elif ppo_leads:
        verdict = (
            "with equal tuning, Gaussian PPO leads on the point estimates, not beyond their intervals (the best "
            f"tuned flow method, {best_text}, an interval that reaches 0.5)"
        )
    elif poi.side > 0:
        verdict = f"with equal tuning, a flow method leads PPO ({best_text})"
    else:
        verdict = f"with equal tuning, no method leads (the best tuned flow method, {best_text})"
    runs = budget_runs()
    parts = []
    collapse_all, ppo_holds = False, False
    for label, seeds in sorted(runs.items(), key=lambda kv: kv[0] == "ppo"):
        fell = [r for r in seeds if r["last"] < fall_share() * r["peak"]]
        stopped = sum(r["stopped"] for r in seeds)
        name = "PPO" if label == "ppo" else FLOW_NAMES.get(label, label)
        parts.append(
            f"{count_text(len(fell), len(seeds))} seeds of {name}"
            + (f" ({stopped} stopped on a non-finite loss, counted as 0 from there)" if stopped else "")
        )
        if label == "ppo":
            ppo_holds = len(seeds) - len(fell) > len(seeds) / 2
        else:
            collapse_all = len(fell) == len(seeds)
    budget_text = ""
    if runs:
        first = next(iter(runs.values()))[0]
        longest = max(r["steps"] for seeds in runs.values() for r in seeds)
        budget_text = (
            f", and on {short(first['task'])} at {longest / profile_steps(first['task']):.0f}× the CPU "
            f"profile's env steps, at the tuned values (`{relative(TUNING / 'budget')}`), the periodic return ends "
            f"below {fall_share():g} × its peak in " + " and in ".join(parts)
        )
    advice = (
        ": pick PPO for a from-scratch run at this budget, a flow policy for one-step multimodal actions"
        if ppo_leads and collapse_all and ppo_holds
        else ""
    )
    return where + verdict + budget_text + advice


# ------------------------------------------------------------------------------------------------ trend
def trend() -> str:
    """The trend to 8x the CPU profile's env steps at the paper's values (trend/runs.csv, the trend page's own
    reading): ReFPO against PPO at the smallest and the largest budget, whether any flow method leads PPO at any
    budget, and ReFPO against FPO in returns, straightness and non-finite stops."""
    page = page_script("trend", "make_page")
    rows = page.committed()
    _, found = page.gap_table(rows)
    if "refpo" not in found or "fpo" not in found:
        return "the trend's ReFPO, FPO and PPO runs are not committed yet (`docs/results/trend/`)"
    refpo = found["refpo"]
    first, last = min(refpo), max(refpo)
    seeds = sorted({int(r["seed"]) for r in rows})
    averaged = page.last_checkpoint_gaps(page.last_checkpoint(rows)).get("refpo")
    text = (
        f"Measured on a CPU, seeds {seeds_text(seeds)} of `{relative(page.RUNS_CSV)}`: P(a ReFPO run beats a PPO run "
        f"at N = 10) {refpo[first].text(2)} at {first}×, {refpo[last].text(2)} at {last}×"
    )
    if averaged is not None:
        text += f" (from each run's two evaluations of its last checkpoint averaged, {averaged[1]['averaged'].text(2)})"
    ahead = [f"{page.METHODS[label]} at {m}×" for label, by in found.items() for m, g in by.items() if g.side > 0]
    text += f", and {and_list(ahead)} ahead of PPO" if ahead else ", and no flow method is ahead of PPO at any budget"
    over_fpo = page.refpo_over_fpo(rows)
    bends = {task: page.final_straightness(rows, task) for task in page.TASKS}
    bent = all(improvement_of(b["fpo"], b["refpo"]).side > 0 for b in bends.values())
    stopped = {label: sum(r["status"] == "failed" for r in rows if r["label"] == label) for label in ("fpo", "refpo")}
    runs = {label: sum(r["label"] == label for r in rows) for label in ("fpo", "refpo")}
    fpo_errors = [e for b in bends.values() for e in b["fpo"]]
    refpo_errors = [e for b in bends.values() for e in b["refpo"]]
    text += (
        f"; P(a ReFPO run beats an FPO run) {over_fpo[first][0].text(2)} at {first}× and "
        f"{over_fpo[last][0].text(2)} at {last}×, "
        f"the flow's straightness error at each run's end {value_range(refpo_errors, '.3g')} for ReFPO and "
        f"{value_range(fpo_errors, '.3g')} for FPO"
        + (" (every FPO run above every ReFPO run on each task)" if bent else "")
        + f", and {stopped['fpo']} of {runs['fpo']} FPO runs stopped on a non-finite loss, "
        f"{stopped['refpo']} of {runs['refpo']} ReFPO runs"
    )
    if bent and stopped["refpo"] <= stopped["fpo"] and over_fpo[first][0].side > 0 and not ahead:
        text += ": for runs past the CPU budget pick ReFPO over FPO; "
        text += f"up to {last}× the budget, no flow method overtakes PPO"
    return text


# ------------------------------------------------------------------------------------------------ demonstrations


def grouped(by_method: dict[str, list[str]]) -> str:
    """``refpo_onestep (point_mass, reacher_easy) and refpo (reacher_easy)``."""
    return and_list([f"{m} ({', '.join(tasks)})" for m, tasks in by_method.items()])


def demonstrations() -> str:
    folder = RESULTS / "finetuning" / "gridworld"
    flow, gauss = eval_results(folder / "clone_flow" / "eval.json"), eval_results(folder / "clone_gauss" / "eval.json")
    if flow is None or gauss is None:
        return "the fine-tuning study's GridWorld runs are not committed yet"
    g = gauss["mean_action"]
    f = flow["N=10"]
    both = 0 < f["top_share"] < 1
    grid = (
        "on GridWorld's two-mode demonstrations the flow clone "
        + (
            f"reaches both goals (success {f['success_rate']:.2f} at N = 10, the top band's share {f['top_share']:.2f})"
            if both
            else f"reaches one goal only (success {f['success_rate']:.2f} at N = 10)"
        )
        + f" and the Gaussian clone reaches neither in {100 * (1 - g['success_rate']):.0f} % of its "
        f"{g['episodes']} episodes"
    )
    above: dict[str, list[str]] = {}
    overlap: dict[str, list[str]] = {}
    holds: dict[str, list[str]] = {}
    highest: dict[str, tuple[str, Estimate, list[str]]] = {}
    tasks = []
    for task_dir in sorted(FINETUNED.glob("dmc_*")):
        tasks.append(short(task_dir.name))
        means = {}
        for method in FT_METHODS:
            tuned, scratch = seed_returns(task_dir / method), seed_returns(SCRATCH / task_dir.name / method)
            if not tuned:
                continue
            means[method] = interval([v[0] for v in tuned.values()])
            if scratch:
                e_t, e_s = means[method], interval([v[0] for v in scratch.values()])
                (above if e_t.low > e_s.high else overlap).setdefault(method, []).append(short(task_dir.name))
        for method in ("refpo_adaptive", "refpo_onestep"):
            runs = seed_returns(task_dir / method)
            if runs:
                kept = sum(one is not None and one >= one_step_share() * multi for multi, one in runs.values())
                holds.setdefault(method, []).append(f"{kept} of {len(runs)} runs on {short(task_dir.name)}")
        for method in [p.name for p in sorted(task_dir.iterdir()) if list(p.glob("seed*/eval.json"))]:
            means.setdefault(method, interval([v[0] for v in seed_returns(task_dir / method).values()]))
        top = max(means, key=lambda m: means[m].point)
        beaten = [m for m in means if m != top and means[m].high >= means[top].low]  # intervals that overlap
        highest[short(task_dir.name)] = (top, means[top], beaten)
    if not tasks:
        return grid
    names = {"refpo_adaptive": "ReFPO with adaptive λ", "refpo_onestep": "`refpo_onestep`"}
    steps = json.loads(next(FINETUNED.glob("dmc_*/*/seed*/eval.json")).read_text())["env_steps"]
    dmc = (
        f"; on {' and '.join(tasks)}, from a PPO checkpoint's noisy demonstrations and fine-tuned for "
        f"{steps_text(steps)} env steps, the final N = 10 return's 95 % interval lies above the same method's from "
        f"scratch at those env steps for {grouped(above) or 'no method'}"
        + (f", and overlaps it for {grouped(overlap)}" if overlap else "")
        + f"; N = 1 keeps at least {one_step_share():g} × the N = 10 return in "
        + "; in ".join(f"{and_list(where)} for {names[m]}" for m, where in holds.items())
    )
    for task, (top, e, beaten) in highest.items():
        who = "PPO from its Gaussian clone" if top == "ppo" else top
        dmc += f"; the highest mean on {task}: {who} ({e.point:.0f} [{e.low:.0f}, {e.high:.0f}]" + (
            f"; its interval overlaps those of {and_list(beaten)})" if beaten else ", above every other method's)"
        )
    return grid + dmc


def page_script(folder: str, script: str):
    """A results page's script (``<folder>/<script>.py``), its functions read, not run; its folder goes on the path
    for the scripts it imports (multimodal/two_way_runs.py and the rest)."""
    import importlib.util

    where = str(RESULTS / folder)
    if where not in sys.path:
        sys.path.append(where)
    path = RESULTS / folder / f"{script}.py"
    spec = importlib.util.spec_from_file_location(f"{folder}_{script}", path)
    if spec is None or spec.loader is None:
        raise SystemExit(f"{path}: not a Python script")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def multimodal_page(script: str = "finetuning"):
    """A two-way task page's script: multimodal/finetuning.py or multimodal/scratch.py."""
    return page_script("multimodal", script)


def multimodal_scratch() -> tuple[str, int, int]:
    """The two-way task from scratch: how many runs of each kind reach the target (success at N = 10, PPO's mean
    action, at least the page's floor): the clause, the runs that reach it and the runs."""
    page = multimodal_page("scratch")
    runs_of = page.RUNS
    reached, total = 0, 0
    for method in runs_of.methods():
        for n in runs_of.numbers_at(method["label"], 10).values():
            total += 1
            reached += n["success"] >= page.SUCCESS_FLOOR
    if not total:
        return "", 0, 0
    sweep = page.load_yaml(runs_of.sweep)
    seeds = runs_of.seeds()
    text = (
        f"; from scratch at the task's full CPU budget ({steps_text(runs_of.first_config()['total_env_steps'])} env "
        f"steps, seeds {seeds_text(seeds)}{'' if seeds == sweep['seeds'] else ' so far'}), {reached} of "
        f"{total} runs of the {len(runs_of.methods())} methods reach the target in {100 * page.SUCCESS_FLOOR:.0f} % "
        "of their episodes"
    )
    return text, reached, total


def two_way_clones(page) -> tuple[dict[str, float], dict[str, float]]:
    """The flow clone's numbers at N = 10 and the Gaussian clone's at its mean action (the fine-tuning page's)."""
    return page.clone_numbers("clone_flow", "N=10"), page.clone_numbers("clone_gauss", "mean_action")


def multimodal() -> str:
    page = multimodal_page()
    flow, gauss = two_way_clones(page)
    text = (
        f"on `dmc_point_mass_wall`, a continuous task with two ways to its target, the flow clone of two-mode "
        f"demonstrations reaches the target in {100 * flow['success']:.0f} % of {flow['episodes']} episodes, its "
        f"rarer way {100 * flow['rarer']:.0f} % of its passes, and the Gaussian clone's mean action in "
        f"{100 * gauss['success']:.0f} %"
    )
    outcomes, ppo = {"both ways": 0, "one way": 0, "lost": 0}, []
    runs_of = page.RUNS
    for method in runs_of.methods():
        for n in runs_of.numbers_at(method["label"], 10).values():
            if method["label"] == "ppo":
                ppo.append(n["success"])
            else:
                outcomes[page.outcome(n)] += 1
    runs = sum(outcomes.values())
    if not runs:
        return text
    sweep = page.load_yaml(runs_of.sweep)
    steps = sweep["overrides"]["total_env_steps"]
    seeds = runs_of.seeds()
    text += (
        f"; fine-tuned from their clones for {steps_text(steps)} env steps (seed{'s' if len(seeds) > 1 else ''} "
        f"{seeds_text(seeds)}{'' if seeds == sweep['seeds'] else ' so far'}), "
        f"of {runs} flow-policy runs (ReFPO, ReFPO with adaptive λ, FPO, FPO++) {outcomes['both ways']} kept both "
        f"ways, {outcomes['one way']} one way and {outcomes['lost']} lost the task (success below "
        f"{100 * page.SUCCESS_FLOOR:.0f} % at N = 10)"
    )
    if ppo:
        text += f", and PPO from the Gaussian clone ends at a success of {estimate([100 * v for v in ppo])} %"
    scratch, reached, tried = multimodal_scratch()
    text += scratch + ": "
    if tried and not reached:
        text += "without demonstrations no method finds this task's target at this budget; with them, "
    if outcomes["lost"] > runs / 2:
        return text + (
            "pick a flow policy to clone demonstrations that hold several ways; at these values, fine-tuning it lost "
            "the task in most runs"
        )
    if outcomes["both ways"] > runs / 2:
        return text + "pick a flow policy for demonstrations that hold several ways, cloned and fine-tuned"
    return text + "pick a flow policy to clone demonstrations that hold several ways; fine-tuned, most runs keep one"


# ------------------------------------------------------------------------------------------------ the page
BLOCKS = {
    "gif": gif,
    "humanoid_gif": humanoid_gif,
    "budget": budget,
    "trend": trend,
    "demonstrations": demonstrations,
    "multimodal": multimodal,
    "table": table,
}


def render(text: str) -> str:
    found = [m.group(2) for m in BLOCK.finditer(text)]
    unknown, missing = sorted(set(found) - set(BLOCKS)), sorted(set(BLOCKS) - set(found))
    if unknown or missing:
        raise SystemExit(f"{README}: unknown measured blocks {unknown}, blocks missing {missing}")
    values = {name: make() for name, make in BLOCKS.items()}
    return BLOCK.sub(lambda m: m.group(1) + values[m.group(2)] + m.group(4), text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="compare README.md with the data; exit 1 if it differs")
    args = parser.parse_args()
    old = README.read_text(encoding="utf-8")
    new = render(old)
    if args.check:
        if old != new:
            diff = difflib.unified_diff(old.splitlines(), new.splitlines(), str(README), "from the data", lineterm="")
            print("\n".join(diff))
            sys.exit(1)
        return
    if old != new:
        from refpo_warp.utils.atomic_files import write_text

        write_text(README, new)
    print(f"{README}: measured blocks {'written' if old != new else 'unchanged'}")


if __name__ == "__main__":
    main()
