"""The budget runs (budget/): each run's periodic returns read back, the curves' table at the marks of the profile's
budget, the figure (budget_curves.png) and each run's fall from its peak."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
from study_files import BUDGET, HERE, NAMES, big_text, read_yaml, steps_text

from refpo_warp.studies.reports.committed_runs import read_jsonl, seeds_text


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
        rows = read_jsonl(path)
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

    cfg = read_yaml(next(BUDGET.glob("*/*/seed*/config.yaml")))
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
