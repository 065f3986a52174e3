"""What a sweep dir says about its runs: each run's state (done, failed, paused, stale, unfinished, new), the plan
of what to train, an earlier attempt cleared (its logs kept) and ``sweep.yaml``, the resolved spec merged over
earlier invocations."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import yaml

from refpo_warp.config.yaml_files import dump_config, load_yaml
from refpo_warp.studies.grid.spec import Run, Sweep, fingerprint
from refpo_warp.utils.errors import STOPPED_FILE, ConfigError

SPEC_FILE = "sweep.yaml"
STATUS_FILE = "status.json"
LOG_FILE = "train.log"
KEPT_STATES = ("done", "failed")  # not trained again: a finished run, or one a non-finite loss stopped (its outcome)


def run_state(run: Run, expected: str) -> str:
    """``done`` (eval.json of this config), ``failed`` (this config, stopped by a non-finite loss: its outcome, kept;
    a rerun would repeat it), ``paused`` (this config, no eval.json yet, a checkpoint to continue: a run stopped at a
    piece's end, or interrupted), ``stale`` (another config), ``unfinished`` (nothing to continue) or ``new``."""
    config = run.run_dir / "config.yaml"
    if not config.exists():
        return "unfinished" if run.run_dir.exists() and _not_logs(run.run_dir) else "new"
    try:
        if fingerprint(load_yaml(config)) != expected:
            return "stale"
    except (OSError, ValueError, ConfigError, yaml.YAMLError):
        return "unfinished"
    try:
        report = json.loads((run.run_dir / "eval.json").read_text())
    except (OSError, ValueError):
        report = {}
    if report.get("task") == run.task and report.get("algo") == run.method.algo:
        return "done"
    from refpo_warp.runner.checkpoints import list_checkpoints  # torch: not for a Ray worker's light imports

    if (run.run_dir / STOPPED_FILE).exists():
        return "failed"
    return "paused" if list_checkpoints(run.run_dir) else "unfinished"


def _not_logs(run_dir: Path) -> list[Path]:
    return [p for p in run_dir.iterdir() if not (p.name.startswith("train") and p.name.endswith(".log"))]


def clear_run_dir(run_dir: Path) -> None:
    """Remove everything of an earlier attempt but its logs; the last log becomes ``train.attempt<k>.log``."""
    if not run_dir.exists():
        return
    for path in _not_logs(run_dir):
        shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()
    log = run_dir / LOG_FILE
    if log.exists():
        k = 1
        while (run_dir / f"train.attempt{k}.log").exists():
            k += 1
        log.rename(run_dir / f"train.attempt{k}.log")


def write_spec(sweep: Sweep, prints: dict[str, str]) -> Path:
    """Write ``<sweep dir>/sweep.yaml``, merged with an existing one (union of methods and runs, ours win)."""
    path = sweep.out_dir / SPEC_FILE
    old = load_yaml(path) if path.exists() else {}
    methods = {m["label"]: m for m in old.get("methods", [])}
    methods.update(
        {m.label: {"label": m.label, "name": m.name, "algo": m.algo, "overrides": m.overrides} for m in sweep.methods}
    )
    runs = {r["run_dir"]: r for r in old.get("runs", [])}
    for run in sweep.runs:
        rel = str(run.run_dir.relative_to(sweep.out_dir))
        runs[rel] = {
            "task": run.task,
            "label": run.method.label,
            "algo": run.method.algo,
            "seed": run.seed,
            "run_dir": rel,
            "args": list(run.args),
            "fingerprint": prints[run.key],
        }
    spec = {
        "name": sweep.name,
        "source": sweep.source,
        "description": sweep.description,
        "device": sweep.device,
        "tasks": list(dict.fromkeys(old.get("tasks", []) + sweep.tasks)),
        "seeds": sorted(set(old.get("seeds", [])) | set(sweep.seeds)),
        "methods": list(methods.values()),
        "report": {**old.get("report", {}), **sweep.report},
        "runs": sorted(runs.values(), key=lambda r: (r["seed"], r["task"], r["label"])),
    }
    dump_config(json.loads(json.dumps(spec)), path)  # a plain copy: no YAML anchors for shared lists
    return path


def plan(sweep: Sweep, prints: dict[str, str]) -> tuple[list[Run], list[tuple[Run, str]], dict[str, list[str]]]:
    """(runs to train, runs kept as they are with their state: done or failed, run keys per state) for the current
    state of the sweep dir; a paused run is continued from its newest checkpoint."""
    states: dict[str, list[str]] = {}
    todo: list[Run] = []
    kept: list[tuple[Run, str]] = []
    for run in sweep.runs:
        state = run_state(run, prints[run.key])
        states.setdefault(state, []).append(run.key)
        if state in KEPT_STATES:
            kept.append((run, state))
        else:
            todo.append(run.continued() if state == "paused" else run)
    return todo, kept, states
