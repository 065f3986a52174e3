"""A sweep's committed runs on the two-way task (fine-tuned from clones, or from scratch): their rows, final
evaluations and curves, the numbers a page shows of each (success, each way's share, the rarer way among the passes,
return), and the tables and the figure both pages draw from them."""

from __future__ import annotations

import argparse
import functools
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import append_runs, read_jsonl, read_rows, seeds_text
from refpo_warp.studies.reports.intervals import Estimate, improvement_of, mean_estimate
from refpo_warp.studies.reports.results_page import main_args
from refpo_warp.utils.atomic_files import save_figure

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
TASK = "dmc_point_mass_wall"
SUCCESS_FLOOR = 0.5  # a run below this success has lost the task
MINORITY_FLOOR = 0.1  # a run whose rarer way is below this share of its passes keeps one way
MACHINE = "a 2-core AMD EPYC shared with other work"  # where the sweeps ran (their runs record no machine)
COLOURS = {"refpo": "#1f77b4", "refpo_adaptive": "#17becf", "fpo": "#ff7f0e", "fpo_pp": "#9467bd", "ppo": "#2ca02c"}


# ------------------------------------------------------------------------------------------------ one run's numbers
def setting_of(label: str, n: int) -> str | None:
    """The eval.json setting of a method at N (PPO: its mean action, at N = 10 only)."""
    if label == "ppo":
        return "mean_action" if n == 10 else None
    return f"N={n}"


def numbers(result: dict) -> dict[str, float]:
    """One evaluation setting's success, each way's share of the episodes, the rarer way's share of the passes and
    the return (a failed run: zeros)."""
    if not result:
        return {"success": 0.0, "left": 0.0, "right": 0.0, "rarer": 0.0, "return": 0.0, "episodes": 0}
    left, right = result["went_left_mean"], result["went_right_mean"]
    return {
        "success": result["success_mean"],
        "left": left,
        "right": right,
        "rarer": min(left, right) / (left + right) if left + right else 0.0,
        "return": result["return_mean"],
        "episodes": result["episodes"],
    }


def outcome(n: dict[str, float]) -> str:
    if n["success"] < SUCCESS_FLOOR:
        return "lost"
    return "one way" if n["rarer"] < MINORITY_FLOOR else "both ways"


def percent(e: Estimate, digits: int = 0) -> str:
    return f"{100 * e.point:.{digits}f} % [{100 * e.low:.{digits}f}, {100 * e.high:.{digits}f}]"


# ------------------------------------------------------------------------------------------------ a sweep's runs
@dataclass(frozen=True)
class TwoWayRuns:
    """The committed runs of one sweep on the task: its sweep file and the ``runs.csv`` its runs are appended to
    (``refpo report``'s rows; each row's ``run_dir`` holds the run's small files)."""

    sweep: Path
    runs_csv: Path

    @property
    def runs_dir(self) -> Path:
        return self.runs_csv.parent / "runs"

    def methods(self) -> list[dict]:
        return load_yaml(self.sweep)["methods"]

    @functools.cached_property
    def rows(self) -> tuple[dict, ...]:
        return tuple(read_rows(self.runs_csv)) if self.runs_csv.exists() else ()

    def run_results(self, label: str) -> dict[int, dict]:
        """seed -> the run's eval.json results (a failed run: {})."""
        out: dict[int, dict] = {}
        for row in self.rows:
            if row["task"] != TASK or row["label"] != label:
                continue
            if row["status"] == "failed":
                out[int(row["seed"])] = {}
            elif row["status"] == "ok":
                out[int(row["seed"])] = json.loads((ROOT / row["run_dir"] / "eval.json").read_text())["results"]
        return out

    def numbers_at(self, label: str, n: int) -> dict[int, dict[str, float]]:
        """seed -> the run's numbers at N = n (PPO: its mean action); a failed run, or a setting the method has
        not (PPO at N = 1), reads as zeros."""
        setting = setting_of(label, n)
        return {
            seed: numbers(r.get(setting, {}) if r and setting else {}) for seed, r in self.run_results(label).items()
        }

    def folders(self, label: str) -> list[Path]:
        return [ROOT / r["run_dir"] for r in self.rows if r["label"] == label and r["status"] == "ok"]

    def curves(self, label: str) -> dict[int, list[dict]]:
        out = {}
        for row in self.rows:
            if row["task"] == TASK and row["label"] == label and row["status"] == "ok":
                path = ROOT / row["run_dir"] / "progress_eval.jsonl"
                out[int(row["seed"])] = read_jsonl(path)
        return out

    def first_config(self) -> dict:
        row = next(r for r in self.rows if r["status"] == "ok")
        return load_yaml(ROOT / row["run_dir"] / "config.yaml")

    def seeds(self) -> list[int]:
        return sorted({s for m in self.methods() for s in self.run_results(m["label"])})


def page_arguments(doc: str, runs: TwoWayRuns) -> argparse.Namespace:
    """A page script's command line (``--check``, ``--add-runs DIR ...``), the sweeps' new runs appended first."""
    parser = main_args(doc.splitlines()[0])
    parser.add_argument("--add-runs", nargs="*", default=[], type=Path, help="sweep dirs whose finished runs to add")
    args = parser.parse_args()
    for sweep_dir in args.add_runs:
        added = append_runs(sweep_dir, runs.runs_csv, runs.runs_dir, ROOT)
        print(f"{runs.runs_csv.relative_to(ROOT)}: {added} run(s) added from {sweep_dir}")
    return args


# ------------------------------------------------------------------------------------------------ tables
def method_table(runs: TwoWayRuns, n: int, below: Callable[[str, str], str] | None = None) -> str:
    """Each method's cells at N = n over its seeds; ``below(label, setting)`` adds a row under each method."""
    head = (
        "| method | seeds | success [95 %] | left [95 %] | right [95 %] | rarer way among the passes [95 %] | "
        "return [95 %] | runs: both ways / one way / lost |"
    )
    lines = [head, "|---|---|---|---|---|---|---|---|"]
    for method in runs.methods():
        label = method["label"]
        setting = setting_of(label, n)
        results = runs.run_results(label)
        if setting is None or not results:
            continue
        per = list(runs.numbers_at(label, n).values())
        kinds = [outcome(p) for p in per]
        cells = [percent(mean_estimate([p[k] for p in per])) for k in ("success", "left", "right", "rarer")]
        ret = mean_estimate([p["return"] for p in per]).text()
        counts = " / ".join(str(kinds.count(k)) for k in ("both ways", "one way", "lost"))
        lines.append(f"| {method['name']} | {seeds_text(results)} | {' | '.join(cells)} | {ret} | {counts} |")
        if below is not None:
            lines.append(below(label, setting))
    return "\n".join(lines)


def per_run_table(runs: TwoWayRuns) -> str:
    lines = ["| method | seed | N = 10 (PPO: mean action): success, left, right | N = 1: success, left, right |"]
    lines.append("|---|---|---|---|")
    for method in runs.methods():
        label = method["label"]
        by_n = {n: runs.numbers_at(label, n) for n in (10, 1)}
        for seed in sorted(by_n[10]):
            cells = []
            for n in (10, 1):
                if setting_of(label, n) is None:
                    cells.append("--")
                    continue
                p = by_n[n][seed]
                text = f"{100 * p['success']:.0f} %, {100 * p['left']:.0f} %, {100 * p['right']:.0f} %"
                cells.append(text + f" ({outcome(p)})" if n == 10 else text)
            lines.append(f"| {method['name']} | {seed} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


def comparison_table(runs: TwoWayRuns) -> str:
    """Each flow method's success against PPO's, and its rarer way's share against PPO's, by P(improvement)."""
    ppo = runs.run_results("ppo")
    lines = ["| comparison | statistic | P(improvement) [95 %] | what it says |", "|---|---|---|---|"]
    for method in runs.methods():
        label = method["label"]
        results = runs.run_results(label)
        if label == "ppo" or not results or not ppo:
            continue
        name = method["name"].split(" from")[0]
        for key, statistic in (("success", "success"), ("rarer", "rarer way among the passes")):
            x = [p[key] for p in runs.numbers_at(label, 10).values()]
            y = [p[key] for p in runs.numbers_at("ppo", 10).values()]
            p = improvement_of(x, y)
            if p.side > 0:
                says = f"{name} higher: the interval lies above 0.5"
            elif p.side < 0:
                says = "PPO higher: the interval lies below 0.5"
            else:
                says = "the interval holds 0.5: these seeds do not separate them"
            lines.append(f"| {name} over PPO | {statistic} (N = 10) | {p.text(2)} | {says} |")
    return "\n".join(lines)


def summary(runs: TwoWayRuns) -> str:
    """One line per method: its runs' outcomes at N = 10 (PPO: its mean action)."""
    lines = []
    for method in runs.methods():
        label = method["label"]
        results = runs.run_results(label)
        if not results:
            continue
        per = list(runs.numbers_at(label, 10).values())
        kinds = [outcome(p) for p in per]
        lines.append(
            f"- **{method['name']}**: of its {len(per)} runs, {kinds.count('both ways')} kept both ways, "
            f"{kinds.count('one way')} one way and {kinds.count('lost')} lost the task; success "
            f"{percent(mean_estimate([p['success'] for p in per]))}."
        )
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------ the figure
def _over_seeds(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mean, lowest and highest over seeds (rows) of each evaluation (column), NaN where no seed has a value (a
    left share where no run passed the wall): a gap in the curve."""
    out = np.full((3, values.shape[1]), np.nan)
    some = np.isfinite(values).any(axis=0)
    kept = values[:, some]
    out[:, some] = np.nanmean(kept, axis=0), np.nanmin(kept, axis=0), np.nanmax(kept, axis=0)
    return out[0], out[1], out[2]


def curves_figure(runs: TwoWayRuns, path: Path, title: str, xlabel: str, mark: tuple[int, str] | None = None) -> None:
    """Success and the left share of the passes through training (N = 10; PPO: its mean action), the mean over
    seeds with a band from the lowest to the highest; ``mark``: (env steps, label) of a dashed line."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for method in runs.methods():
        label = method["label"]
        suffix = "" if label == "ppo" else "_N10"
        curves = runs.curves(label)
        if not curves:
            continue
        steps = np.array([r["env_steps"] for r in next(iter(curves.values()))])
        length = min(len(rows) for rows in curves.values())  # runs still going are drawn as far as all have gone
        steps = steps[:length]
        success = np.array([[r[f"eval/success{suffix}"] for r in rows[:length]] for rows in curves.values()])
        left = np.array([[r[f"eval/went_left{suffix}"] for r in rows[:length]] for rows in curves.values()])
        right = np.array([[r[f"eval/went_right{suffix}"] for r in rows[:length]] for rows in curves.values()])
        passes = left + right
        share = np.divide(left, passes, out=np.full_like(left, np.nan), where=passes > 0)
        for ax, values in ((axes[0], success), (axes[1], share)):
            mean, low, high = _over_seeds(values)
            ax.plot(steps, mean, color=COLOURS[label], label=method["name"])
            ax.fill_between(steps, low, high, color=COLOURS[label], alpha=0.15)
    if mark is not None:
        for ax in axes:
            ax.axvline(mark[0], color="grey", lw=0.8, ls="--")
        axes[0].text(mark[0], 0.5, f" {mark[1]}", color="grey", fontsize=7)
    axes[0].set_ylabel("success (N = 10; PPO: mean action)")
    axes[1].set_ylabel("left share of the passes")
    axes[1].axhline(0.5, color="k", lw=0.5, ls=":")
    for ax in axes:
        ax.set_xlabel(xlabel)
        ax.set_ylim(-0.02, 1.02)
    axes[0].legend(fontsize=7, loc="lower right")
    fig.suptitle(title)
    save_figure(fig, path, dpi=110, bbox_inches="tight")
    plt.close(fig)
