"""The DMC fine-tuning runs as the page reads them: each seed run's final returns and periodic curve, the groups of
runs per task and method, where they came from (tables.py --dmc copies them), and PPO's from-scratch targets."""

from __future__ import annotations

import csv
import functools
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from study_layout import DMC_KEPT, DMC_METHODS, DMC_SOURCES, DMC_TASKS, FALL, FILES, FROM_SCRATCH, read_json


# ------------------------------------------------------------------------------------------------ DMC: the runs
@dataclass(frozen=True)
class Run:
    path: Path
    seed: int
    n10: float  # the final evaluation: N = 10, or PPO's mean action
    n1: float | None
    rows: tuple
    train_time_s: float

    @property
    def curve(self) -> tuple[list[float], list[float]]:
        """(env steps, return) of the periodic evaluations: N = 10 for a flow, the mean action for PPO."""
        key = "eval/return_N10" if any("eval/return_N10" in r for r in self.rows) else "eval/return"
        points = [(r["env_steps"], r[key]) for r in self.rows if key in r]
        return [p[0] for p in points], [p[1] for p in points]

    @property
    def peak(self) -> tuple[float, int]:
        """(the highest periodic N = 10 return, its iteration)."""
        key = "eval/return_N10" if any("eval/return_N10" in r for r in self.rows) else "eval/return"
        return max((r[key], r["iteration"]) for r in self.rows if key in r)

    @property
    def last_periodic(self) -> float:
        return self.curve[1][-1]

    @property
    def fell(self) -> bool:
        return self.last_periodic < FALL * self.peak[0]

    def at(self, key: str, iteration: int | None = None) -> float:
        """A progress scalar at ``iteration`` (the last row when None)."""
        row = self.rows[-1] if iteration is None else next(r for r in self.rows if r["iteration"] == iteration)
        return row[key]


def final_returns(path: Path) -> tuple[float, float | None]:
    """(N = 10 or the Gaussian's mean-action return, N = 1 return or None) of an eval.json."""
    results = read_json(path)["results"]
    if "mean_action" in results:
        return results["mean_action"]["return_mean"], None
    return results["N=10"]["return_mean"], results["N=1"]["return_mean"]


@functools.cache
def load_run(path: Path) -> Run:
    from refpo_warp.runner.progress import read_rows

    evaluation = read_json(path / "eval.json")
    n10, n1 = final_returns(path / "eval.json")
    return Run(path, evaluation["seed"], n10, n1, tuple(read_rows(path)), evaluation["train_time_s"])


@functools.cache
def group(kept: Path, task: str, label: str) -> tuple[Run, ...]:
    return tuple(
        sorted((load_run(p.parent) for p in (kept / task / label).glob("seed*/eval.json")), key=lambda r: r.seed)
    )


def n10(runs, seeds=None) -> list[float]:
    return [r.n10 for r in runs if seeds is None or r.seed in seeds]


def eval_curve(run: Path) -> tuple[list[float], list[float]]:
    return load_run(run).curve


def first_reaching(curve: tuple[list[float], list[float]], value: float) -> float | None:
    """Env steps at the first periodic evaluation of ``curve`` whose return reaches ``value``."""
    return next((s for s, v in zip(*curve) if v >= value), None)


def keep_dmc(runs: Path, sweeps: Path) -> None:
    """The DMC study's small files (each stage's and each finished run's config, eval.json and progress rows), from
    runs/finetuning/dmc and the sweeps of DMC_SOURCES into their folders here."""
    for task in DMC_TASKS:
        stages = [(runs / task / name, DMC_KEPT / task / name) for name in ("demonstrator", "clone_refpo", "clone_ppo")]
        for kept, names, _ in DMC_SOURCES:
            for name in names:
                stages += [
                    (run, kept / task / run.parent.name / run.name)
                    for run in sorted((sweeps / name.format(task[4:]) / task).glob("*/seed*"))
                ]
        for src, dst in stages:
            if (src / "eval.json").exists():
                dst.mkdir(parents=True, exist_ok=True)
                for file in FILES:
                    if (src / file).exists():
                        shutil.copyfile(src / file, dst / file)
        if (runs / task / "data" / "metadata.json").exists():
            (DMC_KEPT / task / "data").mkdir(parents=True, exist_ok=True)
            shutil.copyfile(runs / task / "data" / "metadata.json", DMC_KEPT / task / "data" / "metadata.json")


def run_groups(task: str) -> Iterator[tuple[str, str, str, str, list[Path]]]:
    """(start, label, base, what, seed runs) of the task's fine-tuned and from-scratch groups, in the table's order:
    per method, its runs from the clone, with the normalisers updated, its variants, from scratch."""
    for label, base, what in DMC_METHODS:
        clone = "Gaussian clone" if base == "ppo" else "flow clone"
        for kept, _, start in DMC_SOURCES:
            runs = sorted((kept / task / label).glob("seed*/eval.json"))
            if runs:
                yield start.format(clone=clone), label, base, what, [r.parent for r in runs]


@functools.cache
def cpu_dmc_rows() -> dict[tuple[str, str], dict]:
    """The committed cpu_dmc rows by (task, label)."""
    with FROM_SCRATCH.open() as f:
        return {(r["task"], r["label"]): r for r in csv.DictReader(f)}


def return_targets(task: str) -> tuple[float, float]:
    """The data's return and PPO's from-scratch final return at the full CPU profile (cpu_dmc)."""
    data = read_json(DMC_KEPT / task / "clone_refpo" / "eval.json")["dataset"]["return_mean"]
    return data, float(cpu_dmc_rows()[(task, "ppo")]["return_multi_mean"])
