"""Run health: did a run's periodic evaluation return end near its best, or fall off a cliff?

For each evaluated setting (``N=10``, ``N=1``, ``N=10/zero``, ``mean_action``) of ``progress.jsonl``'s periodic
evaluations: the peak return and its iteration, the final return (the last evaluation, at the run's end) and the drop
from the peak, ``(peak - final) / |peak|``. A drop of ``CLIFF_DROP`` (30 %) or more flags the setting: FPO++'s cliff
rule (a late 50-iteration mean 30 % below the peak), scaled to our evaluation interval, where one evaluation stands
for the window. A collapse such as a one-step return that peaks and then sinks shows without reading a curve.
"""

from __future__ import annotations

import math

CLIFF_DROP = 0.3
CURVE_PREFIX = "eval/return"


def setting_of(curve_key: str) -> str:
    """The evaluation setting of a periodic curve: ``eval/return_N10_zero`` -> ``N=10/zero``, ``eval/return`` ->
    ``mean_action`` (the inverse of ``refpo_warp.evaluation.evaluate_policy.curve_key``)."""
    if curve_key == CURVE_PREFIX:
        return "mean_action"
    steps, _, protocol = curve_key[len(CURVE_PREFIX) + 2 :].partition("_")
    return f"N={steps}" + (f"/{protocol}" if protocol else "")


def run_health(rows: list[dict]) -> dict[str, dict]:
    """``{setting: {peak, peak_iteration, final, final_iteration, drop, cliff}}`` from progress rows (see above)."""
    keys = sorted({k for row in rows for k in row if k == CURVE_PREFIX or k.startswith(CURVE_PREFIX + "_N")})
    out = {}
    for key in keys:
        series = [(row["iteration"], float(row[key])) for row in rows if key in row and math.isfinite(row[key])]
        if not series:
            continue
        peak_iteration, peak = max(series, key=lambda point: point[1])  # the first of equal peaks
        final_iteration, final = series[-1]
        drop = (peak - final) / abs(peak) if peak else 0.0
        out[setting_of(key)] = {"peak": peak, "peak_iteration": peak_iteration, "final": final,
                                "final_iteration": final_iteration, "drop": drop,
                                "cliff": drop >= CLIFF_DROP}  # fmt: skip
    return out

