"""A tuning's records, rewritten after every trial: ``trials.csv`` (every spent trial: its values, state, score,
per-task returns and why it did not complete), ``chosen.yaml`` (each method's best completed trial) and, once every
method has spent its trials, ``evaluate.yaml`` (the sweep of the chosen values on fresh seeds)."""

from __future__ import annotations

import csv
import io
import json
from typing import Any

from refpo_warp.studies.tuning.spec import Tuning
from refpo_warp.utils.atomic_files import write_text

TRIALS_FILE = "trials.csv"
CHOSEN_FILE = "chosen.yaml"
EVALUATION_FILE = "evaluate.yaml"  # the sweep of the chosen values on fresh seeds (tuning files with `evaluate`)


def spent_trials(study) -> list:
    """The trials that count against the budget: completed, pruned and failed ones (a failure says why); not those
    cut off by an interruption (failed without a reason, and enqueued again)."""
    from optuna.trial import TrialState

    return [
        t
        for t in study.trials
        if t.state in (TrialState.COMPLETE, TrialState.PRUNED) or (t.state == TrialState.FAIL and "why" in t.user_attrs)
    ]


def write_records(tuning: Tuning, studies: dict[str, Any]) -> None:
    write_text(tuning.out_dir / TRIALS_FILE, trials_csv(tuning, studies))
    write_text(tuning.out_dir / CHOSEN_FILE, chosen_yaml(tuning, studies))
    sweep = evaluation_sweep(tuning, studies)
    if sweep is not None:
        write_text(tuning.out_dir / EVALUATION_FILE, sweep)


def trial_rows(tuning: Tuning, studies: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for method in tuning.methods:
        study = studies.get(method.label)
        for t in spent_trials(study) if study is not None else []:
            row = {
                "method": method.label,
                "trial": t.user_attrs.get("slot", t.number),
                "state": t.state.name.lower(),
                "enqueued": bool(t.user_attrs.get("enqueued")),
                "score": t.value if t.state.name == "COMPLETE" else None,
                "seconds": t.user_attrs.get("seconds"),
            }
            for task in tuning.tasks:
                for metric in ("return_multi", "return_1"):
                    row[f"{task}/{metric}"] = t.user_attrs.get(f"{task}/{metric}")
            row.update({d.key: t.params.get(d.key) for d in method.space})
            row["why"] = t.user_attrs.get("why", "")
            rows.append(row)
    return rows


def trials_csv(tuning: Tuning, studies: dict[str, Any]) -> str:
    rows = trial_rows(tuning, studies)
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def chosen_values(tuning: Tuning, studies: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Each method's best completed trial: its values, score and trial number (methods without one are left out)."""
    from optuna.trial import TrialState

    out = {}
    for method in tuning.methods:
        study = studies.get(method.label)
        complete = [t for t in (study.trials if study else []) if t.state == TrialState.COMPLETE]
        if not complete:
            continue
        best = max(complete, key=lambda t: t.value)
        out[method.label] = {
            "algo": method.algo,
            "trial": best.user_attrs.get("slot"),
            "score": best.value,
            "trials_spent": len(spent_trials(study)),
            "overrides": {**method.overrides, **best.params},
        }
    return out


def chosen_yaml(tuning: Tuning, studies: dict[str, Any]) -> str:
    import yaml

    head = (
        f"# refpo tune {tuning.name}: each method's best completed trial (objective: mean over "
        f"{', '.join(tuning.tasks)} of {tuning.objective.metric} / its reference, seed {tuning.seed}).\n"
    )
    return head + yaml.safe_dump(chosen_values(tuning, studies), sort_keys=False)


def evaluation_sweep(tuning: Tuning, studies: dict[str, Any]) -> str | None:
    """The sweep file of the chosen values on fresh seeds (``refpo sweep <out>/evaluate.yaml``), once every method has
    spent its trials and has a completed one; None before. A run keeps its method's own evaluation protocol (the
    tuning's ``overrides`` are for the trials only)."""
    import yaml

    ev = tuning.evaluation
    chosen = chosen_values(tuning, studies)
    done = all(len(spent_trials(studies[m.label])) >= tuning.trials and m.label in chosen for m in tuning.methods)
    if ev is None or not done:
        return None
    methods = [
        {"label": m.label, "algo": m.algo, "name": f"{m.name} (tuned)", "overrides": chosen[m.label]["overrides"]}
        for m in tuning.methods
    ]
    for v in ev.variants:
        methods.append(
            {
                "label": v["label"],
                "algo": v["algo"],
                "name": f"{v['name']} (tuned {v['of']})",
                "overrides": chosen[v["of"]]["overrides"],
            }
        )
    spec = {
        "description": f"the chosen values of refpo tune {tuning.name} on fresh seeds {ev.seeds}",
        "device": tuning.device,
        "tasks": ev.tasks,
        "seeds": ev.seeds,
        "methods": methods,
        "out": str(tuning.out_dir / "evaluate"),
    }
    head = (
        f"# Written by refpo tune {tuning.name} when every method had spent its {tuning.trials} trials: each "
        f"method's best trial (chosen.yaml). Run: refpo sweep <this file>\n"
    )
    return head + yaml.safe_dump(json.loads(json.dumps(spec)), sort_keys=False)  # a plain copy: no YAML anchors
