"""Committing a sweep's runs beside a results page: the rows appended once, the small files copied, the evaluation
rows kept; and the pages' names for sets of seeds."""

import csv
import json

from refpo_warp.studies.reports.committed_runs import append_runs, eval_rows, seeds_text


def test_seeds_text_writes_runs_of_consecutive_seeds_as_ranges():
    assert seeds_text([22, 1, 3, 2, 21]) == "1-3, 21-22"
    assert seeds_text(["5", 7, 7]) == "5, 7"
    assert seeds_text([]) == "none"


def write_rows(path, rows):
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def test_append_runs_adds_each_new_seed_once_with_its_small_files(tmp_path):
    sweep = tmp_path / "runs" / "sweeps" / "grid"
    run = sweep / "task_a" / "ppo" / "seed21"
    run.mkdir(parents=True)
    (run / "config.yaml").write_text("seed: 21\n")
    (run / "eval.json").write_text("{}")
    (run / "model_3.pt").write_bytes(b"not copied")
    train = {"iteration": 0, "reward_mean": 2.0, "Loss/value": 1.0, "Flow/clip_fraction": 0.1, "Episode/success": 0.5}
    progress = [{**train, "time_s": 3.0, "steps_per_s": 7}, {"iteration": 1, "env_steps": 9, "eval/return_N10": 5.0}]
    (run / "progress.jsonl").write_text("\n".join(map(json.dumps, progress)) + "\n")
    (sweep / "report").mkdir()
    new = [
        {"task": "task_a", "label": "ppo", "seed": "1", "status": "ok", "minutes": "2", "run_dir": "elsewhere"},
        {"task": "task_a", "label": "ppo", "seed": "21", "status": "ok", "minutes": "3", "run_dir": str(run)},
        {"task": "task_a", "label": "ppo", "seed": "22", "status": "missing", "minutes": "", "run_dir": "x"},
    ]
    write_rows(sweep / "report" / "runs.csv", new)
    page = tmp_path / "docs"
    page.mkdir()
    write_rows(page / "runs.csv", [{"task": "task_a", "label": "ppo", "seed": "1", "status": "ok", "run_dir": "r"}])

    assert append_runs(sweep, page / "runs.csv", page / "runs", tmp_path) == 1
    assert append_runs(sweep, page / "runs.csv", page / "runs", tmp_path) == 0  # already there
    rows = list(csv.DictReader((page / "runs.csv").open()))
    assert [(r["seed"], r["minutes"], r["run_dir"]) for r in rows] == [
        ("1", "", "r"),
        ("21", "3", "docs/runs/task_a/ppo/seed21"),
    ]
    kept = page / "runs" / "task_a" / "ppo" / "seed21"
    assert sorted(p.name for p in kept.iterdir()) == [
        "config.yaml",
        "eval.json",
        "progress_eval.jsonl",
        "progress_train.jsonl",
    ]
    assert eval_rows(run / "progress.jsonl") == json.dumps(progress[1]) + "\n"
    assert (kept / "progress_train.jsonl").read_text() == json.dumps(train) + "\n"  # no timings, no evaluations


def test_append_runs_starts_a_missing_table_and_keeps_every_eval_curve(tmp_path):
    sweep = tmp_path / "sweep"
    run = sweep / "t" / "refpo" / "seed1"
    run.mkdir(parents=True)
    (run / "config.yaml").write_text("seed: 1\n")
    row = {"iteration": 4, "env_steps": 9, "eval/return_N10": 5.0, "eval/success_N10": 0.5, "Loss/value": 1.0}
    (run / "progress.jsonl").write_text(json.dumps(row) + "\n")
    (sweep / "report").mkdir()
    write_rows(
        sweep / "report" / "runs.csv",
        [{"task": "t", "label": "refpo", "seed": "1", "status": "ok", "run_dir": str(run)}],
    )
    assert append_runs(sweep, tmp_path / "page" / "runs.csv", tmp_path / "page" / "runs", tmp_path) == 1
    rows = list(csv.DictReader((tmp_path / "page" / "runs.csv").open()))
    assert [(r["label"], r["run_dir"]) for r in rows] == [("refpo", "page/runs/t/refpo/seed1")]
    kept = json.loads((tmp_path / "page" / "runs" / "t" / "refpo" / "seed1" / "progress_eval.jsonl").read_text())
    assert kept == {k: v for k, v in row.items() if k != "Loss/value"}  # a task's curve metrics beside the return
