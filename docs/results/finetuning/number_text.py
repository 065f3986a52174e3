"""How the fine-tuning page writes numbers: lists, ranges, env steps, and means with their 95 % intervals
(refpo_warp/studies/reports/intervals.py)."""

from __future__ import annotations

from refpo_warp.studies.reports.intervals import mean_estimate

# ------------------------------------------------------------------------------------------------ formatting


def span(values, digits: int = 0, sep: str = "-") -> str:
    """'lowest-highest' (one value when they round alike)."""
    low, high = f"{min(values):.{digits}f}", f"{max(values):.{digits}f}"
    return low if low == high else f"{low}{sep}{high}"


def slashed(values, digits: int = 0) -> str:
    return " / ".join(f"{v:.{digits}f}" for v in values)


def thousands(value: float) -> str:
    return f"{value:,.0f}"


def ksteps(value: float | None) -> str:
    return "-" if value is None else f"{value / 1000:.0f}k"


def seconds(value: float) -> str:
    return f"{value:.0f} s" if value >= 10 else f"{value:.1f} s"


# ------------------------------------------------------------------------------------------------ intervals
def interval_cell(values: list[float]) -> str:
    """Mean [95 % interval] (each seed's value)."""
    return f"{mean_estimate(tuple(values)).text()} ({', '.join(f'{v:.0f}' for v in values)})"
