#!/usr/bin/env python
"""Toward the paper's budget on the CPU: ``README.md`` in this folder, written whole from ``README.template.md`` and the
committed runs of ``refpo sweep trend_8x`` (nothing typed in by hand):

    python docs/results/trend/make_page.py [--add-runs runs/sweeps/trend_8x] [--check]

Rows: ``runs.csv`` here (``refpo report`` of the sweep); each run's periodic evaluations (``progress_eval.jsonl``,
one at every multiple of the profile's budget) and training statistics (``progress_train.jsonl``) under ``runs/``.
``--add-runs`` appends the finished runs of a sweep dir not yet in the table and copies their small files; the page
shows every run committed so far and names the grid's runs still to come.
"""

from __future__ import annotations

import functools
import itertools
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import append_runs, read_jsonl, read_rows, run_machine, seeds_text
from refpo_warp.studies.reports.intervals import Estimate, improvement, improvement_of, mean_estimate
from refpo_warp.studies.reports.phrases import and_list, machine_text, value_range
from refpo_warp.studies.reports.results_page import page_main
from refpo_warp.utils.atomic_files import save_figure

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
SWEEP = load_yaml(ROOT / "configs" / "sweep" / "trend_8x.yaml")
TASKS: tuple[str, ...] = tuple(SWEEP["tasks"])
METHODS = {m["label"]: m["name"] for m in SWEEP["methods"]}
FLOWS = tuple(label for label in METHODS if label != "ppo")
COLOURS = {"ppo": "#2ca02c", "fpo": "#ff7f0e", "refpo": "#1f77b4", "refpo_onestep": "#9467bd"}
RUNS_CSV, RUNS_DIR = HERE / "runs.csv", HERE / "runs"
# Where the runs made before eval.json recorded its machine ran (docs/results/history.md, sessions 7-9)
UNRECORDED_MACHINE = "a 2-core AMD EPYC (AVX2) shared with other work, one torch thread a run (not recorded by the run)"


# ------------------------------------------------------------------------------------------------ data
def profile_iterations() -> int:
    """Iterations of the CPU profile's budget: the sweep's evaluation interval (one evaluation per multiple)."""
    return int(SWEEP["overrides"]["eval"]["interval"])


def multiples() -> list[int]:
    """The budgets the tables show, as multiples of the profile's: 1, 2, 4, ... up to the sweep's (the periodic
    evaluations fall at every multiple; the curves show them all)."""
    largest = int(SWEEP["overrides"]["total_env_steps"]) // env_steps_per_profile()
    return [2**k for k in range(largest.bit_length()) if 2**k <= largest]


@functools.cache  # resolves a config; the tables ask for the budgets once per row
def env_steps_per_profile() -> int:
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.runner.build import env_steps_per_iteration

    cfg = resolve_config([f"task={TASKS[0]}", "algo=ppo", "device=cpu"], device_type="cpu")
    return env_steps_per_iteration(cfg) * profile_iterations()


def committed() -> list[dict]:
    """The committed runs' rows (finished or failed), each with its evaluations and training rows."""
    if not RUNS_CSV.exists():
        return []
    rows = []
    for row in read_rows(RUNS_CSV):
        run = ROOT / row["run_dir"]
        row["evals"] = read_jsonl(run / "progress_eval.jsonl") if (run / "progress_eval.jsonl").exists() else []
        row["train"] = read_jsonl(run / "progress_train.jsonl") if (run / "progress_train.jsonl").exists() else []
        row["machine"] = run_machine(run) if row["status"] == "ok" else None
        row["final"] = json.loads((run / "eval.json").read_text()) if (run / "eval.json").exists() else None
        rows.append(row)
    return rows


def at_budget(row: dict, multiple: int, key: str) -> float | None:
    """The run's periodic evaluation of ``key`` at ``multiple`` x the profile's budget; 0 at a budget a failed run
    stopped before (it has no policy there); None at one a run still going has not reached."""
    iteration = multiple * profile_iterations() - 1
    found = [e for e in row["evals"] if e["iteration"] == iteration and key in e]
    if found:
        return float(found[0][key])
    return 0.0 if row["status"] == "failed" else None


def return_key(label: str, setting: str) -> str:
    """The evaluation's key: PPO's mean action; a flow's N = 10 or N = 1 from random initial noise."""
    return "eval/return" if label == "ppo" else f"eval/return_N{setting}"


def scores(rows: list[dict], label: str, task: str, multiple: int, setting: str) -> dict[int, float]:
    """seed -> the return at that budget, for the runs that reached it."""
    out = {}
    for row in rows:
        if row["label"] == label and row["task"] == task:
            value = at_budget(row, multiple, return_key(label, setting))
            if value is not None:
                out[int(row["seed"])] = value
    return out


def final_scores(rows: list[dict], label: str, task: str) -> dict[int, float]:
    """seed -> the N = 10 return (PPO: its mean action) of the run's final evaluation (``eval.json``), for the runs
    whose final checkpoint is the largest budget's."""
    last = multiples()[-1] * profile_iterations() - 1
    setting = "mean_action" if label == "ppo" else "N=10"
    return {
        int(r["seed"]): float(r["final"]["results"][setting]["return_mean"])
        for r in rows
        if r["label"] == label and r["task"] == task and r["final"] and r["final"]["checkpoint_iteration"] == last
    }


def window(row: dict, after: int, upto: int) -> list[dict]:
    """The run's training rows from ``after`` to ``upto`` times the profile's budget."""
    bottom, top = after * profile_iterations(), upto * profile_iterations()
    return [r for r in row["train"] if bottom <= r["iteration"] < top]


# ------------------------------------------------------------------------------------------------ tables
def mean_cell(values: dict[int, float]) -> str:
    if not values:
        return "--"
    estimate = mean_estimate(values.values())
    return f"{estimate.text()} ({len(values)})" if estimate.compared else estimate.text()


def returns_table(rows: list[dict], setting: str) -> str:
    labels = [label for label in METHODS if setting == "10" or label != "ppo"]
    header = ["task", "method", *(f"{m}x" for m in multiples())]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    for task in TASKS:
        for label in labels:
            cells = [mean_cell(scores(rows, label, task, m, setting)) for m in multiples()]
            if all(c == "--" for c in cells):
                continue
            lines.append(f"| `{task}` | {METHODS[label]} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def seed_matrices(
    x: dict[str, dict[int, float]], y: dict[str, dict[int, float]]
) -> tuple[np.ndarray, np.ndarray, list[int]] | None:
    """(seeds x tasks) of two methods' task -> seed -> score, over the seeds both have on every task; None if none."""
    seeds = sorted(set.intersection(*(set(x.get(t, {})) & set(y.get(t, {})) for t in TASKS)))
    if not seeds:
        return None
    return (
        np.array([[x[t][s] for t in TASKS] for s in seeds]),
        np.array([[y[t][s] for t in TASKS] for s in seeds]),
        seeds,
    )


def paired(
    rows: list[dict], label: str, multiple: int, other: str = "ppo"
) -> tuple[np.ndarray, np.ndarray, list[int]] | None:
    """``seed_matrices`` of ``label`` and of ``other`` (PPO unless named) at N = 10 at ``multiple``."""
    return seed_matrices(
        {t: scores(rows, label, t, multiple, "10") for t in TASKS},
        {t: scores(rows, other, t, multiple, "10") for t in TASKS},
    )


def refpo_over_fpo(rows: list[dict]) -> dict[int, tuple[Estimate, list[int]]]:
    """budget -> P(a ReFPO run at N = 10 beats an FPO run) over both tasks, and the seeds it pairs."""
    out = {}
    for m in multiples():
        pair = paired(rows, "refpo", m, other="fpo")
        if pair is not None:
            out[m] = (improvement(pair[0], pair[1]), pair[2])
    return out


def leader(p: Estimate, name: str, other: str = "PPO") -> str:
    """Who P(the flow at N = 10 beats ``other``) says leads (``name``: the flow's)."""
    return {1: f"{name} ahead", -1: f"{other} ahead", 0: "not separated"}[p.side]


def gap_text(p: Estimate, name: str) -> str:
    """P(the flow at N = 10 beats PPO), its interval and who it says leads."""
    return f"{p.text(2)}: {leader(p, name)}" if p.compared else p.text(2)


def gap_table(rows: list[dict]) -> tuple[str, dict[str, dict[int, Estimate]]]:
    """P(a run of the flow at N = 10 beats a run of PPO) at each budget over both tasks, and the estimates."""
    header = ["method", "seeds", *(f"{m}x" for m in multiples())]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    found: dict[str, dict[int, Estimate]] = {}
    for label in FLOWS:
        cells, seeds = [], set()
        for m in multiples():
            pair = paired(rows, label, m)
            if pair is None:
                cells.append("--")
                continue
            gap = improvement(pair[0], pair[1])
            found.setdefault(label, {})[m] = gap
            seeds |= set(pair[2])
            cells.append(gap_text(gap, "flow"))
        if label in found:
            lines.append(f"| {METHODS[label]} | {seeds_text(sorted(seeds))} | " + " | ".join(cells) + " |")
    if not found:
        return "(no flow method has a seed in common with PPO on both tasks yet)", found
    return "\n".join(lines), found


SOURCES = {"periodic": "periodic", "final": "final", "averaged": "the two averaged"}


def last_checkpoint(rows: list[dict]) -> dict[str, dict[tuple[str, str], dict[int, float]]]:
    """Each finished run's last checkpoint scored by its periodic evaluation, by its final one (``eval.json``) and by
    the two averaged: source -> (task, label) -> seed -> N = 10 return (PPO: its mean action)."""
    out: dict[str, dict[tuple[str, str], dict[int, float]]] = {source: {} for source in SOURCES}
    for task, label in itertools.product(TASKS, METHODS):
        final = final_scores(rows, label, task)
        if final:
            periodic = {s: v for s, v in scores(rows, label, task, multiples()[-1], "10").items() if s in final}
            out["periodic"][task, label], out["final"][task, label] = periodic, final
            out["averaged"][task, label] = {s: (periodic[s] + final[s]) / 2 for s in final}
    return out


def last_checkpoint_gaps(
    by_source: dict[str, dict[tuple[str, str], dict[int, float]]],
) -> dict[str, tuple[list[int], dict[str, Estimate]]]:
    """Per flow method: the seeds it shares with PPO on both tasks and, from each source, P(its run beats PPO's)."""
    out = {}
    for label in FLOWS:
        per_source = {
            source: seed_matrices(
                {t: found[t, label] for t in TASKS if (t, label) in found},
                {t: found[t, "ppo"] for t in TASKS if (t, "ppo") in found},
            )
            for source, found in by_source.items()
        }
        if per_source["final"] is not None:
            out[label] = (
                per_source["final"][2],
                {source: improvement(m[0], m[1]) for source, m in per_source.items() if m is not None},
            )
    return out


def two_evaluations(rows: list[dict]) -> tuple[str, str]:
    """The two evaluations' means over seeds side by side with the largest difference of one run, and the gap to PPO
    at the largest budget from each evaluation and from their average."""
    by_source = last_checkpoint(rows)
    if not by_source["final"]:
        return "(no committed run has its final evaluation at the largest budget yet)", ""
    header = ["task", "method", "seeds", "periodic", "final (`eval.json`)", "largest difference of a run"]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    for (task, label), final in by_source["final"].items():
        periodic = by_source["periodic"][task, label]
        differences = [abs(periodic[s] - final[s]) for s in final]
        lines.append(
            f"| `{task}` | {METHODS[label]} | {seeds_text(sorted(final))} | {mean_cell(periodic)} | "
            f"{mean_cell(final)} | {max(differences):.0f} |"
        )
    gaps = last_checkpoint_gaps(by_source)
    if not gaps:
        return "\n".join(lines), "(no flow method shares a seed with PPO on both tasks)"
    gap_lines = [
        "| method | seeds | " + " | ".join(SOURCES.values()) + " |",
        "|" + "|".join("---" for _ in range(2 + len(SOURCES))) + "|",
    ]
    for label, (seeds, by) in gaps.items():
        cells = [gap_text(by[source], "flow") for source in SOURCES]
        gap_lines.append(f"| {METHODS[label]} | {seeds_text(seeds)} | " + " | ".join(cells) + " |")
    return "\n".join(lines), "\n".join(gap_lines)


def eval_episodes(rows: list[dict]) -> str:
    """How many episodes the periodic and the final evaluations each ran (one env an episode)."""
    periodic = int(SWEEP["overrides"]["eval"]["interval_num_envs"])
    final = sorted({int(r["final"]["eval_envs"]) for r in rows if r["final"]})
    if final == [periodic]:
        return f"{periodic} episodes each"
    return f"{periodic} episodes and {and_list(str(n) for n in final)} episodes"


def health_table(rows: list[dict]) -> str:
    """Per flow method, each window from the table's previous budget (the start, for the first) to the next: the
    largest ratio, the mean explosion rate and the straightness error at the window's end, means over seeds."""
    header = ["task", "method", "statistic", *(f"{m}x" for m in multiples())]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    stats = (
        ("largest ratio", lambda w: max(r.get("Flow/ratio_max", np.nan) for r in w)),
        ("explosion rate", lambda w: float(np.mean([r.get("Flow/explosion_rate", np.nan) for r in w]))),
        ("straightness error", lambda w: w[-1].get("Flow/straightness_error", np.nan)),
    )
    for task in TASKS:
        for label in FLOWS:
            runs = [r for r in rows if r["label"] == label and r["task"] == task]
            if not runs:
                continue
            for name, fn in stats:
                cells = []
                for after, upto in itertools.pairwise([0, *multiples()]):
                    values = [fn(w) for w in (window(r, after, upto) for r in runs) if w]
                    cells.append(f"{np.mean(values):.3g}" if values else "--")
                lines.append(f"| `{task}` | {METHODS[label]} | {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def failures(rows: list[dict]) -> str:
    """The runs that stopped on a non-finite loss: where (the iteration whose update was refused)."""
    failed = [r for r in rows if r["status"] == "failed"]
    if not failed:
        return "No committed run has failed."
    per_iteration = env_steps_per_profile() // profile_iterations()
    parts = []
    for r in failed:
        stopped = max((t["iteration"] for t in r["train"]), default=-1) + 1
        steps = stopped * per_iteration
        parts.append(
            f"{r['task'].removeprefix('dmc_')}/{r['label']}/seed{r['seed']} in iteration {stopped}, after {steps:,} "
            f"env steps ({steps / env_steps_per_profile():.1f}x the profile's budget)"
        )
    return (
        "Stopped on a non-finite loss (the update refused before it was applied; `refpo report`'s status failed): "
        + and_list(parts)
        + "."
    )


def health_verdicts(rows: list[dict]) -> str:
    """How many runs each verdict of the rule has, naming the runs of every verdict but healthy."""
    by_verdict: dict[str, list[str]] = {}
    for r in rows:
        if r.get("health"):
            by_verdict.setdefault(r["health"], []).append(
                f"{r['task'].removeprefix('dmc_')}/{r['label']}/seed{r['seed']}"
            )
    if not by_verdict:
        return "no run has a verdict yet"
    return and_list(
        f"{verdict} in {len(runs)} run{'s' if len(runs) != 1 else ''}"
        + ("" if verdict == "healthy" else f" ({and_list(runs)})")
        for verdict, runs in sorted(by_verdict.items())
    )


# ------------------------------------------------------------------------------------------------ the answer
def movement(g0: Estimate, g1: Estimate) -> str:
    """How the probability of improvement moved between two budgets, in words of who leads (one half: level)."""
    p0, p1 = g0.point, g1.point

    def side(p: float) -> str:
        return "level" if p == 0.5 else "PPO" if p < 0.5 else "the flow"

    s0, s1 = side(p0), side(p1)
    if s0 == "level":
        moved = "they stay level" if s1 == "level" else f"from level, {s1} moves ahead"
    elif s1 == "level":
        moved = f"{s0}'s lead closes to level"
    elif s0 != s1:
        moved = f"{s0}'s lead turns into {s1}'s"
    elif p1 == p0:
        moved = f"{s0}'s lead holds"
    else:
        moved = f"{s0}'s lead {'narrows' if abs(p1 - 0.5) < abs(p0 - 0.5) else 'widens'}"
    if not (g0.compared and g1.compared):
        return f"by the point estimates {moved}; one seed separates nothing"
    if g0.high >= g1.low and g1.high >= g0.low:
        return f"by the point estimates {moved}; the two intervals overlap, so the seeds do not show the change"
    return f"by the point estimates {moved}, and the two intervals do not overlap"


def answer(found: dict[str, dict[int, Estimate]]) -> str:
    """Per flow method: the probability of beating PPO at the smallest and the largest budget both reached."""
    if not found:
        return (
            "Not yet: the comparison pairs seeds over both tasks, and no flow method and PPO share a committed seed on "
            "both; the page answers when they do."
        )
    lines = []
    for label, by_budget in found.items():
        first, last = min(by_budget), max(by_budget)
        g0, g1 = by_budget[first], by_budget[last]
        if first == last:
            lines.append(f"- **{METHODS[label]}**: only {first}x reached so far: {gap_text(g0, 'it')}.")
            continue
        lines.append(
            f"- **{METHODS[label]}** against PPO: P(improvement) "
            + ", ".join(
                f"{g.text(2)} at {m}x" + (f" ({leader(g, METHODS[label])})" if g.compared else "")
                for m, g in ((first, g0), (last, g1))
            )
            + f"; {movement(g0, g1)}."
        )
    return "\n".join(lines)


def degradation(rows: list[dict]) -> str:
    """The paper's Figure 3 question (there on point_mass; here on every task): does FPO fall from its best budget
    where ReFPO holds? The mean over seeds and each run's own best against its last budget (a mean can hide one run
    falling while another climbs)."""
    lines = []
    for task, label in itertools.product(TASKS, ("fpo", "refpo")):
        means = {m: scores(rows, label, task, m, "10") for m in multiples()}
        means = {m: v for m, v in means.items() if v}
        if len(means) < 2:
            continue
        first, last = min(means), max(means)
        runs = {int(r["seed"]): r for r in rows if (r["task"], r["label"]) == (task, label)}
        by_seed = []
        for seed in sorted(means[last]):
            path = {m: means[m][seed] for m in means if seed in means[m]}
            best = max(path, key=lambda m: path[m])
            text = (
                f"seed {seed} best at {last}x, {path[last]:.0f}"
                if best == last
                else f"seed {seed} best at {best}x, {path[best]:.0f}, then {path[last]:.0f} at {last}x"
            )
            if runs[seed]["status"] == "failed":
                text += " (stopped on a non-finite loss before it, counted as zero)"
            by_seed.append(text)
        lines.append(
            f"- {METHODS[label]} on `{task}` (N = 10): the mean {mean_cell(means[first])} at {first}x, "
            f"{mean_cell(means[last])} at {last}x; {'; '.join(by_seed)}."
        )
    gaps = refpo_over_fpo(rows)
    if gaps:
        seeds = sorted(set().union(*(set(g[1]) for g in gaps.values())))
        lines.append(
            f"- P(a {METHODS['refpo']} run at N = 10 scores above an FPO run), over both tasks, seeds "
            f"{seeds_text(seeds)}: "
            + "; ".join(f"{g.text(2)} at {m}x ({leader(g, METHODS['refpo'], 'FPO')})" for m, (g, _) in gaps.items())
            + "."
        )
    lines += [line for task in TASKS if (line := straightness(rows, task))]
    return "\n".join(lines) if lines else "- Not enough committed runs yet."


def final_straightness(rows: list[dict], task: str) -> dict[str, list[float]]:
    """flow label -> the straightness error at each of its runs' last logged iteration on ``task``."""
    return {
        label: [r["train"][-1]["Flow/straightness_error"] for r in rows if (r["task"], r["label"]) == (task, label)]
        for label in FLOWS
    }


def straightness(rows: list[dict], task: str) -> str | None:
    """The flows' straightness error at each run's last logged iteration (a failed run: the last before its stop),
    and P(an FPO run's above a ReFPO run's): does FPO's flow bend where ReFPO's stays straight?"""
    last = final_straightness(rows, task)
    if not last["fpo"] or not last["refpo"]:
        return None
    ranges = and_list(f"{METHODS[label]} {value_range(v, '.3g')}" for label, v in last.items() if v)
    p = improvement_of(last["fpo"], last["refpo"])
    return (
        f"- The straightness error on `{task}` at each run's last logged iteration (a stopped run's: before its stop): "
        f"{ranges}. P(an FPO run's error above a {METHODS['refpo']} run's) {p.text(2)}."
    )


# ------------------------------------------------------------------------------------------------ figure
def curves(rows: list[dict], path: Path) -> None:
    """N = 10 (PPO: its mean action) at every evaluation, the mean over seeds and a band from lowest to highest."""
    fig, axes = plt.subplots(1, len(TASKS), figsize=(5.5 * len(TASKS), 4))
    for ax, task in zip(axes, TASKS, strict=True):
        for label, name in METHODS.items():
            runs = [r for r in rows if r["label"] == label and r["task"] == task]
            if not runs:
                continue
            key = return_key(label, "10")
            series = [[(e["env_steps"], e[key]) for e in r["evals"] if key in e] for r in runs]
            evaluations = [k * env_steps_per_profile() for k in range(1, multiples()[-1] + 1)]
            series = [  # a failed run scores 0 at the evaluations it did not reach
                s + [(x, 0.0) for x in evaluations[len(s) :]] if run["status"] == "failed" else s
                for run, s in zip(runs, series, strict=True)
            ]
            length = min(len(s) for s in series)
            steps = np.array([x for x, _ in series[0][:length]])
            values = np.array([[y for _, y in s[:length]] for s in series])
            ax.plot(steps, values.mean(axis=0), color=COLOURS[label], label=f"{name} ({len(runs)})")
            ax.fill_between(steps, values.min(axis=0), values.max(axis=0), color=COLOURS[label], alpha=0.15)
        ax.set_title(task)
        ax.set_xlabel("env steps")
        ax.set_ylabel("return (N = 10; PPO: mean action)")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="center right")
        else:
            ax.text(0.5, 0.5, "no run committed yet", ha="center", transform=ax.transAxes, color="grey")
    save_figure(fig, path, dpi=110, bbox_inches="tight")
    plt.close(fig)


# ------------------------------------------------------------------------------------------------ the page
def committed_text(rows: list[dict]) -> str:
    """How much of the grid is committed, and what is still to run."""
    total = len(TASKS) * len(METHODS) * len(SWEEP["seeds"])
    if len(rows) == total:
        return f"All {total} runs of the grid are committed"
    verb = "is" if len(rows) == 1 else "are"
    return f"{len(rows)} of the grid's {total} runs {verb} committed; still to run: {still_to_run(rows)}"


def still_to_run(rows: list[dict]) -> str:
    have = {(r["task"], r["label"], int(r["seed"])) for r in rows}
    missing = []
    for task in TASKS:
        for label in METHODS:
            seeds = [s for s in SWEEP["seeds"] if (task, label, s) not in have]
            if seeds:
                missing.append(
                    f"{task.removeprefix('dmc_')}/{label} (seed{'s' * (len(seeds) > 1)} {seeds_text(seeds)})"
                )
    return and_list(missing) if missing else "none"


def run_minutes(rows: list[dict]) -> str:
    """The finished runs' wall times, by the machine that trained them."""
    by_machine: dict[str, list[float]] = {}
    for r in rows:
        if r.get("minutes"):
            by_machine.setdefault(machine_text(r["machine"], UNRECORDED_MACHINE), []).append(float(r["minutes"]))
    if not by_machine:
        return "No committed run has its wall time yet"
    return "The committed runs took " + "; ".join(
        f"{value_range(minutes, '.0f')} min{' each' * (len(minutes) > 1)} on {where}"
        for where, minutes in by_machine.items()
    )


def values() -> dict[str, object]:
    rows = committed()
    gap, found = gap_table(rows)
    twice, twice_gaps = two_evaluations(rows)
    if rows:
        curves(rows, HERE / "trend_curves.png")
    return {
        "committed": committed_text(rows),
        "run_minutes": run_minutes(rows),
        "budget": f"{env_steps_per_profile():,} env steps ({profile_iterations()} iterations)",
        "largest": f"{multiples()[-1]}x",
        "seeds": seeds_text(SWEEP["seeds"]),
        "returns_n10": returns_table(rows, "10"),
        "returns_n1": returns_table(rows, "1"),
        "gap_table": gap,
        "answer": answer(found),
        "degradation": degradation(rows),
        "two_evaluations": twice,
        "two_evaluations_gap": twice_gaps,
        "eval_episodes": eval_episodes(rows),
        "health_table": health_table(rows),
        "health_verdicts": health_verdicts(rows),
        "failures": failures(rows),
        "figure": "![Returns through training to 8x the budget](trend_curves.png)"
        if rows
        else "(no run committed yet)",
    }


def add_runs(sweep_dir: Path) -> None:
    """Append the sweep's finished runs to runs.csv, copying their small files under runs/."""
    added = append_runs(sweep_dir, RUNS_CSV, RUNS_DIR, ROOT)
    print(f"{RUNS_CSV.relative_to(ROOT)}: {added} run(s) added from {sweep_dir}")


def main() -> None:
    page_main(__doc__.splitlines()[0], HERE / "README.template.md", values, add_runs)


if __name__ == "__main__":
    main()
