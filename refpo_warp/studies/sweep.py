"""Run a sweep: every run of the grid as its own ``refpo train`` process, several at a time, resumable.

- A run whose ``eval.json`` exists and whose ``config.yaml`` is the run's current config is skipped.
- A run of the current config with a checkpoint but no ``eval.json`` (paused at a piece's end by ``stop_after_minutes``
  / ``stop_after_iterations``, or interrupted) is continued from its newest checkpoint (``resume=true``: a run in
  pieces ends bit-identical to one trained in one call), so a long run advances over several sweep calls; a run that
  stops at its piece's end is reported paused, not failed.
- A run that is unfinished with nothing to continue, or stale (its config changed), is trained again from scratch;
  only its log files are kept.
- A run that exits non-zero is reported with its log and retried once from scratch (``retries``), a continued one
  too; not one stopped on a non-finite loss (exit 3), whose rerun would repeat it and whose files are the result.
- The sweep dir holds ``sweep.yaml`` (the resolved spec: methods, runs, their arguments and config fingerprints,
  merged over earlier invocations) and ``status.json`` (per run: state, attempts, exit codes, seconds, node, log).
- Backends (``backends.py``): ``local`` (subprocesses of this machine, ``grid/local.py``) and ``ray`` (one Ray task per
  run on a cluster, ``ray/backend.py``); both run the same executor (``grid/executor.py``) and the same training
  command (``grid/launch.py``).
"""

from __future__ import annotations

import shlex

from refpo_warp.studies.backends import check_backend, make_launcher
from refpo_warp.studies.grid.executor import Summary, SweepExecutor
from refpo_warp.studies.grid.lock import SweepLock
from refpo_warp.studies.grid.spec import Sweep, validate
from refpo_warp.studies.grid.state import plan, write_spec
from refpo_warp.studies.ray.backend import RayOptions


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
    check_backend(backend, sweep, ray)  # the options' own checks, before the grid's
    prints = validate(sweep)
    shape = f"{len(sweep.tasks)} task(s) x {len(sweep.methods)} method(s) x {len(sweep.seeds)} seed(s)"
    echo(f"[sweep] {sweep.name}: {len(sweep.runs)} runs ({shape}) in {sweep.out_dir}; every config resolves")
    words = {
        "done": "done (skipped)",
        "failed": "stopped by a non-finite loss (kept, not trained again)",
        "new": "new",
        "paused": "paused (continued from its newest checkpoint)",
        "unfinished": "unfinished (rerun from scratch)",
        "stale": "stale: config changed (rerun from scratch)",
    }
    if dry_run:
        todo, kept, states = plan(sweep, prints)
        echo("[sweep] " + ", ".join(f"{len(v)} {words[k]}" for k, v in states.items()))
        for run in sweep.runs:
            state = next(k for k, v in states.items() if run.key in v)
            echo(f"  {state:10s} {run.key}: refpo train {shlex.join(run.args)}")
        return Summary(total=len(sweep.runs), skipped=[run.key for run, _ in kept])
    runner = make_launcher(backend, sweep, jobs, launcher, ray, echo)
    try:
        lock = SweepLock(sweep.out_dir)
        try:
            todo, kept, states = plan(sweep, prints)
            runner.prepare(sweep)
            echo(
                "[sweep] "
                + ", ".join(f"{len(v)} {words[k]}" for k, v in states.items())
                + f"; {runner.jobs} at a time {runner.where}"
            )
            write_spec(sweep, prints)
            summary = SweepExecutor(sweep, runner, retries, echo).execute(todo, prints, kept)
        finally:
            lock.release()
    finally:
        runner.close()
    echo(
        f"[sweep] finished {len(summary.finished)} run(s), skipped {len(summary.skipped)} already done, "
        f"failed {len(summary.failed)}"
        + (f", interrupted {len(summary.interrupted)}" if summary.interrupted else "")
        + (f", paused {len(summary.paused)} (run the sweep again to continue them)" if summary.paused else "")
    )
    for key, why in summary.failed:
        echo(f"  failed {key}: {why}")
    for key in summary.interrupted:
        echo(f"  interrupted {key} (rerun the sweep to train it again)")
    echo(f"[sweep] report: refpo report {sweep.out_dir}")
    return summary
