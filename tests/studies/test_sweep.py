"""Sweep runner: grid expansion, validation before anything starts, the named sweeps, and real tiny gridworld runs
(separate tools/train.py processes) that finish, are skipped when done, or really fail and are retried once."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
import torch
import yaml
from tiny_runs import TINY  # tests/studies/tiny_runs.py

from refpo_warp.config.dotted import parse_overrides
from refpo_warp.config.resolve import resolve_config
from refpo_warp.studies.grid.spec import cli_value, fingerprint, load_sweep, validate
from refpo_warp.studies.sweep import run_sweep
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT

ROOT = REPO_ROOT


def write_spec(path: Path, **spec) -> Path:
    path.write_text(yaml.safe_dump({"device": "cpu", "tasks": ["gridworld"], "seeds": [1], **spec}))
    return path


def test_grid_expands_tasks_methods_seeds_and_list_overrides(tmp_path):
    spec = write_spec(
        tmp_path / "grid.yaml",
        tasks=["gridworld", "dmc_point_mass"],
        seeds=[1, 2],
        methods=[
            {"label": "ppo", "algo": "ppo", "name": "PPO"},
            {
                "label": "refpo_l{algorithm.reflow_coef}",
                "algo": "refpo",
                "name": "ReFPO, λ={algorithm.reflow_coef}",
                "overrides": {"algorithm": {"reflow_coef": [0.02, 0.08]}, "eval.flow_steps": [10, 1]},
            },
            {"label": "fpo", "algo": "fpo", "overrides": {"eval.flow_steps": [[10, 1], [20, 1]]}},
        ],
    )
    sweep = load_sweep(str(spec), [f"out={tmp_path / 'out'}"])
    labels = [m.label for m in sweep.methods]
    # A list expands the grid; eval.flow_steps takes a list, so only a list of lists expands it.
    assert labels == ["ppo", "refpo_l0.02", "refpo_l0.08", "fpo_flow_steps10-1", "fpo_flow_steps20-1"]
    assert [m.name for m in sweep.methods][1:4] == ["ReFPO, λ=0.02", "ReFPO, λ=0.08", "fpo (flow_steps=10-1)"]
    assert sweep.methods[1].overrides == {"algorithm.reflow_coef": 0.02, "eval.flow_steps": [10, 1]}
    assert len(sweep.runs) == 2 * 5 * 2
    assert [r.key for r in sweep.runs[:6]] == [  # seed-major: a first full table as early as possible
        "gridworld/ppo/seed1",
        "gridworld/refpo_l0.02/seed1",
        "gridworld/refpo_l0.08/seed1",
        "gridworld/fpo_flow_steps10-1/seed1",
        "gridworld/fpo_flow_steps20-1/seed1",
        "dmc_point_mass/ppo/seed1",
    ]
    run = sweep.runs[2]
    assert run.run_dir == tmp_path / "out" / "gridworld" / "refpo_l0.08" / "seed1"
    assert "algorithm.reflow_coef=0.08" in run.args and "eval.flow_steps=[10, 1]" in run.args
    cfg = resolve_config(parse_overrides(list(run.args)))  # the arguments resolve as tools/train.py reads them
    assert cfg["algorithm"]["reflow_coef"] == 0.08 and cfg["seed"] == 1 and cfg["run_dir"] == str(run.run_dir)
    # Command-line values: run options for every run (a list expands), sweep-level keys narrow the grid.
    sweep = load_sweep(str(spec), ["methods=[refpo_l0.02,ppo]", "seeds=[3]", "algorithm.learning_rate=[0.001,0.002]"])
    assert [m.label for m in sweep.methods] == [
        "ppo_learning_rate0.001",
        "ppo_learning_rate0.002",
        "refpo_l0.02_learning_rate0.001",
        "refpo_l0.02_learning_rate0.002",
    ]
    assert {r.seed for r in sweep.runs} == {3}


def test_cli_values_read_back_unchanged():
    for value in (0.02, 1e-06, 1e30, 3, True, None, "u", [10, 1], [[1, 2], [3]], {"a": 1.5}, float("inf")):
        assert parse_overrides([f"k={cli_value(value)}"])["k"] == value


def test_a_typo_fails_before_anything_starts(tmp_path):
    spec = write_spec(tmp_path / "typo.yaml", methods=[{"algo": "refpo", "overrides": {"algorithm.reflow_coeff": 0.1}}])
    sweep = load_sweep(str(spec), [f"out={tmp_path / 'out'}"])
    with pytest.raises(ConfigError, match=r"gridworld/refpo/seed1.*Did you mean 'algorithm.reflow_coef'"):
        run_sweep(sweep, echo=lambda line: None)
    assert not (tmp_path / "out").exists()
    with pytest.raises(ConfigError, match="Did you mean 'refpo'"):
        load_sweep(str(write_spec(tmp_path / "algo.yaml", methods=[{"algo": "refp"}])))
    with pytest.raises(ConfigError, match="'seed=' is spelled 'seeds='"):
        load_sweep(str(spec), ["seed=3"])
    if not torch.cuda.is_available():  # a CUDA sweep validates anywhere but trains only with a GPU
        cuda_spec = write_spec(tmp_path / "cuda.yaml", device="cuda", methods=[{"algo": "ppo"}])
        cuda = load_sweep(str(cuda_spec), [f"out={tmp_path / 'cuda'}"])
        lines: list[str] = []
        run_sweep(cuda, dry_run=True, echo=lines.append)
        assert "1 new" in lines[1]
        with pytest.raises(ConfigError, match="no CUDA device is available"):
            run_sweep(cuda, echo=lambda line: None)
        assert not (tmp_path / "cuda").exists()


def test_named_sweeps_resolve():
    paper = load_sweep("paper_dmc")
    assert len(paper.tasks) == 10 and paper.seeds == [1, 2, 3, 4, 5] and paper.device == "cuda"
    assert [m.label for m in paper.methods] == [
        "ppo",
        "fpo",
        "refpo",
        "refpo_l0.02",
        "refpo_l0.08",
        "refpo_l0.12",
        "refpo_aw",
        "flow_grpo",
        "reinflow",
    ]
    assert len(validate(paper)) == 450
    cfg = resolve_config(parse_overrides([*paper.runs[2].args, "device=cuda"]), device_type="cuda")
    assert (cfg["num_envs"], cfg["total_env_steps"], cfg["algorithm"]["reflow_coef"]) == (2048, 100_000_000, 0.04)
    cpu = load_sweep("cpu_dmc")
    assert len(cpu.tasks) >= 3 and all(t.startswith("dmc_") for t in cpu.tasks) and cpu.seeds == [1, 2, 3, 21, 22]
    assert [(m.label, m.algo) for m in cpu.methods] == [("ppo", "ppo"), ("fpo", "fpo"), ("refpo", "refpo")]
    assert cpu.methods[2].overrides == {"algorithm.reflow_coef": 0.04} and cpu.device == "cpu"
    assert len(validate(cpu)) == len(cpu.tasks) * 3 * 5


def test_fingerprint_ignores_options_that_do_not_change_the_run():
    cfg = resolve_config(parse_overrides(["task=gridworld", "algo=refpo"]), device_type="cpu")
    same = {**cfg, "verbose": not cfg["verbose"], "run_dir": "/elsewhere", "device": "cuda:1", "resume": "x"}
    assert fingerprint(same) == fingerprint(cfg) == fingerprint({**cfg, "torch_threads": 2})
    assert fingerprint({**cfg, "seed": cfg["seed"] + 1}) != fingerprint(cfg)


def test_sweep_runs_skips_finished_and_keeps_a_non_finite_failure(tmp_path):
    spec = write_spec(
        tmp_path / "tiny.yaml",
        overrides=TINY,
        methods=[
            {"label": "ppo", "algo": "ppo"},
            {"label": "refpo", "algo": "refpo"},
            # Resolves (every value is within its option's range), then really fails at run time: a 1e6 output scale and
            # a unit learning rate send the log-ratio to its clip of 100, whose exp overflows float32 (exit 3).
            {
                "label": "broken",
                "algo": "fpo",
                "overrides": {
                    "algorithm.learning_rate": 1.0,
                    "actor.output_scale": 1.0e6,
                    "algorithm.log_ratio_clip": 100.0,
                },
            },
        ],
    )
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "sweep.py"), str(spec), f"out={out}", "--jobs", "2"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
        check=False,
    )
    text = result.stdout
    assert result.returncode == 1, text + result.stderr
    broken = out / "gridworld" / "broken" / "seed1"
    assert "FAILED gridworld/broken/seed1 (attempt 1, exit 3" in text and f"log: {broken / 'train.log'}" in text
    # A non-finite loss is the run's outcome: not retried (a retry repeats it), its files kept as it stopped.
    assert "not retrying gridworld/broken/seed1: a non-finite loss" in text and "(attempt 2" not in text
    stopped = json.loads((broken / "stopped.json").read_text())
    assert stopped["reason"] == "non-finite loss" and "Non-finite" in stopped["error"]
    assert "finished 2 run(s), skipped 0 already done, failed 1" in text
    assert "failed gridworld/broken/seed1: exit 3, 1 attempt(s)" in text
    assert "Non-finite" in (broken / "train.log").read_text() and not (broken / "train.attempt1.log").exists()
    assert (broken / "config.yaml").exists()  # it stops in its first update, before any progress row
    status = json.loads((out / "status.json").read_text())
    assert status["gridworld/broken/seed1"]["state"] == "failed"
    assert status["gridworld/broken/seed1"]["exit_codes"] == [3]
    progress = [line for line in text.splitlines() if line.startswith("[sweep ")]
    assert progress[0].startswith("[sweep 1/3] done gridworld/")
    assert "ETA" in text
    for label in ("ppo", "refpo"):
        report = json.loads((out / "gridworld" / label / "seed1" / "eval.json").read_text())
        assert (report["task"], report["algo"]) == ("gridworld", label)
    spec_file = yaml.safe_load((out / "sweep.yaml").read_text())
    assert [r["run_dir"] for r in spec_file["runs"]] == [f"gridworld/{m}/seed1" for m in ("broken", "ppo", "refpo")]

    # Again (in-process, same executor): the finished runs are skipped, nothing is launched or rewritten.
    evals = {label: out / "gridworld" / label / "seed1" / "eval.json" for label in ("ppo", "refpo")}
    stamps = {label: path.stat().st_mtime_ns for label, path in evals.items()}
    lines: list[str] = []
    summary = run_sweep(load_sweep(str(spec), [f"out={out}", "methods=[ppo,refpo]"]), jobs=2, echo=lines.append)
    assert summary.ok and summary.skipped == ["gridworld/ppo/seed1", "gridworld/refpo/seed1"] and not summary.finished
    assert "2 done (skipped)" in "\n".join(lines)
    assert {label: path.stat().st_mtime_ns for label, path in evals.items()} == stamps

    # A changed config makes a finished run stale (rerun); a run without its eval.json is continued from its checkpoint.
    evals["refpo"].unlink()
    lines.clear()
    run_sweep(
        load_sweep(str(spec), [f"out={out}", "methods=[ppo,refpo]", "eval.num_envs=3"]), dry_run=True, echo=lines.append
    )
    assert "2 stale: config changed (rerun from scratch)" in lines[1]
    lines.clear()
    run_sweep(load_sweep(str(spec), [f"out={out}", "methods=[ppo,refpo]"]), dry_run=True, echo=lines.append)
    assert "1 done (skipped), 1 paused (continued from its newest checkpoint)" in lines[1]

    # A later invocation keeps the stopped run as it is: listed as failed, nothing launched, its files untouched.
    files = {p.name: p.stat().st_mtime_ns for p in broken.iterdir()}
    lines.clear()
    summary = run_sweep(load_sweep(str(spec), [f"out={out}", "methods=[broken]"]), jobs=1, echo=lines.append)
    assert "1 stopped by a non-finite loss (kept, not trained again)" in lines[1], lines
    assert [key for key, _ in summary.failed] == ["gridworld/broken/seed1"] and not summary.finished
    assert {p.name: p.stat().st_mtime_ns for p in broken.iterdir()} == files

    # The report lists the crashed run as missing, with its log.
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "report.py"), str(out)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    report = (out / "report" / "report.md").read_text()
    assert "| ppo | 1/1 |" in report and "| broken | 0/1 | -- | -- | -- | -- |" in report
    assert f"- gridworld / broken / seed 1: failed: exit codes [3]; log {broken / 'train.log'}" in report
    assert "- gridworld / refpo / seed 1: missing" in report


def test_a_run_in_pieces_is_paused_then_continued_and_ends_as_one_uncut_run(tmp_path):
    """stop_after_iterations=1 ends each sweep call's piece after an iteration: the first call leaves the run paused
    (reported, not failed), the second continues it from its checkpoint to the end, bit-identical to the same run
    trained in one sweep call."""
    spec = write_spec(tmp_path / "tiny.yaml", overrides=TINY, methods=[{"label": "refpo", "algo": "refpo"}])
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    assert run_sweep(load_sweep(str(spec), [f"out={whole}"]), jobs=1, echo=lambda _: None).ok
    lines: list[str] = []
    first = run_sweep(load_sweep(str(spec), [f"out={cut}", "stop_after_iterations=1"]), jobs=1, echo=lines.append)
    run_dir = cut / "gridworld" / "refpo" / "seed1"
    assert first.paused == ["gridworld/refpo/seed1"] and not first.failed and not first.finished, lines
    text = "\n".join(lines)
    assert "] paused gridworld/refpo/seed1 after" in text and "paused 1 (run the sweep again" in text
    assert not (run_dir / "eval.json").exists() and (run_dir / "model_0.pt").exists()
    assert json.loads((cut / "status.json").read_text())["gridworld/refpo/seed1"]["state"] == "paused"
    lines.clear()
    second = run_sweep(load_sweep(str(spec), [f"out={cut}", "stop_after_iterations=1"]), jobs=1, echo=lines.append)
    assert "1 paused (continued from its newest checkpoint)" in lines[1]
    assert second.finished == ["gridworld/refpo/seed1"] and second.ok, lines
    log = (run_dir / "train.log").read_text()
    assert log.count("continued from its newest checkpoint") == 1 and "resume=true" in log
    ends = [torch.load(d / "gridworld" / "refpo" / "seed1" / "model_1.pt", weights_only=True) for d in (whole, cut)]
    for name in ("actor_state_dict", "critic_state_dict"):
        for key, value in ends[0][name].items():
            assert torch.equal(value, ends[1][name][key]), f"{name}.{key}"
    results = [
        json.loads((d / "gridworld" / "refpo" / "seed1" / "eval.json").read_text())["results"] for d in (whole, cut)
    ]
    assert results[0] == results[1]
