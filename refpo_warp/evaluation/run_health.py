"""Run health: did a run's training reward fall off a cliff, and where did each periodic evaluation curve end?

``cliff``: FPO++'s receipts rule (``fpo_training_receipts/cliff.py`` in ``amazon-far/fpo-control``), on the training
reward of each iteration (``reward_mean`` in ``progress.jsonl``; an iteration without it counts as 0, as FPO++'s reader
counts a missing step): a run shorter than ``MIN_PLATEAU + WINDOW`` iterations, or whose peak is under
``MIN_PEAK``, has ``insufficient_data``; otherwise it is ``cliff_detected`` when the mean over some ``WINDOW``
iterations starting ``MIN_PLATEAU`` or more iterations after the peak lies ``DROP`` (30 %) or more below the peak,
and ``healthy`` when none does. A window of 50 training iterations averages out the noise of any one of them.

``curves``: for each periodically evaluated setting (``N=10``, ``N=1``, ``N=10/zero``, ``mean_action``), its peak
return and iteration, the final return (the last evaluation) and the drop from the peak, ``(peak - final) / |peak|``:
a one-step return that peaks and then sinks shows without reading a curve. With one evaluation of 16 episodes per
point these numbers move with evaluation noise, so they carry no verdict.
"""

from __future__ import annotations

import math

MIN_PEAK, MIN_PLATEAU, DROP, WINDOW = 10.0, 100, 0.30, 50  # FPO++'s detect_reward_cliff defaults
REWARD_KEY = "reward_mean"
CURVE_PREFIX = "eval/return"
HEALTHY, CLIFF, INSUFFICIENT = "healthy", "cliff_detected", "insufficient_data"


def setting_of(curve_key: str) -> str:
    """The evaluation setting of a periodic curve: ``eval/return_N10_zero`` -> ``N=10/zero``, ``eval/return`` ->
    ``mean_action`` (the inverse of ``refpo_warp.evaluation.evaluate_policy.curve_key``)."""
    if curve_key == CURVE_PREFIX:
        return "mean_action"
    steps, _, protocol = curve_key[len(CURVE_PREFIX) + 2 :].partition("_")
    return f"N={steps}" + (f"/{protocol}" if protocol else "")


def reward_cliff(rewards: list[float]) -> dict:
    """FPO++'s verdict on a training-reward series, one value per iteration (see the module docstring)."""
    out = {
        "status": INSUFFICIENT,
        "iterations": len(rewards),
        "peak": None,
        "peak_iteration": None,
        "cliff_iteration": None,
        "drop": None,
    }
    if len(rewards) < MIN_PLATEAU + WINDOW:
        return {**out, "message": f"needs {MIN_PLATEAU + WINDOW} iterations, has {len(rewards)}"}
    peak = max(rewards)
    peak_iteration = rewards.index(peak)
    out.update(peak=peak, peak_iteration=peak_iteration)
    if peak < MIN_PEAK:
        return {**out, "message": f"peak reward {peak:.4g} under {MIN_PEAK:g}"}
    for start in range(peak_iteration + MIN_PLATEAU, len(rewards) - WINDOW + 1):
        drop = (peak - sum(rewards[start : start + WINDOW]) / WINDOW) / max(peak, 1e-8)
        if drop >= DROP:
            return {
                **out,
                "status": CLIFF,
                "cliff_iteration": start,
                "drop": drop,
                "message": f"the {WINDOW}-iteration mean from iteration {start} is {100 * drop:.0f} % under "
                f"the peak {peak:.4g} (iteration {out['peak_iteration']})",
            }
    return {
        **out,
        "status": HEALTHY,
        "message": f"no cliff after the peak {peak:.4g} (iteration {out['peak_iteration']})",
    }


def curve_summaries(rows: list[dict]) -> dict[str, dict]:
    """``{setting: {peak, peak_iteration, final, final_iteration, drop}}`` of the periodic evaluation curves."""
    keys = sorted({k for row in rows for k in row if k == CURVE_PREFIX or k.startswith(CURVE_PREFIX + "_N")})
    out = {}
    for key in keys:
        series = [(row["iteration"], float(row[key])) for row in rows if key in row and math.isfinite(row[key])]
        if not series:
            continue
        peak_iteration, peak = max(series, key=lambda point: point[1])  # the first of equal peaks
        final_iteration, final = series[-1]
        out[setting_of(key)] = {
            "peak": peak,
            "peak_iteration": peak_iteration,
            "final": final,
            "final_iteration": final_iteration,
            "drop": (peak - final) / abs(peak) if peak else 0.0,
        }
    return out


def run_health(rows: list[dict]) -> dict:
    """``{"cliff": reward_cliff(training reward), "curves": curve_summaries(rows)}`` from a run's progress rows."""
    rewards = [0.0] * (max((int(r["iteration"]) for r in rows), default=-1) + 1)
    for row in rows:
        value = row.get(REWARD_KEY)
        if value is not None and math.isfinite(value):
            rewards[int(row["iteration"])] = float(value)
    return {"cliff": reward_cliff(rewards), "curves": curve_summaries(rows)}
