"""Reading the committed results and the phrases the top-level results pages share: the tuning study's
thresholds, runs.csv rows and eval.json returns, intervals over seeds, the configs' profiles, task names and env
steps (measured.py, index_page.py and learning_checks_page.py)."""

from __future__ import annotations

import csv
import functools
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # imported where used: numpy's import is the cost of a page that needs no interval
    from refpo_warp.studies.reports.intervals import Estimate


RESULTS = Path(__file__).resolve().parent
ROOT = RESULTS.parents[1]


@functools.cache
def criteria() -> dict:
    """The tuning study's thresholds (``tuning/criteria.yaml``): definitions its page and these sentences judge by,
    not measurements."""
    import yaml

    return yaml.safe_load((RESULTS / "tuning" / "criteria.yaml").read_text(encoding="utf-8"))


def one_step_share() -> float:
    """ "N = 1 keeps the N = 10 return": at least this share of it (the tuning goal's one-step part)."""
    return float(criteria()["goal"]["one_step"]["share"])


def fall_share() -> float:
    """A budget run falls when its last periodic return is below this share of its peak."""
    return float(criteria()["report"]["fall"])


def relative(path: Path) -> str:
    return str(path.relative_to(ROOT))


def number(text: str | None) -> float | None:
    return float(text) if text not in ("", None) else None


def interval(values) -> Estimate:
    """The mean over ``values`` (one per seed) with its 95 % stratified-bootstrap interval (``intervals.Estimate``)."""
    from refpo_warp.studies.reports.intervals import mean_estimate

    return mean_estimate(values)


def estimate(values, digits: int = 0) -> str:
    """``mean [low, high]`` over ``values``: the form every results page compares."""

    e = interval(values)
    return e.text(digits)


def read_csv(path: Path) -> list[dict]:
    return list(csv.DictReader(path.open(encoding="utf-8"))) if path.exists() else []


def method_names(runs_csv: Path) -> dict[str, str]:
    """label -> the method's name in the report beside ``runs_csv`` (its per_task.csv), or the label."""
    return {r["label"]: r["method"] for r in read_csv(runs_csv.with_name("per_task.csv"))}


def task_runs(rows: list[dict], label: str) -> dict[str, dict[int, dict]]:
    """task -> seed -> {multi, one, failed} of one method's runs in a runs.csv. A run that failed (its training
    stopped, e.g. on a non-finite loss) counts as return 0 at every N, as the tuning page counts it: leaving it out
    would flatter its method. Runs of any other status (not run yet, stale) are left out."""
    flow = any(r["label"] == label and r["return_1"] for r in rows)
    out: dict[str, dict[int, dict]] = {}
    for r in rows:
        if r["label"] != label:
            continue
        if r["status"] == "ok" and r["return_multi"]:
            run = {"multi": float(r["return_multi"]), "one": number(r["return_1"]), "failed": False}
        elif r["status"] == "failed":
            run = {"multi": 0.0, "one": 0.0 if flow else None, "failed": True}
        else:
            continue
        out.setdefault(r["task"], {})[int(r["seed"])] = run
    return out


def short(task: str) -> str:
    return task.removeprefix("dmc_")


def steps_text(steps: float) -> str:
    """``450k``, ``1M``, ``4.06M``: env steps to three significant digits."""
    return f"{steps / 1e6:.3g}M" if steps >= 1e6 else f"{steps / 1e3:.3g}k"


@functools.cache
def profile(task: str, algo: str = "ppo", device: str = "cpu") -> dict:
    """The resolved config of ``task``'s profile for ``device`` (``configs/``, as ``refpo train`` resolves it)."""
    from refpo_warp.config.resolve import resolve_config

    return resolve_config({"task": task, "algo": algo}, device_type=device)


def profile_steps(task: str, algo: str = "ppo", device: str = "cpu") -> int:
    return int(profile(task, algo, device)["total_env_steps"])


def profile_iterations(task: str, algo: str = "ppo", device: str = "cpu") -> int:
    cfg = profile(task, algo, device)
    if cfg["max_iterations"]:
        return int(cfg["max_iterations"])
    return math.ceil(cfg["total_env_steps"] / (cfg["num_envs"] * cfg["runner"]["num_steps_per_env"]))


def eval_results(path: Path) -> dict | None:
    return json.loads(path.read_text())["results"] if path.exists() else None


def final_returns(path: Path) -> tuple[float, float | None]:
    """(N = 10 return, or a Gaussian's mean-action return; N = 1 return or None) of an eval.json."""
    results = json.loads(path.read_text())["results"]
    if "mean_action" in results:
        return results["mean_action"]["return_mean"], None
    return results["N=10"]["return_mean"], results["N=1"]["return_mean"]


def count_text(k: int, n: int) -> str:
    return f"all {n}" if k == n and n > 2 else f"{k} of {n}"
