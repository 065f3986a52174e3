"""What every backend shares: the queue of runs, ``jobs`` of them at a time, a failed run reported with its log and
retried from scratch (not one stopped on a non-finite loss: a retry repeats it, and its files are the result), one
progress line with the ETA per finished run, ``status.json`` kept up to date, and the summary. A backend is a
``Launcher``: it starts one run, reports the runs that ended and stops the others (``local.py``: subprocesses of this
machine; ``studies/ray/backend.py``: one Ray task per run). A sweep runs its whole grid through one executor; a tuning
study runs each trial's runs through one (``studies/tuning/study.py``), whose ``watch`` stops them early (a pruned or
failed trial).
"""

from __future__ import annotations

import json
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from refpo_warp.studies.grid.spec import Run, Sweep
from refpo_warp.studies.grid.state import LOG_FILE, STATUS_FILE, run_state
from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.errors import EXIT_NONFINITE

POLL_S = 0.2


def duration(seconds: float) -> str:
    seconds = round(seconds)
    h, rest = divmod(seconds, 3600)
    return f"{h}h{rest // 60:02d}m" if h else f"{rest // 60}m{rest % 60:02d}s"


@dataclass
class Outcome:
    """How one started run ended: its exit code (None when it never got one, e.g. its Ray node was lost for good),
    its seconds, the node (host name) it ran on, why it has no exit code, and backend fields for ``status.json``."""

    exit_code: int | None
    seconds: float
    node: str
    error: str = ""
    status: dict[str, Any] = field(default_factory=dict)


@dataclass
class Job:
    run: Run
    attempt: int
    slot: int
    handle: Any  # the backend's: a Popen, a Ray ObjectRef
    started: float

    @property
    def log(self) -> Path:
        return self.run.run_dir / LOG_FILE


@dataclass
class Summary:
    total: int
    skipped: list[str] = field(default_factory=list)
    finished: list[str] = field(default_factory=list)
    failed: list[tuple[str, str]] = field(default_factory=list)  # (run key, why + log)
    interrupted: list[str] = field(default_factory=list)
    paused: list[str] = field(default_factory=list)  # stopped at a piece's end (stop_after_*): a rerun continues them
    stopped: str = ""  # why ``watch`` stopped the runs left (their state in status.json: stopped)

    @property
    def ok(self) -> bool:
        return not self.failed and not self.interrupted and not self.stopped


class Launcher:
    """A backend: ``jobs`` runs at a time, ``where`` they run (for the plan line), and how to start, wait for and stop
    them. ``prepare`` runs once the sweep dir exists, ``close`` after the sweep (also after an error)."""

    jobs: int = 1
    where: str = ""
    names_nodes: bool = False  # the progress lines name the node of each run (a cluster)

    def prepare(self, sweep: Sweep) -> None:
        pass

    def start(self, run: Run, attempt: int, slot: int, origin: str) -> Any:
        """Start ``run``; ``origin`` heads its log (``sweep <name>``, ``tune <name>, <method> trial <k>``)."""
        raise NotImplementedError

    def wait(self, jobs: list[Job], timeout: float) -> list[tuple[Job, Outcome]]:
        """The jobs that ended within ``timeout`` seconds, each with its outcome."""
        raise NotImplementedError

    def stop(self, jobs: list[Job]) -> None:
        """Stop every job (Ctrl-C): queued ones never start, running ones get SIGINT and then SIGKILL."""
        raise NotImplementedError

    def close(self) -> None:
        pass


Watch = Callable[["Summary"], str]  # called after every poll: a reason to stop the runs left, or ""


class SweepExecutor:
    """Launches the runs (``launcher.jobs`` at a time), retries failures, prints progress and writes ``status.json``
    (in ``sweep.out_dir``). ``origin`` heads each run's log (default ``sweep <name>``), ``tag`` the progress lines."""

    def __init__(
        self, sweep: Sweep, launcher: Launcher, retries: int = 1, echo=print, origin: str = "", tag: str = "sweep"
    ) -> None:
        self.sweep, self.launcher, self.retries, self.echo = sweep, launcher, retries, echo
        self.origin, self.tag = origin or f"sweep {sweep.name}", tag
        self.jobs = max(1, launcher.jobs)
        sweep.out_dir.mkdir(parents=True, exist_ok=True)  # a Ray task makes its run dir only once it starts
        status_path = sweep.out_dir / STATUS_FILE
        self.status: dict[str, dict] = json.loads(status_path.read_text()) if status_path.exists() else {}
        self.durations: dict[str, float] = {}

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
        try:
            lines = [ln.strip() for ln in log.read_text(errors="replace").splitlines() if ln.strip()]
        except OSError:
            return "(no log)"
        errors = [ln for ln in lines if ln.startswith("error:") or "Error" in ln.split(":")[0]]
        return (errors or lines or ["(empty log)"])[-1][:200]

    def _returns(self, run: Run) -> str:
        try:
            results = json.loads((run.run_dir / "eval.json").read_text())["results"]
        except (OSError, ValueError, KeyError):
            return ""
        return "  ".join(f"{k} {v['return_mean']:.1f}" for k, v in results.items() if "return_mean" in v)

    # ------------------------------------------------------------------------------------------------ main loop
    def execute(
        self, todo: list[Run], prints: dict[str, str], kept: list[tuple[Run, str]], watch: Watch | None = None
    ) -> Summary:
        """Train ``todo`` (``prints``: each run's config fingerprint by key; ``kept``: runs not trained again, each
        with its state: ``done``, or ``failed`` when a non-finite loss stopped it). ``watch`` may stop the runs left:
        they are stopped as on Ctrl-C; the summary says why."""
        summary = Summary(total=len(todo) + len(kept))
        for run, state in kept:
            self._record(run, state=state)
            if state == "failed":
                summary.failed.append(
                    (run.key, f"stopped by a non-finite loss earlier, kept; log {run.run_dir / LOG_FILE}")
                )
            else:
                summary.skipped.append(run.key)
        queue: deque[tuple[Run, int]] = deque((run, 1) for run in todo)
        running: list[Job] = []
        start = time.monotonic()
        done_count = 0
        try:
            while queue or running:
                while queue and len(running) < self.jobs:
                    run, attempt = queue.popleft()
                    slot = min(set(range(self.jobs)) - {j.slot for j in running})
                    running.append(
                        Job(run, attempt, slot, self.launcher.start(run, attempt, slot, self.origin), time.monotonic())
                    )
                    self._record(run, state="running", attempts=attempt, log=str(run.run_dir / LOG_FILE))
                for job, out in self.launcher.wait(running, POLL_S):
                    running.remove(job)
                    rc = out.exit_code
                    codes = self.status.get(job.run.key, {}).get("exit_codes", []) if job.attempt > 1 else []
                    state = run_state(job.run, prints[job.run.key]) if rc == 0 else "failed"
                    finished = state == "done"
                    self._record(
                        job.run, exit_codes=codes + [rc], seconds=round(out.seconds, 1), node=out.node, **out.status
                    )
                    where = f" on {out.node}" if self.launcher.names_nodes else ""
                    if finished:
                        done_count += 1
                        self.durations[job.run.key] = out.seconds
                        summary.finished.append(job.run.key)
                        self._record(job.run, state="done")
                        eta = self._eta(queue, running)
                        self.echo(
                            f"[{self.tag} {done_count}/{len(todo)}] done {job.run.key} in {duration(out.seconds)}"
                            f"{where}  {self._returns(job.run)} | running {len(running)}, queued {len(queue)} | "
                            f"elapsed {duration(time.monotonic() - start)}"
                            + (f", ETA {duration(eta)}" if eta is not None else "")
                        )
                        continue
                    if state == "paused":  # the run ended its piece (stop_after_iterations / _minutes) as asked
                        done_count += 1
                        summary.paused.append(job.run.key)
                        self._record(job.run, state="paused")
                        self.echo(
                            f"[{self.tag} {done_count}/{len(todo)}] paused {job.run.key} after {duration(out.seconds)}"
                            f"{where} at its newest checkpoint: the sweep run again continues it"
                        )
                        continue
                    why = out.error or (f"exit {rc}" if rc else "exit 0 without a matching eval.json")
                    self.echo(
                        f"[{self.tag}] FAILED {job.run.key} (attempt {job.attempt}, {why}, {duration(out.seconds)}"
                        f"{where}): {self._last_error(job.log)}\n        log: {job.log}"
                    )
                    if rc == EXIT_NONFINITE:  # a result, not an accident: kept as it stopped, not retried
                        self.echo(
                            f"[{self.tag}] not retrying {job.run.key}: a non-finite loss is the run's outcome (a "
                            "retry repeats it); it is kept as it stopped, by this sweep and the next"
                        )
                    elif job.attempt <= self.retries:
                        self.echo(f"[{self.tag}] retrying {job.run.key} from scratch (attempt {job.attempt + 1})")
                        queue.appendleft((job.run.from_scratch(), job.attempt + 1))
                        continue
                    done_count += 1
                    earlier = " (earlier attempts: train.attempt*.log beside it)" if job.attempt > 1 else ""
                    summary.failed.append((job.run.key, f"{why}, {job.attempt} attempt(s); log {job.log}{earlier}"))
                    self._record(job.run, state="failed")
                summary.stopped = watch(summary) if watch is not None else ""
                if summary.stopped:
                    self._stop(running, "stopped")
                    break
        except KeyboardInterrupt:
            self.echo(f"[{self.tag}] interrupted: stopping {len(running)} running run(s)")
            self._stop(running, "interrupted")
            summary.interrupted += [job.run.key for job in running]
        return summary

    def _stop(self, running: list[Job], state: str) -> None:
        self.launcher.stop(running)
        for job in running:
            self._record(job.run, state=state)
