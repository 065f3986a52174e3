"""What the Ray backend runs on a node (``backend.py`` submits these as Ray tasks): one run's
``python -m refpo_warp train`` process (the package installed on the node), started exactly as the local backend
starts it, on the GPU Ray assigned (the run sees it as ``cuda:0``); and the check that a node sees the sweep dir and
the working directory at the paths the head sees.

Ray imports this module on its workers by name: it imports ``ray`` only inside the tasks and nothing heavy at all
(a fresh worker starts a run in a fraction of a second instead of loading torch first).
"""

from __future__ import annotations

import os
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from refpo_warp.studies.grid.launch import hostname, start_training, stop_training, train_command, train_env


@dataclass(frozen=True)
class TrainTask:
    """Everything a node needs to train one run; paths are the head's (a shared filesystem has them everywhere)."""

    origin: str  # what heads the log: sweep <name>, or a tuning trial
    key: str
    attempt: int
    args: tuple[str, ...]
    run_dir: str  # absolute
    cuda: bool
    threads: int  # torch threads of a CPU run
    launcher: tuple[str, ...]
    cwd: str
    resume: bool = False  # a paused run, continued in place


def missing_paths(paths: list[str]) -> list[str]:
    return [p for p in paths if not os.path.exists(p)]


def see_paths(paths: list[str], token_file: str, token: str) -> dict:
    """On one node: which of ``paths`` it lacks and whether it reads the head's ``token`` from ``token_file`` (the
    same folder, not a local copy at the same path)."""
    import ray

    try:
        same = Path(token_file).read_text() == token
    except OSError:
        same = False
    return {
        "host": hostname(),
        "node_id": ray.get_runtime_context().get_node_id(),
        "missing": missing_paths(paths),
        "token": same,
    }


def _earlier_executions(run_dir: Path, task_id: str) -> int:
    """Logs of this very task that a lost worker or node left (Ray re-ran the task): its id is in their first line."""
    count = 0
    for log in run_dir.glob("train*.log") if run_dir.is_dir() else []:
        try:
            with open(log, errors="replace") as f:
                count += f"(Ray task {task_id})" in f.readline()
        except OSError:
            pass
    return count


def _wait(proc: subprocess.Popen) -> int:
    """``proc.wait()`` in short steps: Ray's cancel is an exception raised between Python instructions, which a
    ``wait()`` blocked in C would hold back until the run ended."""
    while True:
        try:
            return proc.wait(timeout=0.5)
        except subprocess.TimeoutExpired:
            pass


def train_run(task: TrainTask) -> dict:
    """The Ray task of one run: its exit code, seconds and node; a cancel (``ray.cancel``) stops the training
    process before the task ends, and a lost worker takes it along (``start_training(detach=True)``)."""
    import ray

    ctx = ray.get_runtime_context()
    host, task_id = hostname(), ctx.get_task_id()
    assert task_id is not None  # None only outside a Ray task (the driver)
    result = {"exit_code": None, "seconds": 0.0, "host": host, "node_id": ctx.get_node_id(), "reruns": 0, "error": ""}
    missing = missing_paths([task.cwd])
    if missing:
        return {**result, "error": f"node {host} does not see {missing[0]} (a Ray sweep needs a shared filesystem)"}
    gpus = ray.get_gpu_ids()
    if task.cuda and not gpus:
        return {**result, "error": f"Ray assigned no GPU on {host} to a CUDA run (--gpus-per-run)"}
    run_dir = Path(task.run_dir)
    result["reruns"] = _earlier_executions(run_dir, task_id)
    cmd = train_command(task.args, "cuda:0" if task.cuda else "cpu", task.launcher)
    env = train_env(os.environ, None if task.cuda else task.threads)
    header = f"{task.origin}, attempt {task.attempt} on {host} (Ray task {task_id})"
    start = time.monotonic()
    proc = None
    try:
        proc = start_training(run_dir, header, cmd, env, task.cwd, detach=True, resume=task.resume)
        result["exit_code"] = _wait(proc)
    except KeyboardInterrupt:  # ray.cancel(force=False) raises this here: stop the run before the task ends
        if proc is not None:
            stop_training([proc])
        raise
    result["seconds"] = time.monotonic() - start
    return result
