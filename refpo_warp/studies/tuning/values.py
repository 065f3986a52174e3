"""The values a tuning searches, read from configs: a trial run's config resolved as its ``refpo train`` process will,
a dotted option of it, a method's own values (its first, enqueued trial) and the check that every method's runs
resolve at its enqueued values and at each dimension's extremes, before anything starts."""

from __future__ import annotations

from typing import Any

from refpo_warp.studies.grid.spec import Run
from refpo_warp.studies.tuning.spec import CONFIG_VALUES, TunedMethod, Tuning
from refpo_warp.utils.errors import ConfigError, unknown


def run_config(tuning: Tuning, run: Run) -> dict:
    """A trial run's config, resolved as its ``refpo train`` process will."""
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.studies.grid.spec import device_type

    return resolve_config(
        parse_overrides([*run.args, f"device={tuning.device}"]), device_type=device_type(tuning.device)
    )


def method_config(tuning: Tuning, method: TunedMethod, task: str, values: dict[str, Any]) -> dict:
    return run_config(tuning, tuning.trial_runs(method, 0, values)[tuning.tasks.index(task)])


def option_value(cfg: dict, key: str) -> Any:
    """A dotted option of a resolved config; an unset constructor argument reads its class's default."""
    from refpo_warp.config.classes import class_parameters

    node: Any = cfg
    parts = key.split(".")
    for i, part in enumerate(parts[:-1]):
        if not isinstance(node, dict) or not isinstance(node.get(part), dict):
            choices = [".".join([*parts[:i], k]) for k, v in node.items() if isinstance(v, dict)]
            raise unknown("config section", ".".join(parts[: i + 1]), choices)
        node = node[part]
    params = class_parameters(node["class_name"]) if "class_name" in node else {}
    if parts[-1] in node:
        return node[parts[-1]]
    if parts[-1] in params:
        return params[parts[-1]]
    section = ".".join(parts[:-1])
    raise unknown(f"option of {section}", key, [f"{section}.{k}" for k in sorted({*node, *params})])


def config_values(tuning: Tuning, method: TunedMethod) -> dict[str, Any]:
    """The searched options' values in the method's own config (the first task's profile)."""
    cfg = method_config(tuning, method, tuning.tasks[0], {})
    return {d.key: option_value(cfg, d.key) for d in method.space}


def enqueued_values(tuning: Tuning, method: TunedMethod) -> list[dict[str, Any]]:
    out = []
    for item in method.enqueue:
        values = config_values(tuning, method) if item == CONFIG_VALUES else dict(item)
        for dim in method.space:
            if dim.key not in values:
                raise ConfigError(f"Method '{method.label}': an enqueued trial lacks '{dim.key}'")
            if not dim.contains(values[dim.key]):
                raise ConfigError(
                    f"Method '{method.label}': enqueued {dim.key} = {values[dim.key]!r} lies outside "
                    f"its space {dim.describe()}"
                )
        extra = sorted(set(values) - {d.key for d in method.space})
        if extra:
            raise ConfigError(f"Method '{method.label}': enqueued values of options not searched: {extra}")
        out.append({d.key: values[d.key] for d in method.space})
    return out


def validate(tuning: Tuning) -> dict[str, list[dict[str, Any]]]:
    """Resolve every method's runs at its enqueued values and at each dimension's extremes, on every task, as
    ``refpo train`` will; returns the enqueued values per method. Every failure is collected and raised together."""
    errors: list[str] = []
    enqueued: dict[str, list[dict[str, Any]]] = {}
    for method in tuning.methods:
        try:
            enqueued[method.label] = enqueued_values(tuning, method)
        except ConfigError as err:
            errors.append(f"- {method.label}: {err}")
            continue
        base = enqueued[method.label][0] if enqueued[method.label] else {}
        probes = [base] + [{**base, d.key: v} for d in method.space for v in (d.choices or (d.low, d.high))]
        for task in tuning.tasks:
            for values in probes:
                try:
                    cfg = method_config(tuning, method, task, values)
                    if not cfg["eval"]["at_end"]:
                        raise ConfigError("eval.at_end is false: a trial run must write eval.json")
                except ConfigError as err:
                    errors.append(f"- {method.label} on {task} at {values}: {err}")
                    break
    if errors:
        raise ConfigError(
            f"Tuning '{tuning.name}': {len(errors)} method config(s) do not resolve:\n" + "\n".join(errors)
        )
    return enqueued
