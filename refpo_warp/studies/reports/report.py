"""The report of a sweep dir: the paper's DMC tables as Markdown and CSV, the Appendix C table and the figures.

``write_report(sweep_dir)`` reads ``sweep.yaml`` (runs, methods, figure choices; written by ``refpo sweep``) and
``status.json``, then every run's ``eval.json`` and ``progress.jsonl``, and writes into ``<sweep dir>/report/``:
``report.md`` (all tables, the figures, the missing runs), ``main.csv``, ``per_task.csv``, ``appendix_c.csv``,
``runs.csv`` (one row per run), ``fig3_reward_curves.png``, ``fig4_ratio_spikes.png`` and, when a latency JSON
from ``refpo bench latency out=PATH`` is there, ``fig5b_latency.png``. A directory without ``sweep.yaml`` is
read as ``<task>/<label>/seed<k>/`` run dirs. A run without a (current) ``eval.json`` is listed as missing.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
from pathlib import Path

import yaml

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.runner.progress import read_rows
from refpo_warp.studies.grid.run_metrics import headline_setting, run_metrics
from refpo_warp.studies.grid.spec import fingerprint
from refpo_warp.studies.reports.figures import (
    CURVE_KEYS,
    latency_bars,
    ratio_key,
    ratio_spikes,
    reward_curve_grid,
    seed_mean,
    series,
)
from refpo_warp.studies.reports.tables import (
    AGGREGATION,
    APPENDIX_C_METRICS,
    MAIN_METRICS,
    METRIC_TITLES,
    SOURCES_APPENDIX_C,
    SOURCES_MAIN,
    RunRecord,
    appendix_c_markdown,
    cliffs_markdown,
    main_markdown,
    method_rows,
    task_markdown,
    task_rows,
    to_csv,
)
from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.errors import STOPPED_FILE, ConfigError

REPORT_DIR = "report"


def _scan(sweep_dir: Path) -> dict:
    """A spec for a directory of ``<task>/<label>/seed<k>`` run dirs without ``sweep.yaml``."""
    runs = []
    for path in sorted(sweep_dir.glob("*/*/seed*")):
        match = re.fullmatch(r"seed(\d+)", path.name)
        if match and path.is_dir() and ((path / "eval.json").exists() or (path / "config.yaml").exists()):
            task, label = path.parent.parent.name, path.parent.name
            runs.append(
                {"task": task, "label": label, "seed": int(match.group(1)), "run_dir": str(path.relative_to(sweep_dir))}
            )
    labels = list(dict.fromkeys(r["label"] for r in runs))
    return {
        "name": sweep_dir.name,
        "tasks": list(dict.fromkeys(r["task"] for r in runs)),
        "runs": runs,
        "methods": [{"label": label, "name": label} for label in labels],
        "report": {},
    }


def load_spec(sweep_dir: Path) -> dict:
    path = sweep_dir / "sweep.yaml"
    spec = load_yaml(path) if path.exists() else _scan(sweep_dir)
    if not spec.get("runs"):
        raise ConfigError(f"{sweep_dir}: no sweep.yaml and no <task>/<label>/seed<k> run dirs")
    return spec


def _missing(record: RunRecord, status: dict) -> RunRecord:
    state = status.get("state", "")
    stopped = record.run_dir / STOPPED_FILE  # the run's own record, whatever a later invocation left in status.json
    if state == "failed":
        record.status = "failed"
        record.note = f"exit codes {status.get('exit_codes')}; log {status.get('log')}"
    elif stopped.exists():
        record.status = "failed"
        record.note = f"stopped by a non-finite loss ({stopped}); log {record.run_dir / 'train.log'}"
    else:
        record.status = "missing"
        record.note = {"interrupted": "interrupted", "running": "was running (or the sweep stopped)"}.get(
            state, "not run yet"
        )
    return record


def load_record(sweep_dir: Path, entry: dict, status: dict) -> RunRecord:
    """A run's table numbers from its ``eval.json``, or why it has none."""
    record = RunRecord(entry["task"], entry["label"], int(entry["seed"]), sweep_dir / entry["run_dir"])
    report_path = record.run_dir / "eval.json"
    if not report_path.exists():
        return _missing(record, status)
    try:
        if entry.get("fingerprint") and fingerprint(load_yaml(record.run_dir / "config.yaml")) != entry["fingerprint"]:
            record.status, record.note = "stale", "its config.yaml is not the sweep's config for it (rerun the sweep)"
            return record
        report = json.loads(report_path.read_text())
    except (OSError, ValueError, yaml.YAMLError) as err:
        record.status, record.note = "unreadable", f"{type(err).__name__}: {err}"
        return record
    record.metrics, record.multi_n = run_metrics(report)
    record.health = ((report.get("health") or {}).get("cliff") or {}).get("status", "")
    record.headline = headline_setting(report) or ""
    return record


def load_records(sweep_dir: Path, spec: dict) -> list[RunRecord]:
    status_path = sweep_dir / "status.json"
    status = json.loads(status_path.read_text()) if status_path.exists() else {}
    return [
        load_record(sweep_dir, e, status.get(f"{e['task']}/{e['label']}/seed{e['seed']}", {})) for e in spec["runs"]
    ]


def _progress(record: RunRecord) -> list[dict]:
    try:
        return read_rows(record.run_dir)
    except (FileNotFoundError, ValueError):
        return []


def curve_data(records: list[RunRecord], methods: list[tuple[str, str]], tasks: list[str]) -> dict:
    """task -> method name -> progress key -> seed-mean (env steps, values), from the finished runs."""
    out: dict = {}
    for task in tasks:
        for label, name in methods:
            rows = [_progress(r) for r in records if r.task == task and r.label == label and r.status == "ok"]
            keys = {k: seed_mean([series(rs, k) for rs in rows]) for k in CURVE_KEYS}
            if any(x for x, _ in keys.values()):
                out.setdefault(task, {})[name] = keys
    return out


def ratio_data(records: list[RunRecord], methods: list[tuple[str, str]], tasks: list[str], seed: int | None):
    """(seed, task -> method name -> progress rows) for Figure 4: the given seed, else the lowest seed that every
    chosen (task, method) finished with ratio statistics."""
    runs = {(r.task, r.label, r.seed): r for r in records if r.status == "ok" and r.task in tasks}
    have = {k: rows for k, r in runs.items() if ratio_key(rows := _progress(r))}
    pairs = [(t, label) for t in tasks for label, _ in methods]
    seeds = sorted({s for _, _, s in have})
    if seed is None:
        seed = next((s for s in seeds if all((t, lb, s) in have for t, lb in pairs)), seeds[0] if seeds else None)
    if seed is None:  # no run has ratio statistics
        return seed, {}
    names = dict(methods)
    panels: dict = {}
    for task, label in pairs:
        if (task, label, seed) in have:
            panels.setdefault(task, {})[names[label]] = have[(task, label, seed)]
    return seed, panels


def _choice(given: list[str] | None, spec: dict, key: str, default: list[str], valid: list[str], what: str):
    chosen = list(given or spec.get("report", {}).get(key) or default)
    unknown = [c for c in chosen if c not in valid]
    if given and unknown:
        raise ConfigError(f"Unknown {what} {unknown}; the sweep has {valid}")
    return [c for c in chosen if c in valid]


def _write(path: Path, text: str) -> Path:
    write_text(path, text)
    return path


def runs_csv(records: list[RunRecord]) -> str:
    metrics = list(METRIC_TITLES)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(
        ["task", "label", "seed", "status", "multi_step_n", *metrics, "headline", "health", "note", "run_dir"]
    )
    for r in records:
        writer.writerow(
            [
                r.task,
                r.label,
                r.seed,
                r.status,
                r.multi_n or "",
                *[repr(r.metrics[m]) if m in r.metrics else "" for m in metrics],
                r.headline,
                r.health,
                r.note,
                r.run_dir,
            ]
        )
    return out.getvalue()


def write_report(
    sweep_dir: str | Path,
    out_dir: str | Path | None = None,
    latency: str | Path | None = None,
    curve_methods: list[str] | None = None,
    ratio_tasks: list[str] | None = None,
    ratio_methods: list[str] | None = None,
    seed: int | None = None,
) -> list[Path]:
    """Write the tables and figures of a sweep; returns the files written (``report.md`` first)."""
    sweep_dir = Path(sweep_dir)
    spec = load_spec(sweep_dir)
    out = Path(out_dir or sweep_dir / REPORT_DIR)
    out.mkdir(parents=True, exist_ok=True)
    records = load_records(sweep_dir, spec)
    methods = [(m["label"], m.get("name", m["label"])) for m in spec["methods"]]
    labels = [label for label, _ in methods]
    tasks = list(dict.fromkeys(spec.get("tasks") or [r.task for r in records]))
    mrows = method_rows(records, methods, MAIN_METRICS + APPENDIX_C_METRICS)
    trows = task_rows(records, methods, tasks)
    written = [out / "report.md"]
    written.append(_write(out / "main.csv", to_csv(mrows, MAIN_METRICS)))
    written.append(_write(out / "per_task.csv", to_csv(trows, MAIN_METRICS, per_task=True)))
    written.append(_write(out / "appendix_c.csv", to_csv(mrows, APPENDIX_C_METRICS)))
    written.append(_write(out / "runs.csv", runs_csv(records)))

    figures, notes = [], []
    chosen = _choice(curve_methods, spec, "curve_methods", labels, labels, "curve method(s)")
    curves = curve_data(records, [m for m in methods if m[0] in chosen], tasks)
    if curves:
        figures.append(
            (
                "Figure 3: reward curves, 10-step/1-step gap shaded, mean over seeds",
                reward_curve_grid(curves, out / "fig3_reward_curves.png"),
            )
        )
    else:
        notes.append("Figure 3: no finished run has progress.jsonl curves.")
    r_tasks = _choice(ratio_tasks, spec, "ratio_tasks", tasks[:3], tasks, "ratio task(s)")
    r_methods = _choice(ratio_methods, spec, "ratio_methods", labels, labels, "ratio method(s)")
    r_seed, panels = ratio_data(records, [m for m in methods if m[0] in r_methods], r_tasks, seed)
    if panels:
        figures.append(
            (
                f"Figure 4: training return and max proxy ratio per update (seed {r_seed})",
                ratio_spikes(panels, out / "fig4_ratio_spikes.png", r_seed),
            )
        )
    else:
        notes.append("Figure 4: no finished flow run with ratio statistics in progress.jsonl.")
    latency_path = Path(latency) if latency else sweep_dir / "latency.json"
    if latency_path.exists():
        data = json.loads(latency_path.read_text())
        names = {m["algo"]: m.get("name", m["label"]) for m in spec["methods"] if m["label"] == m.get("algo")}
        figures.append(
            (
                f"Figure 5b: action latency, N = 1 vs N = 10 ({latency_path})",
                latency_bars(data, out / "fig5b_latency.png", names),
            )
        )
    else:
        notes.append(
            f"Figure 5b: no {latency_path}; write it with `refpo bench latency tasks=<task> out={latency_path}`."
        )
    written += [path for _, path in figures]
    _write(out / "report.md", report_markdown(spec, records, mrows, trows, figures, notes, sweep_dir, out))
    return written


def report_markdown(spec, records, mrows, trows, figures, notes, sweep_dir: Path, out: Path) -> str:
    ok = [r for r in records if r.status == "ok"]
    lines = [f"# Sweep report: {spec.get('name', sweep_dir.name)}", ""]
    if spec.get("description"):
        lines += [spec["description"], ""]
    lines += [
        (
            f"Sweep dir `{sweep_dir}` (device profile: {spec.get('device', '?')}); {len(records)} runs, "
            f"{len(ok)} finished, {len(records) - len(ok)} missing. Written by "
            f"`refpo report {sweep_dir}`."
        ),
        "",
        '## DMC table (the paper\'s "MuJoCo Playground results")',
        "",
        main_markdown(mrows),
        AGGREGATION,
        "",
        SOURCES_MAIN,
        "",
        "## Per task",
        "",
        task_markdown(trows),
        "## Run health: FPO++'s cliff rule on each run's training reward",
        "",
        cliffs_markdown(records),
        "## Appendix C: Jacobian and policy-ratio diagnostics",
        "",
        appendix_c_markdown(mrows),
        SOURCES_APPENDIX_C,
        "",
        "CSV: `main.csv`, `per_task.csv`, `appendix_c.csv` (full precision), `runs.csv` (one row per run).",
        "",
    ]
    if figures or notes:
        lines += ["## Figures", ""]
        for title, path in figures:
            lines += [f"{title}", "", f"![{title}]({os.path.relpath(path, out)})", ""]
        lines += [f"- {n}" for n in notes] + ([""] if notes else [])
    missing = [r for r in records if r.status != "ok"]
    lines += ["## Missing runs", ""]
    lines += [f"- {r.task} / {r.label} / seed {r.seed}: {r.status}: {r.note}" for r in missing] or ["None."]
    return "\n".join(lines) + "\n"
