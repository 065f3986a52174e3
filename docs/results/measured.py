#!/usr/bin/env python
"""The README's learning results, written from the committed data files: python docs/results/measured.py

Rewrites the table between the markers in README.md ("Measured: learning") from
- docs/results/learning_checks/records/gridworld_refpo.jsonl: ReFPO on GridWorld, the learning check's runs;
- docs/results/*/per_task.csv of the DMC sweeps below (`refpo report`'s output): the CPU profiles' returns per task,
  mean ± population std over seeds 1-3 (the tuning study's chosen values: fresh seeds 11-13);
- docs/results/finetuning/: the GridWorld clones and fine-tuned runs (eval.json each) and the DMC fine-tuning runs
  from a weaker demonstrator (dmc/<task>/<method>/seed<k>/eval.json).
Each row names its data file; nothing here is typed in by hand.
"""

from __future__ import annotations

import csv
import json
import statistics
from pathlib import Path

RESULTS = Path(__file__).resolve().parent
README = RESULTS.parents[1] / "README.md"
BEGIN, END = "<!-- measured: begin (python docs/results/measured.py) -->", "<!-- measured: end -->"
SWEEPS = [  # (per-task CSV, methods in the order shown, seeds)
    ("cpu_dmc/per_task.csv", ["ppo", "fpo", "refpo"], "1-3"),
    ("fpo_pp/report/per_task.csv", ["fpo_pp", "refpo_pp"], "1-3"),
    ("one_step/search/report/per_task.csv", ["onestep_c03"], "1-3"),
    # each method at its values chosen by the equal-budget tuning study (tuning/README.md: intervals, IQM)
    ("tuning/fresh/per_task.csv", ["ppo", "refpo", "refpo_onestep", "fpo_pp"], "11-13"),
]
TASKS = {
    "dmc_cartpole_balance": "cartpole_balance (450k env steps)",
    "dmc_point_mass": "point_mass (1M)",
    "dmc_reacher_easy": "reacher_easy (1M)",
}


def number(text: str) -> float | None:
    return float(text) if text not in ("", None) else None


def cell(mean: float | None, std: float | None) -> str:
    if mean is None:
        return "--"
    return f"{mean:.0f}" if std is None else f"{mean:.0f} ± {std:.0f}"


def gridworld_row() -> str | None:
    path = RESULTS / "learning_checks" / "records" / "gridworld_refpo.jsonl"
    if not path.exists():
        return None
    runs = [r for r in map(json.loads, path.read_text().splitlines()) if not r["null"] and r["threads"] == 1]
    final = [r["final"] for r in runs]
    success = [min(f[s]["success_rate"] for s in ("N=1", "N=10")) for f in final]
    length = {s: statistics.fmean(f[s]["length_mean"] for f in final) for s in ("N=1", "N=10")}
    share = [min(f[s]["top_share"], f[s]["bottom_share"]) for f in final for s in ("N=1", "N=10")]
    seeds = ", ".join(str(r["seed"]) for r in sorted(runs, key=lambda r: r["seed"]))
    return (
        f"| ReFPO on GridWorld, the paper's 260k env steps, seeds {seeds} (`{path.relative_to(README.parent)}`) | "
        f"success ≥ {min(success):.3f} at N = 1 and 10; episode length {length['N=1']:.1f} / {length['N=10']:.1f} "
        f"(N = 1 / 10); the smaller goal band's share of successes "
        f"{min(share):.2f}-{max(share):.2f} |"
    )


def sweep_rows(relative: str, labels: list[str] | None, seeds: str) -> list[str]:
    path = RESULTS / relative
    if not path.exists():
        return []
    rows = list(csv.DictReader(path.open()))
    runs_csv = path.with_name("runs.csv")
    failed = (
        [(r["task"], r["label"]) for r in csv.DictReader(runs_csv.open()) if r["status"] == "failed"]
        if runs_csv.exists()
        else []
    )
    labels = labels or list(dict.fromkeys(r["label"] for r in rows))
    out = []
    for task, title in TASKS.items():
        cells = []
        for label in labels:
            row = next((r for r in rows if r["task"] == task and r["label"] == label), None)
            if row is None or row["runs_finished"] == "0":
                continue
            single = row["runs_finished"] == "1"  # no spread to show
            multi = cell(number(row["return_multi_mean"]), None if single else number(row["return_multi_std"]))
            one = row.get("return_1_mean") and cell(
                number(row["return_1_mean"]), None if single else number(row["return_1_std"])
            )
            partial = row["runs_finished"] != row["runs_total"]
            cells.append(
                f"{row['method']} {multi}"
                + (f" / {one}" if one else "")
                + (f" ({row['runs_finished']} of {row['runs_total']} seeds" if partial else "")
                + (f"; {failed.count((task, label))} failed)" if partial and (task, label) in failed else "")
                + (")" if partial and (task, label) not in failed else "")
            )
        if cells:
            out.append(
                f"| {title}, 10-step / 1-step return, seeds {seeds} (`{path.relative_to(README.parent)}`) | "
                + "; ".join(cells)
                + " |"
            )
    return out


def _eval(path: Path) -> dict | None:
    return json.loads(path.read_text())["results"] if path.exists() else None


def finetuning_gridworld_row() -> str | None:
    """Success and the bands' shares of the clones and the fine-tuned flows on GridWorld's two-mode demonstrations."""
    folder = RESULTS / "finetuning" / "gridworld"
    runs = {
        name: _eval(folder / name / "eval.json")
        for name in ("clone_flow", "clone_gauss", "refpo_from_flow", "fpo_from_flow", "ppo_from_gauss")
    }
    if any(r is None for r in runs.values()):
        return None

    def flow(r: dict) -> str:
        return " / ".join(f"{r[s]['success_rate']:.2f} ({r[s]['top_share']:.2f} top)" for s in ("N=10", "N=1"))

    gauss, ppo = runs["clone_gauss"]["mean_action"], runs["ppo_from_gauss"]["mean_action"]
    return (
        f"| GridWorld from scripted two-mode demonstrations, seed 1 (`{folder.relative_to(README.parent)}`), "
        f"success at N = 10 / N = 1 (the top band's share) | flow clone {flow(runs['clone_flow'])}; Gaussian clone "
        f"{gauss['success_rate']:.2f}; fine-tuned: ReFPO {flow(runs['refpo_from_flow'])}, FPO "
        f"{flow(runs['fpo_from_flow'])}, PPO from its clone {ppo['success_rate']:.2f} |"
    )


def _return_range(folder: Path) -> str | None:
    """'lo-hi (lo-hi at N = 1)' of the final returns of ``folder``'s seed runs, or None if it has none."""
    runs = [_eval(p) for p in sorted(folder.glob("seed*/eval.json"))]
    if not runs:
        return None
    multi = [r.get("N=10", r.get("mean_action", {})).get("return_mean") for r in runs]
    one = [r["N=1"]["return_mean"] for r in runs if "N=1" in r]
    return f"{min(multi):.0f}-{max(multi):.0f}" + (f" ({min(one):.0f}-{max(one):.0f} at N = 1)" if one else "")


def finetuning_dmc_rows() -> list[str]:
    """Per task: each method's final N = 10 (N = 1) return over its seeds, fine-tuned and from scratch at the same
    env steps."""
    out = []
    scratch, updated = RESULTS / "finetuning" / "scratch", RESULTS / "finetuning" / "normalizers_updated"
    for task_dir in sorted((RESULTS / "finetuning" / "dmc").glob("dmc_*")):
        cells = []
        for method in ("ppo", "refpo_onestep", "refpo"):
            tuned = _return_range(task_dir / method)
            others = [
                (what, _return_range(folder / task_dir.name / method))
                for what, folder in (("normalisers updated", updated), ("from scratch", scratch))
            ]
            if tuned:
                cells.append(f"{method} {tuned}" + "".join(f", {what} {got}" for what, got in others if got))
        if cells:
            counts = {len(list((task_dir / m).glob("seed*/eval.json"))) for m in ("ppo", "refpo_onestep", "refpo")}
            seeds = "-".join(str(n) for n in sorted(counts - {0}))
            out.append(
                f"| {task_dir.name.removeprefix('dmc_')} fine-tuned from a half-return PPO's demonstrations, "
                f"half the CPU profile's env steps, {seeds} seeds (`{task_dir.relative_to(README.parent)}`; with the "
                f"normalisers updated from the rollouts: `{updated.relative_to(README.parent)}`; from scratch at the "
                f"same env steps: `{scratch.relative_to(README.parent)}`), final return range | "
                + "; ".join(cells)
                + " |"
            )
    return out


def table() -> str:
    rows = [r for r in [gridworld_row()] if r]
    for relative, labels, seeds in SWEEPS:
        rows += sweep_rows(relative, labels, seeds)
    rows += [r for r in [finetuning_gridworld_row()] if r] + finetuning_dmc_rows()
    return "\n".join([BEGIN, "| Learning result (data file) | Measured |", "|---|---|", *rows, END])


def main() -> None:
    text = README.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        raise SystemExit(f"{README}: no '{BEGIN}' ... '{END}' markers")
    head, rest = text.split(BEGIN, 1)
    README.write_text(head + table() + rest.split(END, 1)[1], encoding="utf-8")
    print(f"{README}: measured table written")


if __name__ == "__main__":
    main()
