"""The numbers of one finished run (its ``eval.json``) that the tables, a report and a tuning trial's score read:
the 10-step and 1-step returns (and under zero initial noise), the run's own headline, its training minutes and its
flow diagnostics (``reports/tables.py`` says which key each comes from)."""

from __future__ import annotations

import math

DIAGNOSTIC_KEYS = {
    "straightness": "straightness_error",
    "explosion": "explosion_rate",
    "one_step": "one_step_error_eval",
    "one_step_ratio": "one_step_ratio_eval",
    "jac_expl": "jacobian_explosion_rate",
    "ratio_expl": "explosion_rate",
    "jac_norm_mean": "jacobian_norm_mean",
    "jac_norm_p95": "jacobian_norm_p95",
}


def finite(value) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


def headline_setting(report: dict) -> str | None:
    """The setting a run's own protocol puts first: its first initial-noise protocol at its largest N (``N=64/zero``
    for FPO++), or ``mean_action``; None for a report without results."""
    results = report.get("results") or {}
    if "mean_action" in results:
        return "mean_action"
    steps = sorted(int(k[2:]) for k in results if k.startswith("N=") and k[2:].isdigit())
    if not steps:
        return None
    protocols = (report.get("protocol") or {}).get("initial_noise") or ["random"]
    return f"N={steps[-1]}" + ("" if protocols[0] == "random" else f"/{protocols[0]}")


def run_metrics(report: dict) -> tuple[dict[str, float], int | None]:
    """The table numbers of one ``eval.json`` and the multi-step N used for the 10-step column (see the module
    docstring)."""
    results = report.get("results") or {}
    steps = sorted(int(k[2:]) for k in results if k.startswith("N=") and k[2:].isdigit())
    raw: dict[str, object] = {}
    multi = 10 if 10 in steps else (steps[-1] if steps and steps[-1] > 1 else None)
    if multi is not None:
        raw["return_multi"] = results[f"N={multi}"].get("return_mean")
    elif "mean_action" in results:
        raw["return_multi"] = results["mean_action"].get("return_mean")
    if 1 in steps:
        raw["return_1"] = results["N=1"].get("return_mean")
    raw["return_multi_zero"] = results.get(f"N={multi}/zero", {}).get("return_mean")
    raw["return_1_zero"] = results.get("N=1/zero", {}).get("return_mean")
    setting = headline_setting(report)
    raw["return_headline"] = results.get(setting, {}).get("return_mean") if setting else None
    raw["minutes"] = report["train_time_s"] / 60 if finite(report.get("train_time_s")) else None
    diagnostics = report.get("diagnostics") or {}
    for metric, key in DIAGNOSTIC_KEYS.items():
        raw[metric] = diagnostics.get(key)
    metrics = {k: v for k, v in ((k, finite(v)) for k, v in raw.items()) if v is not None}
    return metrics, multi
