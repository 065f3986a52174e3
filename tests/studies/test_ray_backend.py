"""The Ray backend of a sweep (``--backend ray``) on a real local Ray, started once for the module with 2 CPUs and 2
declared GPUs: runs see their own GPU, a crash is retried with its first log kept, a killed worker is re-run by Ray
without using the run's retry, finished runs are skipped, ``status.json`` matches the local backend's, a node that
lacks the working directory stops the sweep before anything starts, Ctrl-C leaves no training process behind, and one
real tiny ``refpo train`` run. The training command is the stand-in ``stand_in_train.py`` where speed demands it (the
real command line, with it in front: ``--launcher``)."""

import csv
import itertools
import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import ray
import yaml

from refpo_warp.config.dotted import parse_overrides
from refpo_warp.studies.grid.launch import STOP_GRACE_S
from refpo_warp.studies.grid.spec import load_sweep
from refpo_warp.studies.ray import backend as ray_backend
from refpo_warp.studies.ray.backend import RayOptions
from refpo_warp.studies.sweep import run_sweep
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT

STAND_IN = f"{sys.executable} {Path(__file__).with_name('stand_in_train.py')}"
RAY_ENV = {"RAY_AUTH_MODE": "disabled", "RAY_USAGE_STATS_ENABLED": "0"}  # no token under ~/.ray, no statistics


@pytest.fixture(scope="module")
def local_ray():
    with pytest.MonkeyPatch.context() as mp:
        for key, value in RAY_ENV.items():
            mp.setenv(key, value)
        # "local": a new Ray, never one found through RAY_ADDRESS or /tmp/ray (the other xdist worker's, a cluster's)
        ray.init(address="local", num_cpus=2, num_gpus=2, include_dashboard=False)
        try:
            yield ray.get_runtime_context().get_node_id()
        finally:
            ray.shutdown()


def write_spec(path: Path, **spec) -> Path:
    path.write_text(yaml.safe_dump({"device": "cpu", "tasks": ["gridworld"], "seeds": [1], **spec}))
    return path


def records(out: Path) -> list[dict]:
    path = out / "stand_in.jsonl"
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def test_runs_get_their_own_gpu_a_crash_is_retried_and_a_lost_worker_rerun(local_ray, tmp_path):
    spec = write_spec(
        tmp_path / "grid.yaml",
        device="cuda",
        methods=[
            {"label": "ppo", "algo": "ppo"},
            {"label": "refpo", "algo": "refpo"},
            {"label": "crash", "algo": "ppo"},
            {"label": "lost", "algo": "ppo"},
        ],
    )
    out = tmp_path / "out"
    lines: list[str] = []
    summary = run_sweep(load_sweep(str(spec), [f"out={out}"]), launcher=STAND_IN, backend="ray", echo=lines.append)
    text = "\n".join(lines)
    assert summary.ok and len(summary.finished) == 4, text
    assert "2 at a time on Ray (1 node(s), room for 2 run(s) at 1 GPU and 1 CPU each)" in text
    seen = records(out)
    starts = [r for r in seen if r["event"] == "start"]
    assert {r["device"] for r in starts} == {"cuda:0"} and {r["cuda_visible_devices"] for r in starts} == {"0", "1"}
    # Runs that overlapped in time had different GPUs; the 2 slots overlap at least once (so this checks something).
    spans = [(r["start"], r["time"], r["cuda_visible_devices"]) for r in seen if r["event"] == "end"]
    overlapping = [(a, b) for a, b in itertools.combinations(spans, 2) if a[0] < b[1] and b[0] < a[1]]
    assert overlapping and all(a[2] != b[2] for a, b in overlapping)

    status = json.loads((out / "status.json").read_text())
    assert {s["node"] for s in status.values()} == {socket.gethostname()}
    assert {s["ray_node_id"] for s in status.values()} == {local_ray}
    crash = out / "gridworld" / "crash" / "seed1"
    assert "FAILED gridworld/crash/seed1 (attempt 1, exit 1" in text and f"log: {crash / 'train.log'}" in text
    assert "retrying gridworld/crash/seed1 from scratch (attempt 2)" in text
    assert (status["gridworld/crash/seed1"]["attempts"], status["gridworld/crash/seed1"]["exit_codes"]) == (2, [1, 0])
    assert "stand-in crash" in (crash / "train.attempt1.log").read_text()
    assert "attempt 2 on" in (crash / "train.log").read_text().splitlines()[0]

    # The stand-in killed its worker (SIGKILL) on the first execution: Ray ran the task again, on another worker,
    # and the sweep counts no retry of its own; the orphaned first process died with its worker.
    lost = status["gridworld/lost/seed1"]
    assert (lost["state"], lost["attempts"], lost["exit_codes"], lost["ray_reruns"]) == ("done", 1, [0], 1)
    first, second = [r for r in starts if r["key"] == "gridworld/lost/seed1"]
    assert first["ppid"] != second["ppid"] and not alive(first["pid"]) and not alive(first["ppid"])
    logs = out / "gridworld" / "lost" / "seed1"
    header = (logs / "train.log").read_text().splitlines()[0]
    assert "(Ray task " in header and header == (logs / "train.attempt1.log").read_text().splitlines()[0]
    assert "gridworld/lost/seed1 was re-run by Ray 1 time(s) after a lost worker or node" in text
    assert "[sweep 4/4] done" in text and "ETA" in text and " on " + socket.gethostname() in text

    # Again: every run is done, nothing is launched.
    lines.clear()
    again = run_sweep(load_sweep(str(spec), [f"out={out}"]), launcher=STAND_IN, backend="ray", echo=lines.append)
    assert again.ok and len(again.skipped) == 4 and not again.finished
    assert "4 done (skipped)" in "\n".join(lines) and records(out) == seen


def test_status_agrees_with_the_local_backend(local_ray, tmp_path):
    methods = [{"label": "ppo", "algo": "ppo"}, {"label": "crash", "algo": "fpo"}]
    spec = write_spec(tmp_path / "grid.yaml", methods=methods)
    status = {}
    for backend in ("local", "ray"):
        out = tmp_path / backend
        summary = run_sweep(
            load_sweep(str(spec), [f"out={out}"]), jobs=2, launcher=STAND_IN, backend=backend, echo=lambda line: None
        )
        assert summary.ok and len(summary.finished) == 2
        status[backend] = json.loads((out / "status.json").read_text())
        starts = [r for r in records(out) if r["event"] == "start"]
        assert len(starts) == 3 and {(r["device"], r["omp_num_threads"]) for r in starts} == {("cpu", "1")}
    local, on_ray = status["local"], status["ray"]
    assert sorted(local) == sorted(on_ray) and len(local) == 2
    for key, entry in local.items():
        other = on_ray[key]
        assert set(other) - set(entry) == {"ray_node_id", "ray_reruns"} and set(entry) <= set(other)
        assert {k: v for k, v in entry.items() if k not in ("seconds", "log")} == {
            k: v for k, v in other.items() if k in entry and k not in ("seconds", "log")
        }
        assert Path(entry["log"]).relative_to(tmp_path / "local") == Path(other["log"]).relative_to(tmp_path / "ray")
        assert entry["seconds"] > 0 and other["seconds"] > 0
    assert local["gridworld/crash/seed1"]["exit_codes"] == [1, 0] and local["gridworld/ppo/seed1"]["node"]


def test_a_node_without_the_working_directory_stops_the_sweep_before_it_starts(local_ray, tmp_path, monkeypatch):
    spec = write_spec(tmp_path / "grid.yaml", methods=[{"label": "ppo", "algo": "ppo"}])
    elsewhere = tmp_path / "not_shared"  # as the head sees it; the node (really) does not have it
    monkeypatch.setattr(ray_backend, "shared_paths", lambda: [str(elsewhere)])
    out = tmp_path / "out"
    node = rf"node {re.escape(socket.gethostname())} \(.*, node {local_ray[:8]}\)"
    missing = re.escape(str(elsewhere))
    with pytest.raises(ConfigError, match=rf"{node} does not see {missing}.*needs the package installed on every"):
        run_sweep(load_sweep(str(spec), [f"out={out}"]), launcher=STAND_IN, backend="ray", echo=lambda line: None)
    assert not records(out) and not (out / "status.json").exists() and not (out / ".ray_node_check").exists()


def test_ray_options_are_checked_and_ray_is_imported_only_when_asked_for(tmp_path):
    cpu = load_sweep(str(write_spec(tmp_path / "cpu.yaml", methods=[{"algo": "ppo"}])), [f"out={tmp_path / 'a'}"])
    cuda = load_sweep(
        str(write_spec(tmp_path / "cuda.yaml", device="cuda", methods=[{"algo": "ppo"}])), [f"out={tmp_path / 'b'}"]
    )
    quiet = {"echo": lambda line: None}
    for sweep, options, message in [
        (cpu, RayOptions(gpus_per_run=1), r"trains on the CPU \(device: cpu\): --gpus-per-run must be 0"),
        (cuda, RayOptions(gpus_per_run=0), r"trains on CUDA \(device: cuda\): --gpus-per-run must be above 0"),
        (cuda, RayOptions(gpus_per_run=1.5), r"--gpus-per-run must be a fraction of one \(e.g. 0.5\) or a whole"),
        (cpu, RayOptions(cpus_per_run=0), r"--cpus-per-run must be above 0"),
    ]:
        with pytest.raises(ConfigError, match=message):
            run_sweep(sweep, backend="ray", ray=options, **quiet)
    with pytest.raises(ConfigError, match=r"Unknown sweep backend 'rya'. Did you mean 'ray'\? Valid choices: local"):
        run_sweep(cpu, backend="rya", **quiet)
    with pytest.raises(ConfigError, match=r"need --backend ray"):
        run_sweep(cpu, ray=RayOptions(address="auto"), **quiet)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()

    # Without Ray installed: the local backend never imports it, the Ray backend says how to install it.
    script = f"""
import sys
sys.modules["ray"] = None  # as if Ray were not installed: `import ray` raises ImportError
import refpo_warp.studies.ray.node  # what a Ray worker imports to run a task: no torch (seconds per fresh worker)
print("TORCH", "torch" in sys.modules)
from refpo_warp.cli.main import main
local = main(["sweep", {str(tmp_path / "cpu.yaml")!r}, "out={tmp_path / "a"}", "--dry-run"])
flag = main(["sweep", {str(tmp_path / "cpu.yaml")!r}, "out={tmp_path / "a"}", "--cpus-per-run", "2", "--dry-run"])
ray = main(["sweep", {str(tmp_path / "cpu.yaml")!r}, "out={tmp_path / "a"}", "--backend", "ray"])
print("RESULT", local, flag, ray)
"""
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=REPO_ROOT, timeout=120, check=False
    )
    assert result.stdout.splitlines()[-1] == "RESULT 0 2 2", result.stdout + result.stderr
    assert "TORCH False" in result.stdout.splitlines()
    assert "Ray options (--ray-address, --gpus-per-run, --cpus-per-run) need --backend ray" in result.stderr
    assert 'error: --backend ray needs Ray, an optional extra of this project: pip install "refpo-warp[ray]"' in (
        result.stderr
    )
    # A head that is not there fails at once (ray.init would wait for it forever).
    with pytest.raises(ConfigError, match=r"No Ray cluster at '127.0.0.1:1' \(.*\): `ray start --head` prints"):
        ray_backend.check_reachable("127.0.0.1:1")


@pytest.mark.slow(minutes=1)
def test_ctrl_c_stops_every_run_and_leaves_no_training_process(tmp_path):
    """A terminal's Ctrl-C (SIGINT to the whole process group: the sweep and the local Ray it started) while two runs
    train and a third is queued: the runs stop, nothing is left running, the sweep exits 130. Each run gets SIGINT
    through Ray's cancel; on a busy machine a cancel can miss its task for the whole grace, and then the task is
    force-cancelled and its training process killed with it (both are the documented stop)."""
    spec = write_spec(tmp_path / "grid.yaml", seeds=[1, 2, 3], methods=[{"label": "sleepy", "algo": "ppo"}])
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-m",
        "refpo_warp",
        "sweep",
        str(spec),
        f"out={out}",
        "--backend",
        "ray",
        "--jobs",
        "2",
        "--launcher",
        STAND_IN,
    ]
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"} | RAY_ENV  # the sweep starts its own Ray
    proc = subprocess.Popen(
        cmd, cwd=REPO_ROOT, env=env, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    try:
        deadline = time.monotonic() + 120
        while len(records(out)) < 2 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.2)
        started = records(out)
        assert len(started) == 2, proc.communicate(timeout=60)[0] if proc.poll() is not None else "no run started"
        assert all(alive(r["pid"]) for r in started)
        stopped = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        text = proc.communicate(timeout=90)[0]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    took = time.monotonic() - stopped
    assert proc.returncode == 130, text
    assert took < STOP_GRACE_S + 30, text  # at the latest: the grace, then the force-cancel and Ray's shutdown
    assert "interrupted: stopping 2 running run(s)" in text and "interrupted 2" in text
    assert not any(alive(r["pid"]) for r in started) and len(records(out)) == 2  # the queued run never started
    status = json.loads((out / "status.json").read_text())
    assert sorted(k for k, v in status.items() if v["state"] == "interrupted") == [
        r["key"] for r in sorted(started, key=lambda r: r["key"])
    ]
    if took < STOP_GRACE_S:  # the cancel reached the tasks in time: each run got SIGINT, not the SIGKILL
        for r in started:
            assert "KeyboardInterrupt" in (out / r["key"].replace("/", os.sep) / "train.log").read_text()


@pytest.mark.slow(minutes=0.3)
def test_a_real_training_run_on_ray(local_ray, tmp_path, quick_run):
    overrides = parse_overrides([a for a in quick_run if a.split("=")[0] not in ("task", "algo", "device")])
    spec = write_spec(tmp_path / "grid.yaml", overrides=overrides, methods=[{"label": "refpo", "algo": "refpo"}])
    out = tmp_path / "out"
    lines: list[str] = []
    summary = run_sweep(load_sweep(str(spec), [f"out={out}"]), backend="ray", echo=lines.append)
    run_dir = out / "gridworld" / "refpo" / "seed1"
    log = (run_dir / "train.log").read_text()
    assert summary.ok and summary.finished == ["gridworld/refpo/seed1"], "\n".join(lines) + log
    assert f"{sys.executable} -m refpo_warp train task=gridworld algo=refpo seed=1" in log.splitlines()[0]
    assert log.splitlines()[0].endswith("device=cpu")
    report = json.loads((run_dir / "eval.json").read_text())
    assert (report["task"], report["algo"]) == ("gridworld", "refpo") and "N=1" in report["results"]
    assert json.loads((out / "status.json").read_text())["gridworld/refpo/seed1"]["ray_node_id"] == local_ray


@pytest.mark.slow(minutes=0.3)
def test_a_tuning_study_on_ray(local_ray, tmp_path):
    """refpo tune --backend ray: a trial's run is a Ray task under the same executor as a sweep's (status.json names
    its node), and the trial is scored from the run it trained."""
    from tiny_runs import TINY  # tests/studies/tiny_runs.py

    from refpo_warp.studies.tuning.spec import load_tuning
    from refpo_warp.studies.tuning.study import Tuner

    lr = {"algorithm.learning_rate": {"low": 1.0e-4, "high": 3.0e-3, "log": True}}
    spec = tmp_path / "tiny.yaml"
    spec.write_text(
        yaml.safe_dump(
            {
                "device": "cpu",
                "tasks": ["gridworld"],
                "trials": 1,
                "overrides": TINY,
                "pruner": None,
                "objective": {"metric": "return_multi", "reference": {"gridworld": 20.0}},
                "methods": [{"label": "ppo", "algo": "ppo", "space": lr}],
            }
        )
    )
    out = tmp_path / "out"
    lines: list[str] = []
    assert Tuner(load_tuning(str(spec), [f"out={out}"]), backend="ray", echo=lines.append).run(), "\n".join(lines)
    trial = out / "ppo" / "trial00"
    status = json.loads((trial / "status.json").read_text())["gridworld/ppo/seed101"]
    assert (status["state"], status["exit_codes"], status["ray_node_id"]) == ("done", [0], local_ray)
    header = (trial / "gridworld" / "train.log").read_text().splitlines()[0]
    assert header.startswith("# tune tiny, ppo trial 00, attempt 1 on ") and "(Ray task " in header
    rows = list(csv.DictReader((out / "trials.csv").open()))
    report = json.loads((trial / "gridworld" / "eval.json").read_text())
    assert [r["state"] for r in rows] == ["complete"]
    assert float(rows[0]["score"]) == pytest.approx(report["results"]["mean_action"]["return_mean"] / 20.0)
