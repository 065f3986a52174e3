"""Run a sweep: every run of the grid as its own ``refpo train`` process, several at a time, resumable.

- A run whose ``eval.json`` exists and whose ``config.yaml`` is the run's current config is skipped.
- A run that is unfinished (interrupted earlier) or stale (its config changed) is trained again from scratch; only
  its log files are kept. Runs are short enough that a clean rerun is cheaper than reasoning about a resumed one.
- A run that exits non-zero is reported with its log and retried once from scratch (``retries``).
- The sweep dir holds ``sweep.yaml`` (the resolved spec: methods, runs, their arguments and config fingerprints,
  merged over earlier invocations) and ``status.json`` (per run: state, attempts, exit codes, seconds, node, log).
- Backends: ``local`` (subprocesses of this machine, ``local.py``) and ``ray`` (one Ray task per run on a cluster,
  ``ray_backend.py``); both run the same executor (``executor.py``) and the same training command (``launch.py``).
"""

from __future__ import annotations

import fcntl
import shlex
from pathlib import Path

from refpo_warp.sweeps.executor import Launcher, Summary, SweepExecutor
from refpo_warp.sweeps.local import LocalLauncher
from refpo_warp.sweeps.ray_backend import RayLauncher, RayOptions, run_resources  # Ray itself: only in RayLauncher
from refpo_warp.sweeps.spec import Sweep, validate
from refpo_warp.sweeps.state import plan, write_spec
from refpo_warp.utils.errors import ConfigError, unknown

BACKENDS = ("local", "ray")


class SweepLock:
    """One sweep process per sweep dir: a second one would clear the first one's run dirs."""

    def __init__(self, out_dir: Path) -> None:
        out_dir.mkdir(parents=True, exist_ok=True)
        self.file = open(out_dir / ".lock", "w")  # noqa: SIM115 (held open: the lock lasts while the file is open)
        try:
            fcntl.flock(self.file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError as err:
            self.file.close()
            raise ConfigError(f"Another sweep is running in {out_dir} (lock {out_dir / '.lock'})") from err

    def release(self) -> None:
        fcntl.flock(self.file, fcntl.LOCK_UN)
        self.file.close()


def make_launcher(
    backend: str, sweep: Sweep, jobs: int | None, launcher: str, ray: RayOptions | None, echo=print
) -> Launcher:
    """The backend's launcher; a CUDA sweep without a GPU, or a Ray cluster without room for a run, fails here."""
    if backend == "ray":
        return RayLauncher(sweep, ray or RayOptions(), jobs, launcher, echo)
    return LocalLauncher(sweep, jobs, launcher)


def run_sweep(
    sweep: Sweep,
    jobs: int | None = None,
    retries: int = 1,
    launcher: str = "",
    dry_run: bool = False,
    echo=print,
    backend: str = "local",
    ray: RayOptions | None = None,
) -> Summary:
    """Validate the whole grid, then train what is not done yet; returns what finished, was skipped or failed.

    ``backend``: ``local`` (default) or ``ray`` with its ``RayOptions`` (address, GPUs and CPUs per run)."""
    if backend not in BACKENDS:
        raise unknown("sweep backend", backend, BACKENDS)
    if ray is not None and backend != "ray":
        raise ConfigError("Ray options (--ray-address, --gpus-per-run, --cpus-per-run) need --backend ray")
    if backend == "ray":
        run_resources(sweep, ray or RayOptions())  # the options' own checks, before the grid's
    prints = validate(sweep)
    shape = f"{len(sweep.tasks)} task(s) x {len(sweep.methods)} method(s) x {len(sweep.seeds)} seed(s)"
    echo(f"[sweep] {sweep.name}: {len(sweep.runs)} runs ({shape}) in {sweep.out_dir}; every config resolves")
    words = {
        "done": "done (skipped)",
        "new": "new",
        "unfinished": "unfinished (rerun from scratch)",
        "stale": "stale: config changed (rerun from scratch)",
    }
    if dry_run:
        todo, done, states = plan(sweep, prints)
        echo("[sweep] " + ", ".join(f"{len(v)} {words[k]}" for k, v in states.items()))
        for run in sweep.runs:
            state = next(k for k, v in states.items() if run.key in v)
            echo(f"  {state:10s} {run.key}: refpo train {shlex.join(run.args)}")
        return Summary(total=len(sweep.runs), skipped=[r.key for r in done])
    runner = make_launcher(backend, sweep, jobs, launcher, ray, echo)
    try:
        lock = SweepLock(sweep.out_dir)
        try:
            todo, done, states = plan(sweep, prints)
            runner.prepare(sweep)
            echo(
                "[sweep] "
                + ", ".join(f"{len(v)} {words[k]}" for k, v in states.items())
                + f"; {runner.jobs} at a time {runner.where}"
            )
            write_spec(sweep, prints)
            summary = SweepExecutor(sweep, runner, retries, echo).execute(todo, prints, done)
        finally:
            lock.release()
    finally:
        runner.close()
    echo(
        f"[sweep] finished {len(summary.finished)} run(s), skipped {len(summary.skipped)} already done, "
        f"failed {len(summary.failed)}" + (f", interrupted {len(summary.interrupted)}" if summary.interrupted else "")
    )
    for key, why in summary.failed:
        echo(f"  failed {key}: {why}")
    for key in summary.interrupted:
        echo(f"  interrupted {key} (rerun the sweep to train it again)")
    echo(f"[sweep] report: refpo report {sweep.out_dir}")
    return summary
