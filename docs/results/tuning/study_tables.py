"""The tuning study itself (study/): its trials, the values it chose, each method's own values, and the page's tables
of the search spaces, the trials, the chosen values and the search's times."""

from __future__ import annotations

import csv
import json
import math
import re
from datetime import datetime

from study_files import NAMES, STUDY, TUNING_FILE, fmt, number, read_yaml, short

from refpo_warp.utils.errors import DataFileError


# ------------------------------------------------------------------------------------------------ the study
def trials() -> list[dict]:
    path = STUDY / "trials.csv"
    return list(csv.DictReader(path.open(encoding="utf-8"))) if path.exists() else []


def own_trial(label: str) -> dict | None:
    """A method's first trial, its own values (enqueued), as trials.csv records it."""
    mine = [r for r in trials() if r["method"] == label]
    return next((r for r in mine if r["enqueued"] == "True"), None) or next(
        (r for r in mine if r["trial"] == "0"), None
    )


def own_values(label: str) -> dict:
    """``own_trial`` where the page needs it: an error naming the file when trials.csv has none."""
    own = own_trial(label)
    if own is None:
        raise DataFileError(f"{STUDY / 'trials.csv'}: no trial of '{label}' at its own values (enqueued or trial 0)")
    return own


def chosen() -> dict:
    path = STUDY / "chosen.yaml"
    return read_yaml(path) if path.exists() else {}


def profile_values() -> dict[str, dict]:
    """Each method's values of its searched options at the CPU profile as the configs resolve them today."""
    from refpo_warp.studies.tuning.spec import load_tuning
    from refpo_warp.studies.tuning.values import config_values

    tuning = load_tuning(str(TUNING_FILE))
    return {m.label: config_values(tuning, m) for m in tuning.methods}


def _same(a: dict, b: dict) -> bool:
    return set(a) == set(b) and all(math.isclose(float(a[k]), float(b[k]), rel_tol=1e-9) for k in a)


def spaces_table(profile: dict[str, dict]) -> str:
    spec = read_yaml(TUNING_FILE)
    lines = [
        "| method | option | searched | first trial (its own values, `study/trials.csv`) | CPU profile today |",
        "|---|---|---|---|---|",
    ]
    for m in spec["methods"]:
        first = own_trial(m["label"]) or {}
        for key, dim in m["space"].items():
            space = (
                "{" + ", ".join(str(c) for c in dim["choices"]) + "}"
                if "choices" in dim
                else f"[{dim['low']:g}, {dim['high']:g}]" + (" log" if dim.get("log") else "")
            )
            now = profile.get(m["label"], {}).get(key)
            lines.append(f"| {m['name']} | `{key}` | {space} | {fmt(number(first.get(key)))} | {fmt(now)} |")
    return "\n".join(lines)


def trials_table() -> str:
    spec = read_yaml(TUNING_FILE)
    rows = trials()
    out = []
    for m in spec["methods"]:
        mine = [r for r in rows if r["method"] == m["label"]]
        keys = list(m["space"])
        head = ["trial", "state", "score", "point_mass N=10 (N=1)", "reacher N=10 (N=1)", "min"]
        head += [k.rsplit(".", 1)[-1] for k in keys]
        lines = [
            f"**{m['name']}** ({len(mine)} of {spec['trials']} trials)",
            "",
            "| " + " | ".join(head) + " |",
            "|" + "---|" * len(head),
        ]
        for r in sorted(mine, key=lambda r: int(r["trial"])):
            cells = [
                r["trial"] + (" (own)" if r["enqueued"] == "True" else ""),
                r["state"] + _why(r),
                fmt(number(r["score"])),
            ]
            for task in ("dmc_point_mass", "dmc_reacher_easy"):
                multi, one = number(r.get(f"{task}/return_multi")), number(r.get(f"{task}/return_1"))
                cells.append("--" if multi is None else f"{multi:.0f}" + (f" ({one:.0f})" if one is not None else ""))
            cells.append(f"{float(r['seconds']) / 60:.1f}" if r.get("seconds") else "--")
            cells += [fmt(number(r.get(k))) for k in keys]
            lines.append("| " + " | ".join(cells) + " |")
        out.append("\n".join(lines))
    return "\n\n".join(out)


def _why(row: dict) -> str:
    match = re.search(r"periodic evaluation (\d+)", row.get("why") or "")
    return f" at eval {match.group(1)}" if match else ""


def budget_table() -> str:
    spec = read_yaml(TUNING_FILE)
    rows = trials()
    head = (
        "| method | trials spent | complete / pruned / failed | wall time (min) | best score (trial) "
        "| own values' score |"
    )
    lines = [head, "|---|---|---|---|---|---|"]
    for m in spec["methods"]:
        mine = [r for r in rows if r["method"] == m["label"]]
        states = [sum(r["state"] == s for r in mine) for s in ("complete", "pruned", "fail")]
        done = [r for r in mine if r["state"] == "complete"]
        best = max(done, key=lambda r: float(r["score"])) if done else None
        own = next((r for r in mine if r["enqueued"] == "True" and r["state"] == "complete"), None)
        minutes = sum(float(r["seconds"]) for r in mine if r.get("seconds")) / 60
        best_cell = f"{float(best['score']):.3f} ({best['trial']})" if best else "--"
        own_cell = f"{float(own['score']):.3f}" if own else "--"
        lines.append(
            f"| {m['name']} | {len(mine)} of {spec['trials']} | {' / '.join(map(str, states))} | "
            f"{minutes:.0f} | {best_cell} | {own_cell} |"
        )
    return "\n".join(lines)


def chosen_table() -> str:
    picked = chosen()
    if not picked:
        return "No completed trial yet."
    lines = ["| method | trial | score | values |", "|---|---|---|---|"]
    for label, c in picked.items():
        values = ", ".join(f"`{k}` {fmt(v)}" for k, v in c["overrides"].items())
        lines.append(f"| {NAMES.get(label, label)} | {c['trial']} | {c['score']:.3f} | {values} |")
    return "\n".join(lines)


def search_times() -> tuple[str, str]:
    """The first trial's start and the last trial's end in the Optuna journal (UTC)."""
    starts, ends = [], []
    path = STUDY / "journal.log"
    for line in path.read_text(encoding="utf-8").splitlines() if path.exists() else []:
        try:
            op = json.loads(line)
        except ValueError:
            continue
        if op.get("datetime_start"):
            starts.append(datetime.fromisoformat(op["datetime_start"]))
        if op.get("datetime_complete"):
            ends.append(datetime.fromisoformat(op["datetime_complete"]))
    if not starts or not ends:
        return "--", "--"
    return min(starts).strftime("%Y-%m-%d %H:%M"), max(ends).strftime("%Y-%m-%d %H:%M")


def trial_returns(row: dict, task: str) -> tuple[float | None, float | None]:
    return number(row.get(f"{task}/return_multi")), number(row.get(f"{task}/return_1"))


def chosen_one_step(crit: dict) -> str:
    """What the objective does not see: whether each flow method's chosen and own values keep N = 1 near N = 10 on
    the tuning tasks (from trials.csv)."""
    share, rows, picked, spec = crit["goal"]["one_step"]["share"], trials(), chosen(), read_yaml(TUNING_FILE)
    parts = []
    for label in [m["label"] for m in spec["methods"]]:
        if label not in picked:
            continue
        row = next((r for r in rows if r["method"] == label and int(r["trial"]) == picked[label]["trial"]), None)
        own = own_trial(label)
        if row is None or own is None or trial_returns(row, spec["tasks"][0])[1] is None:
            continue  # a Gaussian: no N = 1 return

        def held(r):
            pairs = [trial_returns(r, t) for t in spec["tasks"]]
            ok = sum(one is not None and multi is not None and one >= share * multi for multi, one in pairs)
            text = ", ".join(
                f"{short(t)} {one:.0f} against {multi:.0f}" for t, (multi, one) in zip(spec["tasks"], pairs)
            )
            return ok, text

        (k, text), (j, own_text) = held(row), held(own)
        n = len(spec["tasks"])
        parts.append(
            f"{NAMES[label]}'s chosen values (trial {row['trial']}) hold N = 1 ≥ {share:g} × N = 10 on {k} of {n} "
            f"tuning tasks ({text}), its own values (trial {own['trial']}) on {j} of {n} ({own_text})."
        )
    return " ".join(parts)
