"""The local backend of a sweep: ``jobs`` runs at a time as subprocesses of this machine (one per GPU, or one per CPU
core with one torch thread each), failed runs retried, a progress line with the ETA and ``status.json`` kept up to
date."""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

from refpo_warp.sweeps.spec import Run, Sweep, device_type
from refpo_warp.sweeps.state import LOG_FILE, STATUS_FILE, clear_run_dir, run_state
from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT, TOOLS_DIR


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
        write_text(self.sweep.out_dir / STATUS_FILE, json.dumps(self.status, indent=2))

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
