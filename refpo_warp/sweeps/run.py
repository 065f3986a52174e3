"""Run a sweep: every run of the grid as its own ``tools/train.py`` process, several at a time, resumable.

- A run whose ``eval.json`` exists and whose ``config.yaml`` is the run's current config is skipped.
- A run that is unfinished (interrupted earlier) or stale (its config changed) is trained again from scratch; only
  its log files are kept. Runs are short enough that a clean rerun is cheaper than reasoning about a resumed one.
- A run that exits non-zero is reported with its log and retried once from scratch (``retries``).
- The sweep dir holds ``sweep.yaml`` (the resolved spec: methods, runs, their arguments and config fingerprints,
  merged over earlier invocations) and ``status.json`` (per run: state, attempts, exit codes, seconds, log).
"""

from __future__ import annotations

import fcntl
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from refpo_warp.config.yaml_files import dump_config, load_yaml
from refpo_warp.sweeps.spec import Run, Sweep, device_type, fingerprint, validate
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT, TOOLS_DIR

SPEC_FILE = "sweep.yaml"
STATUS_FILE = "status.json"
LOG_FILE = "train.log"


def run_state(run: Run, expected: str) -> str:
    """``done`` (eval.json of this config), ``stale`` (another config), ``unfinished`` or ``new``."""
    config = run.run_dir / "config.yaml"
    if not config.exists():
        return "unfinished" if run.run_dir.exists() and _not_logs(run.run_dir) else "new"
    try:
        if fingerprint(load_yaml(config)) != expected:
            return "stale"
        report = json.loads((run.run_dir / "eval.json").read_text())
    except (OSError, ValueError, ConfigError, yaml.YAMLError):
        return "unfinished"
    return "done" if report.get("task") == run.task and report.get("algo") == run.method.algo else "unfinished"


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


def _write_atomic(text: str, path: Path) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def write_spec(sweep: Sweep, prints: dict[str, str]) -> Path:
    """Write ``<sweep dir>/sweep.yaml``, merged with an existing one (union of methods and runs, ours win)."""
    path = sweep.out_dir / SPEC_FILE
    old = load_yaml(path) if path.exists() else {}
    methods = {m["label"]: m for m in old.get("methods", [])}
    methods.update({m.label: {"label": m.label, "name": m.name, "algo": m.algo, "overrides": m.overrides}
                    for m in sweep.methods})  # fmt: skip
    runs = {r["run_dir"]: r for r in old.get("runs", [])}
    for run in sweep.runs:
        rel = str(run.run_dir.relative_to(sweep.out_dir))
        runs[rel] = {"task": run.task, "label": run.method.label, "algo": run.method.algo, "seed": run.seed,
                     "run_dir": rel, "args": list(run.args), "fingerprint": prints[run.key]}  # fmt: skip
    spec = {
        "name": sweep.name, "source": sweep.source, "description": sweep.description, "device": sweep.device,
        "tasks": list(dict.fromkeys(old.get("tasks", []) + sweep.tasks)),
        "seeds": sorted(set(old.get("seeds", [])) | set(sweep.seeds)),
        "methods": list(methods.values()), "report": {**old.get("report", {}), **sweep.report},
        "runs": sorted(runs.values(), key=lambda r: (r["seed"], r["task"], r["label"])),
    }  # fmt: skip
    dump_config(json.loads(json.dumps(spec)), path)  # a plain copy: no YAML anchors for shared lists
    return path


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    return f"{h}h{rest // 60:02d}m" if h else f"{rest // 60}m{rest % 60:02d}s"


@dataclass
class Job:
    run: Run
    attempt: int
    slot: int
    proc: subprocess.Popen
    started: float
    log: Path


@dataclass
class Summary:
    total: int
    skipped: list[str] = field(default_factory=list)
    finished: list[str] = field(default_factory=list)
    failed: list[tuple[str, str]] = field(default_factory=list)  # (run key, why + log)
    interrupted: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failed and not self.interrupted


class SweepExecutor:
    """Launches the runs (``jobs`` at a time), retries failures, prints progress and writes ``status.json``."""

    def __init__(self, sweep: Sweep, jobs: int, retries: int = 1, launcher: str = "", echo=print) -> None:
        self.sweep, self.jobs, self.retries, self.echo = sweep, max(1, jobs), retries, echo
        self.launcher = shlex.split(launcher)
        self.gpus = cuda_devices(sweep)
        status_path = sweep.out_dir / STATUS_FILE
        self.status: dict[str, dict] = json.loads(status_path.read_text()) if status_path.exists() else {}
        self.durations: dict[str, float] = {}

    # ------------------------------------------------------------------------------------------------ launching
    def _device(self, slot: int) -> str:
        if not self.gpus:
            return self.sweep.device if self.sweep.device != "auto" else "cpu"
        return self.sweep.device if ":" in self.sweep.device else f"cuda:{slot % self.gpus}"

    def _start(self, run: Run, attempt: int, slot: int) -> Job:
        clear_run_dir(run.run_dir)
        run.run_dir.mkdir(parents=True, exist_ok=True)
        log = run.run_dir / LOG_FILE
        cmd = [*self.launcher, sys.executable, str(TOOLS_DIR / "train.py"), *run.args,
               f"device={self._device(slot)}"]  # fmt: skip
        env = dict(os.environ, PYTHONUNBUFFERED="1", PYTHONPATH=os.pathsep.join(
            [str(REPO_ROOT)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else [])))  # fmt: skip
        if not self.gpus:  # one thread per run: the sweep runs several at once
            env.update(OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
        with open(log, "w") as f:
            f.write(f"# sweep {self.sweep.name}, attempt {attempt}: {shlex.join(cmd)}\n")
            f.flush()
            proc = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, cwd=os.getcwd(), env=env)
        return Job(run, attempt, slot, proc, time.monotonic(), log)

    # ------------------------------------------------------------------------------------------------ reporting
    def _record(self, run: Run, **values) -> None:
        entry = self.status.setdefault(run.key, {})
        entry.update(values)
        _write_atomic(json.dumps(self.status, indent=2), self.sweep.out_dir / STATUS_FILE)

    def _eta(self, queue: deque, running: list[Job]) -> float | None:
        if not self.durations:
            return None
        mean = sum(self.durations.values()) / len(self.durations)

        def estimate(run: Run) -> float:
            same = [d for k, d in self.durations.items() if k.split("/")[:2] == run.key.split("/")[:2]]
            same = same or [d for k, d in self.durations.items() if k.split("/")[0] == run.task]
            return sum(same) / len(same) if same else mean

        now = time.monotonic()
        work = sum(estimate(r) for r, _ in queue) + sum(max(0.0, estimate(j.run) - (now - j.started)) for j in running)
        return work / self.jobs

    @staticmethod
    def _last_error(log: Path) -> str:
        lines = [ln.strip() for ln in log.read_text(errors="replace").splitlines() if ln.strip()]
        errors = [ln for ln in lines if ln.startswith("error:") or "Error" in ln.split(":")[0]]
        return (errors or lines or ["(empty log)"])[-1][:200]

    def _returns(self, run: Run) -> str:
        try:
            results = json.loads((run.run_dir / "eval.json").read_text())["results"]
        except (OSError, ValueError, KeyError):
            return ""
        return "  ".join(f"{k} {v['return_mean']:.1f}" for k, v in results.items() if "return_mean" in v)

    # ------------------------------------------------------------------------------------------------ main loop
    def execute(self, todo: list[Run], prints: dict[str, str], skipped: list[Run]) -> Summary:
        summary = Summary(total=len(todo) + len(skipped), skipped=[r.key for r in skipped])
        for run in skipped:
            self._record(run, state="done")
        queue: deque[tuple[Run, int]] = deque((run, 1) for run in todo)
        running: list[Job] = []
        start = time.monotonic()
        done_count = 0
        try:
            while queue or running:
                while queue and len(running) < self.jobs:
                    run, attempt = queue.popleft()
                    slot = min(set(range(self.jobs)) - {j.slot for j in running})
                    running.append(self._start(run, attempt, slot))
                    self._record(run, state="running", attempts=attempt, log=str(run.run_dir / LOG_FILE))
                time.sleep(0.2)
                for job in [j for j in running if j.proc.poll() is not None]:
                    running.remove(job)
                    seconds = time.monotonic() - job.started
                    rc = job.proc.returncode
                    codes = self.status.get(job.run.key, {}).get("exit_codes", []) if job.attempt > 1 else []
                    finished = rc == 0 and run_state(job.run, prints[job.run.key]) == "done"
                    self._record(job.run, exit_codes=codes + [rc], seconds=round(seconds, 1))
                    if finished:
                        done_count += 1
                        self.durations[job.run.key] = seconds
                        summary.finished.append(job.run.key)
                        self._record(job.run, state="done")
                        eta = self._eta(queue, running)
                        self.echo(f"[sweep {done_count}/{len(todo)}] done {job.run.key} in {_duration(seconds)}  "
                                  f"{self._returns(job.run)} | running {len(running)}, queued {len(queue)} | "
                                  f"elapsed {_duration(time.monotonic() - start)}"
                                  + (f", ETA {_duration(eta)}" if eta is not None else ""))  # fmt: skip
                        continue
                    why = f"exit {rc}" if rc else "exit 0 without a matching eval.json"
                    self.echo(f"[sweep] FAILED {job.run.key} (attempt {job.attempt}, {why}, {_duration(seconds)}): "
                              f"{self._last_error(job.log)}\n        log: {job.log}")  # fmt: skip
                    if job.attempt <= self.retries:
                        self.echo(f"[sweep] retrying {job.run.key} from scratch (attempt {job.attempt + 1})")
                        queue.appendleft((job.run, job.attempt + 1))
                    else:
                        done_count += 1
                        earlier = " (earlier attempts: train.attempt*.log beside it)" if job.attempt > 1 else ""
                        summary.failed.append((job.run.key, f"{why}, {job.attempt} attempt(s); log {job.log}{earlier}"))
                        self._record(job.run, state="failed")
        except KeyboardInterrupt:
            self.echo(f"[sweep] interrupted: stopping {len(running)} running run(s)")
            for job in running:
                if job.proc.poll() is None:
                    job.proc.send_signal(signal.SIGINT)
            for job in running:
                try:
                    job.proc.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    job.proc.kill()
                    job.proc.wait()
                summary.interrupted.append(job.run.key)
                self._record(job.run, state="interrupted")
        return summary


def cuda_devices(sweep: Sweep) -> int:
    """GPUs the sweep's runs share (0 for a CPU sweep); a CUDA sweep without a GPU is an error."""
    if device_type(sweep.device) != "cuda":
        return 0
    import torch

    if not torch.cuda.device_count():
        raise ConfigError(f"Sweep '{sweep.name}' trains on CUDA (device: {sweep.device}) but no CUDA device is "
                          "available here (--dry-run validates it without training)")  # fmt: skip
    return torch.cuda.device_count()


def plan(sweep: Sweep, prints: dict[str, str]) -> tuple[list[Run], list[Run], dict[str, list[str]]]:
    """(runs to train, runs already done, run keys per state) for the current state of the sweep dir."""
    states: dict[str, list[str]] = {}
    todo, done = [], []
    for run in sweep.runs:
        state = run_state(run, prints[run.key])
        states.setdefault(state, []).append(run.key)
        (done if state == "done" else todo).append(run)
    return todo, done, states


class SweepLock:
    """One sweep process per sweep dir: a second one would clear the first one's run dirs."""

    def __init__(self, out_dir: Path) -> None:
        out_dir.mkdir(parents=True, exist_ok=True)
        self.file = open(out_dir / ".lock", "w")
        try:
            fcntl.flock(self.file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError as err:
            self.file.close()
            raise ConfigError(f"Another sweep is running in {out_dir} (lock {out_dir / '.lock'})") from err

    def release(self) -> None:
        fcntl.flock(self.file, fcntl.LOCK_UN)
        self.file.close()


def run_sweep(sweep: Sweep, jobs: int | None = None, retries: int = 1, launcher: str = "", dry_run: bool = False,
              echo=print) -> Summary:  # fmt: skip
    """Validate the whole grid, then train what is not done yet; returns what finished, was skipped or failed."""
    prints = validate(sweep)
    gpus = 0 if dry_run else cuda_devices(sweep)
    if jobs is None:  # one run per GPU, or one per CPU core (one torch thread each)
        jobs = gpus or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))
    shape = f"{len(sweep.tasks)} task(s) x {len(sweep.methods)} method(s) x {len(sweep.seeds)} seed(s)"
    echo(f"[sweep] {sweep.name}: {len(sweep.runs)} runs ({shape}) in {sweep.out_dir}; every config resolves")
    words = {"done": "done (skipped)", "new": "new", "unfinished": "unfinished (rerun from scratch)",
             "stale": "stale: config changed (rerun from scratch)"}  # fmt: skip
    if dry_run:
        todo, done, states = plan(sweep, prints)
        echo("[sweep] " + ", ".join(f"{len(v)} {words[k]}" for k, v in states.items()))
        for run in sweep.runs:
            state = next(k for k, v in states.items() if run.key in v)
            echo(f"  {state:10s} {run.key}: python tools/train.py {shlex.join(run.args)}")
        return Summary(total=len(sweep.runs), skipped=[r.key for r in done])
    lock = SweepLock(sweep.out_dir)
    try:
        todo, done, states = plan(sweep, prints)
        echo("[sweep] " + ", ".join(f"{len(v)} {words[k]}" for k, v in states.items())
             + f"; {jobs} at a time on {sweep.device}")  # fmt: skip
        write_spec(sweep, prints)
        executor = SweepExecutor(sweep, jobs, retries, launcher, echo)
        summary = executor.execute(todo, prints, done)
    finally:
        lock.release()
    echo(f"[sweep] finished {len(summary.finished)} run(s), skipped {len(summary.skipped)} already done, "
         f"failed {len(summary.failed)}" + (f", interrupted {len(summary.interrupted)}" if summary.interrupted else ""))
    for key, why in summary.failed:
        echo(f"  failed {key}: {why}")
    for key in summary.interrupted:
        echo(f"  interrupted {key} (rerun the sweep to train it again)")
    echo(f"[sweep] report: python tools/report.py {sweep.out_dir}")
    return summary
