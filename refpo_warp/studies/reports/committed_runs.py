"""Committing a sweep's finished runs beside a results page: each run's small files (``config.yaml``, ``eval.json``,
its periodic-evaluation rows and its training statistics) copied under the page's folder, and its ``refpo report``
row appended to the page's ``runs.csv``; and how pages name the seeds they hold."""

from __future__ import annotations

import csv
import io
import json
import shutil
from pathlib import Path

from refpo_warp.utils.atomic_files import write_text

RUN_FILES = ("config.yaml", "eval.json")
EVAL_ROW_KEYS = ("iteration", "env_steps", "time_s", "reward_mean")
TRAIN_ROW_KEYS = ("iteration", "env_steps", "reward_mean", "episode_length_mean")
# The training statistics a committed run keeps each iteration: losses and gradient norms, the flow's update
# statistics (ratios, clipping, KL), the training episodes' task metrics; not timings, not evaluations.
TRAIN_PREFIXES = ("Loss/", "Flow/", "Episode/")


def progress_rows(progress: Path, marker: tuple[str, ...], kept: tuple[str, ...], keys: tuple[str, ...]) -> str:
    """The rows of a run's ``progress.jsonl`` that hold a key starting with one of ``marker``, each with only ``keys``
    and the keys starting with one of ``kept``, as JSON lines."""
    rows = []
    for line in progress.read_text().splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        if any(k.startswith(marker) for k in row):
            rows.append(json.dumps({k: v for k, v in row.items() if k in keys or k.startswith(kept)}))
    return "\n".join(rows) + ("\n" if rows else "")


def eval_rows(progress: Path) -> str:
    """The rows of a run's ``progress.jsonl`` that hold a periodic evaluation (the curves a page draws), each with
    only its position, its training reward and its ``eval/`` values."""
    return progress_rows(progress, ("eval/return",), ("eval/",), EVAL_ROW_KEYS)


def train_rows(progress: Path) -> str:
    """Every iteration's training statistics of a run's ``progress.jsonl`` (``TRAIN_PREFIXES``): the losses, each
    network's gradient norm before clipping, the flow's ratio, clipping and KL statistics, the training episodes'
    metrics."""
    return progress_rows(progress, TRAIN_PREFIXES, TRAIN_PREFIXES, TRAIN_ROW_KEYS)


def read_jsonl(path: Path) -> list[dict]:
    """The rows of a JSON-lines file a page reads: a committed run's ``progress_eval.jsonl`` or
    ``progress_train.jsonl``, a learning check's records."""
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def run_machine(run: Path) -> dict | None:
    """The machine a committed run recorded in its ``eval.json``; None for a failed run or one made before runs
    recorded it."""
    path = run / "eval.json"
    return json.loads(path.read_text()).get("machine") if path.exists() else None


def copy_run(run: Path, dst: Path) -> None:
    """A run's small files into ``dst``: config.yaml, eval.json, and from its progress.jsonl the periodic evaluations
    (progress_eval.jsonl) and every iteration's training statistics (progress_train.jsonl)."""
    dst.mkdir(parents=True, exist_ok=True)
    for name in RUN_FILES:
        if (run / name).exists():
            shutil.copy2(run / name, dst / name)
    if (run / "progress.jsonl").exists():
        write_text(dst / "progress_eval.jsonl", eval_rows(run / "progress.jsonl"))
        write_text(dst / "progress_train.jsonl", train_rows(run / "progress.jsonl"))


def read_rows(path: Path) -> list[dict]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def append_runs(sweep_dir: Path, runs_csv: Path, runs_dir: Path, root: Path) -> int:
    """Append the (task, label, seed) rows of ``<sweep_dir>/report/runs.csv`` (``refpo report``'s) that ``runs_csv``
    lacks, finished or failed, copying each run's small files to ``runs_dir/<task>/<label>/seed<k>`` (the row's
    ``run_dir`` then names that folder, relative to ``root``); a missing ``runs_csv`` is started. Returns the rows
    added."""
    new = read_rows(sweep_dir / "report" / "runs.csv")
    old = read_rows(runs_csv) if runs_csv.exists() else []
    have = {(r["task"], r["label"], r["seed"]) for r in old}
    added = [r for r in new if (r["task"], r["label"], r["seed"]) not in have and r["status"] in ("ok", "failed")]
    for row in added:
        run = Path(row["run_dir"])
        run = run if run.is_absolute() or run.exists() else sweep_dir / run
        dst = runs_dir / row["task"] / row["label"] / f"seed{row['seed']}"
        copy_run(run, dst)
        row["run_dir"] = str(dst.relative_to(root))
    columns = list(dict.fromkeys([*(old[0].keys() if old else ()), *(k for r in added for k in r)]))
    out = io.StringIO()
    writer = csv.DictWriter(out, columns, lineterminator="\n", restval="")
    writer.writeheader()
    writer.writerows([*old, *added])
    write_text(runs_csv, out.getvalue())
    return len(added)


def seeds_text(seeds) -> str:
    """How a page names a set of seeds: 1, 2, 3, 21, 22 -> '1-3, 21-22'; none -> 'none'."""
    seeds, parts, start = sorted({int(s) for s in seeds}), [], None
    for i, s in enumerate(seeds):
        start = s if start is None else start
        if i + 1 == len(seeds) or seeds[i + 1] != s + 1:
            parts.append(str(s) if s == start else f"{start}-{s}")
            start = None
    return ", ".join(parts) if parts else "none"
