"""One run's training process, the same on every backend: the ``python -m refpo_warp train`` command line (the
installed package, wherever it is: a node needs the package, not a checkout), its environment, its
log (``train.log``; an earlier attempt's run dir cleared, its logs kept) and how it is stopped. The local backend
starts it from the sweep process, the Ray backend from a Ray task on the node that trains it.

Light on purpose: a Ray worker imports this (through ``studies/ray/node.py``) to run a task, and needs no config
machinery.
"""

from __future__ import annotations

import ctypes
import os
import shlex
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from refpo_warp.studies.grid.state import LOG_FILE, clear_run_dir

STOP_GRACE_S = 30.0  # a run's time to exit after SIGINT (checkpoint, summary) before it is killed
PR_SET_PDEATHSIG = 1


def train_command(
    args: Sequence[str], device: str, launcher: Sequence[str] = (), python: str = sys.executable
) -> list[str]:
    """``[launcher...] python -m refpo_warp train <run args> device=<device>``: what every backend runs for a run."""
    return [*launcher, python, "-m", "refpo_warp", "train", *args, f"device={device}"]


def train_env(base: Mapping[str, str], threads: int | None) -> dict[str, str]:
    """``base`` with unbuffered output (the log is live) and, for a CPU run, ``threads`` torch threads (several runs
    share the cores)."""
    env = dict(base, PYTHONUNBUFFERED="1")
    if threads is not None:
        env.update(OMP_NUM_THREADS=str(threads), MKL_NUM_THREADS=str(threads))
    return env


def hostname() -> str:
    return socket.gethostname()


def start_training(
    run_dir: Path,
    header: str,
    cmd: Sequence[str],
    env: Mapping[str, str],
    cwd: str | Path,
    detach: bool = False,
    resume: bool = False,
) -> subprocess.Popen:
    """Clear the run dir of an earlier attempt (its log becomes ``train.attempt<k>.log``), write ``# <header>: <cmd>``
    as the first line of ``train.log`` and start ``cmd`` with its output there. ``resume``: a paused run is continued
    in place (nothing cleared; its log goes on below a header of its own).

    ``detach``: the run gets its own process group (a terminal's Ctrl-C reaches only whoever started it, which stops
    it with ``stop_training``), a clean signal mask and, on Linux, is killed when its parent dies however it dies (a
    Ray worker lost or force-cancelled leaves no training process behind).
    """
    if not resume:
        clear_run_dir(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    with open(run_dir / LOG_FILE, "a" if resume else "w") as f:
        f.write(f"# {header}{', continued from its newest checkpoint' if resume else ''}: {shlex.join(cmd)}\n")
        f.flush()
        preexec = _detached_child() if detach else None
        # preexec_fn despite a Ray worker's threads: the child only makes two system calls before it execs
        return subprocess.Popen(
            list(cmd),
            stdout=f,
            stderr=subprocess.STDOUT,
            cwd=cwd,
            env=dict(env),
            start_new_session=detach,
            preexec_fn=preexec,  # noqa: PLW1509
        )


def _detached_child():
    """A ``preexec_fn`` for a detached run: an empty signal mask (a Ray worker blocks SIGINT, and a child inherits
    that through exec: it would ignore the stop request) and, on Linux, SIGKILL when its parent exits
    (``PR_SET_PDEATHSIG``). prctl is looked up here, in the parent: between fork and exec the child only calls."""
    prctl = ctypes.CDLL(None, use_errno=True).prctl if sys.platform.startswith("linux") else None
    parent = os.getpid()

    def preexec() -> None:
        signal.pthread_sigmask(signal.SIG_SETMASK, [])
        if prctl is not None:
            prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
            if os.getppid() != parent:  # the parent died before the call: nobody would kill us
                os._exit(1)

    return preexec


def _signal(proc: subprocess.Popen, sig: int) -> None:
    if proc.poll() is not None:
        return
    try:
        if os.getpgid(proc.pid) == proc.pid:  # its own group (detached): the launcher prefix and the run alike
            os.killpg(proc.pid, sig)
        else:
            proc.send_signal(sig)
    except ProcessLookupError:
        pass


def stop_training(procs: Sequence[subprocess.Popen], grace: float = STOP_GRACE_S) -> None:
    """SIGINT to every run (as a Ctrl-C would), then SIGKILL to those still running ``grace`` seconds later."""
    for proc in procs:
        _signal(proc, signal.SIGINT)
    deadline = time.monotonic() + grace
    for proc in procs:
        try:
            proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            _signal(proc, signal.SIGKILL)
            proc.wait()
