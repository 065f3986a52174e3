"""Reading a sweep's runs.csv rows and phrasing their numbers (seeds' returns, intervals, collapse), for both pages
of this folder: search.md (search_tables.py) and README.md (one_step_analysis.py --page)."""

from __future__ import annotations

import csv
import statistics
from pathlib import Path

import yaml

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
ROOT = RESULTS.parents[1]
CPU_DMC_RUNS = RESULTS / "cpu_dmc" / "runs.csv"
CRITERIA = HERE / "criteria.yaml"
MULTI, ONE = "return_multi", "return_1"


def criteria() -> dict:
    return yaml.safe_load(CRITERIA.read_text(encoding="utf-8"))


def read_rows(path: Path) -> list[dict]:
    with path.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def per_seed(rows: list[dict], label: str, task: str, key: str) -> dict[int, float]:
    """seed -> the run's ``key`` (a failed run's return counts as 0; a run without the number is left out)."""
    out = {}
    for row in rows:
        if row["label"] != label or row["task"] != task:
            continue
        if row["status"] == "failed" and key in (MULTI, ONE):
            out[int(row["seed"])] = 0.0
        elif row["status"] == "ok" and row.get(key) not in (None, ""):
            out[int(row["seed"])] = float(row[key])
    return dict(sorted(out.items()))


def labels_of(rows: list[dict]) -> list[str]:
    return list(dict.fromkeys(r["label"] for r in rows))


def tasks_of(rows: list[dict], label: str | None = None) -> list[str]:
    return sorted({r["task"] for r in rows if label is None or r["label"] == label})


def short(task: str) -> str:
    return task.removeprefix("dmc_")


def num(x: float, digits: int = 0) -> str:
    text = f"{x:.{digits}f}"
    return "0" if text.strip("-0.") == "" else text


def pm(values, digits: int = 0) -> str:
    """``mean ± population std`` (ddof 0, as ``refpo report`` writes them)."""
    values = list(values)
    return f"{num(statistics.fmean(values), digits)} ± {num(statistics.pstdev(values), digits)}"


def span(values, digits: int = 2) -> str:
    """``low-high`` of ``values`` (one number when they round alike)."""
    values = list(values)
    low, high = num(min(values), digits), num(max(values), digits)
    return low if low == high else f"{low}-{high}"


def listing(values, digits: int = 0, sep: str = " / ") -> str:
    return sep.join(num(v, digits) for v in values)


def of(k: int, n: int) -> str:
    return f"{k} of {n}"


def intervals(named: dict[str, list[float]]):
    """name -> the mean over the values with its 95 % stratified-bootstrap interval (rliable, one call for all)."""
    import numpy as np

    from refpo_warp.studies.reports.intervals import aggregate

    estimates = aggregate({k: np.asarray(v, dtype=float).reshape(-1, 1) for k, v in named.items()})
    return {k: e["mean"] for k, e in estimates.items()}


def interval_text(estimate, digits: int = 0) -> str:
    return estimate.text(digits)


def separated(a, b) -> bool:
    """Two intervals that do not overlap."""
    return a.high < b.low or b.high < a.low


def signed_pct(change: float) -> str:
    return f"{100 * change:+.1f} %".replace("-", "\u2212")


def collapsed(multi: float, one: float, below: float) -> bool:
    return one < below * multi


def sweep_spec(path: Path) -> dict:
    return yaml.safe_load(path.read_text(encoding="utf-8"))


def method_names(spec: dict) -> dict[str, str]:
    return {m["label"]: m.get("name", m["label"]) for m in spec["methods"]}
