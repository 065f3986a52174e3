"""Sweep report: aggregation on hand-made eval.json files (numbers worked out by hand), Markdown/CSV content,
missing/failed/stale runs, figures, and the latency benchmark's JSON that the report reads."""

import csv
import io
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from refpo_warp.studies.grid.run_metrics import headline_setting, run_metrics
from refpo_warp.studies.grid.spec import fingerprint
from refpo_warp.studies.reports.figures import seed_mean
from refpo_warp.studies.reports.report import load_record, write_report
from refpo_warp.studies.reports.tables import aggregate, fmt_number
from refpo_warp.utils.paths import REPO_ROOT

ROOT = REPO_ROOT


def flow_eval(n10, n1, straight=None, explosion=None, jac=None, multi=10, zero=None, seconds=None, cliff=None):
    report = {"task": "t", "algo": "refpo", "results": {f"N={multi}": {"return_mean": n10}, "N=1": {"return_mean": n1}}}
    if zero is not None:
        report["results"].update({f"N={multi}/zero": {"return_mean": zero[0]}, "N=1/zero": {"return_mean": zero[1]}})
    if seconds is not None:
        report["train_time_s"] = seconds
    report["health"] = {"cliff": {"status": cliff or "healthy"}, "curves": {}}
    diagnostics = {}
    if straight is not None:
        diagnostics.update(straightness_error=straight, explosion_rate=explosion)
    if jac is not None:
        diagnostics.update(jacobian_explosion_rate=jac[0], jacobian_norm_mean=jac[1], jacobian_norm_p95=jac[2])
    report["diagnostics"] = diagnostics
    return report


def gaussian_eval(ret):
    return {"task": "t", "algo": "ppo", "results": {"mean_action": {"return_mean": ret}}, "diagnostics": {}}


# (task, label, seed) -> eval.json; dmc_b/fpo/seed2 failed (no eval.json), dmc_a/refpo_l0.08/seed1 is stale.
RUNS = {
    ("dmc_a", "ppo", 1): gaussian_eval(100.0),
    ("dmc_a", "ppo", 2): gaussian_eval(300.0),
    ("dmc_b", "ppo", 1): gaussian_eval(500.0),
    ("dmc_b", "ppo", 2): gaussian_eval(700.0),
    ("dmc_a", "fpo", 1): flow_eval(400.0, 100.0, 0.05, 0.004),
    ("dmc_a", "fpo", 2): flow_eval(500.0, 300.0, 0.07, 0.002),
    ("dmc_b", "fpo", 1): flow_eval(600.0, 200.0, 0.06, 0.003),
    ("dmc_b", "fpo", 2): None,
    ("dmc_a", "refpo", 1): flow_eval(600.0, 500.0, 0.01, 0.001, (0.01, 0.4, 0.8), zero=(650.0, 600.0), seconds=120),
    ("dmc_a", "refpo", 2): flow_eval(700.0, 700.0, 0.02, 0.002, (0.03, 0.5, 0.9), zero=(750.0, 600.0), seconds=180),
    ("dmc_b", "refpo", 1): flow_eval(800.0, 800.0, 0.03, 0.003, (0.0, 0.6, 1.0), zero=(850.0, 600.0), seconds=240),
    ("dmc_b", "refpo", 2): flow_eval(
        900.0, 800.0, 0.06, 0.002, (0.02, 0.5, 1.3), zero=(950.0, 600.0), seconds=300, cliff="cliff_detected"
    ),
    ("dmc_a", "reinflow", 1): flow_eval(300.0, 250.0, multi=4, cliff="insufficient_data"),
    ("dmc_a", "refpo_l0.08", 1): flow_eval(1000.0, 1000.0, 0.0, 0.0),
}
METHODS = [("ppo", "PPO"), ("fpo", "FPO"), ("refpo", "ReFPO*"), ("reinflow", "ReinFlow"), ("refpo_l0.08", "λ=0.08")]


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("sweep")
    runs = []
    for (task, label, seed), report in RUNS.items():
        run_dir = root / task / label / f"seed{seed}"
        run_dir.mkdir(parents=True)
        config = {"task": task, "algo": label, "seed": seed, "device": "cpu"}
        (run_dir / "config.yaml").write_text(yaml.safe_dump(config))
        entry = {
            "task": task,
            "label": label,
            "algo": label,
            "seed": seed,
            "run_dir": str(run_dir.relative_to(root)),
            "fingerprint": "0000000000000000" if label == "refpo_l0.08" else fingerprint(config),
        }
        runs.append(entry)
        if report is not None:
            (run_dir / "eval.json").write_text(json.dumps(report))
        if label == "refpo":  # curves for the figures: evaluations at 10k and 20k env steps, ratios per update
            rows = [
                {
                    "iteration": i,
                    "env_steps": 10_000 * (i + 1),
                    "reward_mean": 100.0 * i + seed,
                    "eval/return_N10": 500.0 + 100 * i,
                    "eval/return_N1": 400.0 + 100 * i,
                    "Flow/ratio_max": [1.5, 40.0][i],
                }
                for i in range(2)
            ]
            (run_dir / "progress.jsonl").write_text("\n".join(json.dumps(r) for r in rows) + "\n")
    status = {"dmc_b/fpo/seed2": {"state": "failed", "exit_codes": [3, 3], "log": "dmc_b/fpo/seed2/train.log"}}
    (root / "status.json").write_text(json.dumps(status))
    spec = {
        "name": "handmade",
        "device": "cpu",
        "tasks": ["dmc_a", "dmc_b"],
        "seeds": [1, 2],
        "runs": runs,
        "methods": [{"label": label, "name": name, "algo": label} for label, name in METHODS],
    }
    (root / "sweep.yaml").write_text(yaml.safe_dump(spec, allow_unicode=True))
    latency = {
        "device": "cpu",
        "device_name": "test cpu",
        "rows": [
            {"task": "dmc_a", "algo": "ppo", "flow_steps": None, "batch": 1, "latency_ms": 0.05},
            {"task": "dmc_a", "algo": "refpo", "flow_steps": 10, "batch": 1, "latency_ms": 0.8},
            {"task": "dmc_a", "algo": "refpo", "flow_steps": 1, "batch": 1, "latency_ms": 0.1},
        ],
    }
    (root / "latency.json").write_text(json.dumps(latency))
    write_report(root)
    return root


def read_csv(path: Path) -> dict[str, dict]:
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    return {(r.get("task", ""), r["label"]) if "task" in r else r["label"]: r for r in rows}


def test_method_table_numbers_by_hand(sweep_dir):
    rows = read_csv(sweep_dir / "report" / "main.csv")
    refpo = rows["refpo"]
    # 10-step returns 600, 700 (dmc_a), 800, 900 (dmc_b): mean 750; deviations +-150, +-50 -> var 12500.
    assert float(refpo["return_multi_mean"]) == 750.0
    assert float(refpo["return_multi_std"]) == pytest.approx(math.sqrt(12500))
    assert float(refpo["return_multi_std_tasks"]) == pytest.approx(100.0)  # task means 650, 850
    assert float(refpo["return_multi_std_seeds"]) == pytest.approx(50.0)  # seed means 700, 800
    # 1-step 500, 700, 800, 800: mean 700, squared deviations 40000 + 0 + 10000 + 10000 -> var 15000.
    assert float(refpo["return_1_mean"]) == pytest.approx(700.0)
    assert float(refpo["return_1_std"]) == pytest.approx(math.sqrt(15000))
    assert float(refpo["straightness_mean"]) == pytest.approx(0.03)
    assert float(refpo["explosion_mean"]) == pytest.approx(0.002)
    assert (refpo["runs_finished"], refpo["runs_total"], refpo["return_multi_n"]) == ("4", "4", "4")
    # PPO: mean-action returns 100, 300, 500, 700 -> 400, var (300^2 + 100^2) / 2 = 50000; no diagnostics.
    assert float(rows["ppo"]["return_multi_mean"]) == 400.0
    assert float(rows["ppo"]["return_multi_std"]) == pytest.approx(math.sqrt(50000))
    assert rows["ppo"]["return_1_mean"] == rows["ppo"]["straightness_mean"] == ""
    # FPO: dmc_b seed 2 failed; 400, 500, 600 -> 500, var 20000 / 3; seed means 500 (400, 600) and 500.
    fpo = rows["fpo"]
    assert (fpo["runs_finished"], fpo["runs_total"]) == ("3", "4")
    assert float(fpo["return_multi_std"]) == pytest.approx(math.sqrt(20000 / 3))
    assert float(fpo["return_multi_std_seeds"]) == pytest.approx(0.0)
    # The stale run (config.yaml not the sweep's) is not counted.
    assert rows["refpo_l0.08"]["runs_finished"] == "0" and rows["refpo_l0.08"]["return_multi_mean"] == ""


def test_markdown_tables(sweep_dir):
    text = (sweep_dir / "report" / "report.md").read_text()
    assert (
        "| Method | Runs | 10-step Reward | 1-step Reward | 10-step, zero noise | 1-step, zero noise | "
        "Straightness | Explosion | 1-step Err. | 1-step Ratio | Train min. | Cliffs |"
    ) in text
    assert "| PPO | 4/4 | 400 ± 224 | -- | -- | -- | -- | -- | -- | -- | -- | n/a |" in text  # no health: n/a
    assert "| FPO | 3/4 | 500 ± 81.6 | 200 ± 81.6 | -- | -- | 0.06 | 0.003 | -- | -- | -- | 0/3 |" in text
    # zero noise: 10-step 650..950 -> 800 ± 112, 1-step 600 ± 0; minutes 2, 3, 4, 5 -> 3.5; one run flagged
    assert "| ReFPO* | 4/4 | 750 ± 112 | 700 ± 122 | 800 ± 112 | 600 ± 0 | 0.03 | 0.002 | -- | -- | 3.5 | 1/4 |" in text
    assert "| ReinFlow | 1/1 | 300 (N=4) | 250 | -- | -- | -- | -- | -- | -- | -- | n/a |" in text  # too short
    assert "| λ=0.08 | 0/1 | -- | -- | -- | -- | -- | -- | -- | -- | -- | n/a |" in text
    # Per task, mean ± std over seeds: dmc_a ReFPO 600/700 -> 650 ± 50, 1-step 500/700 -> 600 ± 100.
    assert (
        "| dmc_a | ReFPO* | 2/2 | 650 ± 50 | 600 ± 100 | 700 ± 50 | 600 ± 0 | 0.015 ± 0.005 | 0.0015 ± 0.0005 | -- "
        "| -- | 2.5 ± 0.5 | 0/2 |"
    ) in text
    assert "| dmc_b | FPO | 1/2 | 600 | 200 | -- | -- | 0.06 | 0.003 | -- | -- | -- | 0/1 |" in text
    assert (
        "## Run health: FPO++'s cliff rule on each run's training reward\n\n- dmc_b / refpo / seed 2: cliff\n"
        "1 of 12 finished runs are too short for the rule, or peak under its minimum (insufficient data).\n"
    ) in text
    # Appendix C: Jac. Expl. (0.01 + 0.03 + 0 + 0.02) / 4, Ratio Expl. = Explosion, norms 0.5 and P95 1.
    assert "| ReFPO* | 4/4 | 0.015 | 0.002 | 0.5 | 1 |" in text
    assert "| FPO | 3/4 | -- | 0.003 | -- | -- |" in text
    assert "population standard deviation (ddof = 0)" in text
    assert "- dmc_b / fpo / seed 2: failed: exit codes [3, 3]; log dmc_b/fpo/seed2/train.log" in text
    assert "- dmc_a / refpo_l0.08 / seed 1: stale" in text


def test_per_task_csv_and_runs_csv(sweep_dir):
    rows = read_csv(sweep_dir / "report" / "per_task.csv")
    assert float(rows[("dmc_b", "refpo")]["return_multi_mean"]) == 850.0
    assert float(rows[("dmc_b", "refpo")]["return_multi_std"]) == pytest.approx(50.0)
    runs = list(csv.DictReader(io.StringIO((sweep_dir / "report" / "runs.csv").read_text())))
    assert len(runs) == len(RUNS)
    failed = next(r for r in runs if (r["task"], r["label"], r["seed"]) == ("dmc_b", "fpo", "2"))
    assert failed["status"] == "failed" and failed["return_multi"] == ""
    flagged = next(r for r in runs if (r["task"], r["label"], r["seed"]) == ("dmc_b", "refpo", "2"))
    assert (flagged["health"], flagged["return_1_zero"], flagged["minutes"]) == ("cliff_detected", "600.0", "5.0")


def test_a_run_stopped_by_a_non_finite_loss_is_failed_whatever_status_json_says(tmp_path):
    run_dir = tmp_path / "dmc_a" / "fpo" / "seed1"
    run_dir.mkdir(parents=True)
    entry = {"task": "dmc_a", "label": "fpo", "seed": 1, "run_dir": "dmc_a/fpo/seed1"}
    interrupted = {"state": "interrupted"}  # e.g. a later invocation continued it and was stopped
    assert (load_record(tmp_path, entry, interrupted).status, load_record(tmp_path, entry, interrupted).note) == (
        "missing",
        "interrupted",
    )
    (run_dir / "stopped.json").write_text(json.dumps({"reason": "non-finite loss"}))
    record = load_record(tmp_path, entry, interrupted)
    assert record.status == "failed" and "stopped by a non-finite loss" in record.note


def test_figures_written(sweep_dir):
    for name in ("fig3_reward_curves.png", "fig4_ratio_spikes.png", "fig5b_latency.png"):
        assert (sweep_dir / "report" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (
        "![Figure 4: training return and max proxy ratio per update (seed 1)]"
        in (sweep_dir / "report" / "report.md").read_text()
    )


def test_run_metrics_settings():
    metrics, multi = run_metrics(flow_eval(300.0, 250.0, multi=4))
    assert multi == 4 and metrics == {"return_multi": 300.0, "return_1": 250.0, "return_headline": 300.0}
    metrics, multi = run_metrics({"results": {"mean_action": {"return_mean": 12.0}}, "diagnostics": {}})
    assert multi is None and metrics == {"return_multi": 12.0, "return_headline": 12.0}
    # FPO++: N = 64 beside 10 and 1, zero noise first: the 10-step column reads N = 10, its headline N = 64 from zero
    fpo_pp = {
        "results": {
            s: {"return_mean": v}
            for s, v in (
                ("N=64/zero", 9.0),
                ("N=10/zero", 8.0),
                ("N=1/zero", 7.0),
                ("N=64", 6.0),
                ("N=10", 5.0),
                ("N=1", 4.0),
            )
        },
        "protocol": {"initial_noise": ["zero", "random"]},
    }
    metrics, multi = run_metrics(fpo_pp)
    assert multi == 10 and headline_setting(fpo_pp) == "N=64/zero"
    assert metrics == {
        "return_multi": 5.0,
        "return_1": 4.0,
        "return_multi_zero": 8.0,
        "return_1_zero": 7.0,
        "return_headline": 9.0,
    }
    metrics, _ = run_metrics(flow_eval(float("nan"), 5.0, 0.1, 0.2))  # a non-finite number is left out
    assert "return_multi" not in metrics and metrics["ratio_expl"] == metrics["explosion"] == 0.2


def test_aggregate_and_format():
    stat = aggregate([("a", 1, 1.0), ("a", 2, 3.0), ("b", 1, 5.0)])
    assert stat.mean == 3.0 and stat.n == 3
    assert stat.std == pytest.approx(math.sqrt(8 / 3))
    assert stat.std_tasks == pytest.approx(1.5)  # task means 2 and 5
    assert stat.std_seeds == pytest.approx(0.0)  # seed means (1 + 5) / 2 = 3 and 3
    assert [fmt_number(x) for x in (None, 0.0, 641.4, 0.000144, 12.345)] == ["--", "0", "641", "0.000144", "12.3"]


def test_seed_mean_aligns_env_steps():
    steps, values = seed_mean([([10, 20, 30], [1.0, 2.0, 3.0]), ([10, 20], [3.0, 6.0])])
    assert steps == [10, 20] and values == [2.0, 4.0]  # only the counts every seed has
    steps, values = seed_mean([([10], [1.0]), ([15], [3.0])])
    assert steps == [10, 15] and values == [1.0, 3.0]  # nothing shared: each count over the seeds that have it


def test_report_cli_errors_on_empty_dir(tmp_path):
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "report.py"), str(tmp_path)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert result.returncode == 2 and "no sweep.yaml" in result.stderr


def test_latency_benchmark_json(tmp_path):
    out = tmp_path / "latency.json"
    result = subprocess.run(
        [
            sys.executable,
            str(ROOT / "tools" / "bench.py"),
            "latency",
            "tasks=gridworld",
            "algos=[ppo,refpo]",
            "batch_sizes=[1,4]",
            "repeats=3",
            "device=cpu",
            f"out={out}",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    data = json.loads(out.read_text())
    got = {(r["algo"], r["flow_steps"], r["batch"]) for r in data["rows"]}
    assert got == {
        ("ppo", None, 1),
        ("ppo", None, 4),
        ("refpo", 10, 1),
        ("refpo", 10, 4),
        ("refpo", 1, 1),
        ("refpo", 1, 4),
    }
    assert all(r["latency_ms"] > 0 for r in data["rows"]) and data["device"] == "cpu"
    assert "N=10 / N=1 latency ratio" in result.stdout
