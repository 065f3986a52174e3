"""Where the tuning page's committed files are, the methods' labels and names, and the number formats its prose uses."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
REPO = RESULTS.parents[1]
TEMPLATE = HERE / "README.template.md"
STUDY = HERE / "study"
FRESH = HERE / "fresh"
BUDGET = HERE / "budget"
BUDGET_FILE = HERE / "budget.yaml"
CRITERIA = HERE / "criteria.yaml"
TUNING_FILE = REPO / "configs" / "tune" / "cpu_dmc.yaml"
DMC_PROFILE = REPO / "configs" / "task" / "_dmc.yaml"
TASKS = ("dmc_cartpole_balance", "dmc_point_mass", "dmc_reacher_easy")
# The committed rows at the paper's (or the authors') values: (runs.csv, label, where) per method; every seed the
# file holds is read.
COMMITTED = {
    "ppo": (RESULTS / "cpu_dmc" / "runs.csv", "ppo", "`cpu_dmc`"),
    "refpo": (RESULTS / "cpu_dmc" / "runs.csv", "refpo", "`cpu_dmc`"),
    "refpo_onestep": (
        RESULTS / "one_step" / "search" / "report" / "runs.csv",
        "onestep_c03",
        "the one-step search's `onestep_c03`",
    ),
    "fpo_pp": (RESULTS / "fpo_pp" / "report" / "runs.csv", "fpo_pp", "FPO++'s grid"),
}
LABELS = ("ppo", "refpo", "refpo_onestep", "fpo_pp")
FLOWS = ("refpo", "refpo_onestep", "fpo_pp")
NAMES = {"ppo": "PPO", "refpo": "ReFPO", "refpo_onestep": "ReFPO one-step", "fpo_pp": "FPO++"}
CODE_NAMES = {"ppo": "PPO", "refpo": "ReFPO", "refpo_onestep": "`refpo_onestep`", "fpo_pp": "FPO++"}


def read_yaml(path: Path) -> dict:
    return yaml.safe_load(Path(path).read_text(encoding="utf-8")) or {}


def number(text: str | None) -> float | None:
    return float(text) if text not in (None, "") else None


def fmt(value, digits: int = 3) -> str:
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


def short(task: str) -> str:
    return task.removeprefix("dmc_")


def steps_text(steps: float) -> str:
    return f"{steps / 1e6:.3g}M"


def times_text(x: float) -> str:
    """A ratio of two values: '4', '0.33', '6.8'."""
    return f"{x:.2g}"


def big_text(x: float) -> str:
    """A value that may be huge: '351', '2.2e10'."""
    return f"{x:.0f}" if abs(x) < 1e4 else re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", f"{x:.2g}")


def share_text(x: float) -> str:
    """0.1 -> '10 %'."""
    return f"{100 * x:g} %"
