"""Helpers of tests/training/test_reliability*.py: run the tools as a user would (in this process through the command's
own entry point, or as a subprocess where a process must be killed), hash files, craft bad files."""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import pickle
import shutil
import subprocess
import sys
import time
from pathlib import Path

import torch

from refpo_warp.utils.paths import REPO_ROOT

REPO = REPO_ROOT
# A run that takes seconds: GridWorld, 4 envs x 8 steps, tiny networks.
TINY = [
    "task=gridworld",
    "device=cpu",
    "num_envs=4",
    "runner.num_steps_per_env=8",
    "actor.hidden_dims=[16]",
    "critic.hidden_dims=[16]",
    "algorithm.num_mc_samples=2",
    "algorithm.num_learning_epochs=1",
    "algorithm.num_mini_batches=1",
    "eval.num_envs=4",
    "eval.flow_steps=[1]",
    "runner.save_interval=1",
]


def tiny(*overrides: str) -> list[str]:
    """``TINY`` with ``overrides`` replacing its keys (a key may be given only once on the command line)."""
    keys = {o.split("=", 1)[0] for o in overrides if "=" in o}
    return [a for a in TINY if a.split("=", 1)[0] not in keys] + list(overrides)


def tool_env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    env.setdefault("WARP_CACHE_PATH", str(REPO / ".warp_cache"))
    env["PYTHONUNBUFFERED"] = "1"
    return env


def run_tool(tool: str, *args: str, timeout: float = 180) -> subprocess.CompletedProcess:
    """``python tools/<tool>.py args...`` from the repository root; output captured as text."""
    return subprocess.run(
        [sys.executable, str(REPO / "tools" / f"{tool}.py"), *map(str, args)],
        cwd=REPO,
        env=tool_env(),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


def call_tool(tool: str, *args: str) -> subprocess.CompletedProcess:
    """``refpo <tool> args...`` in this process: ``refpo_warp.cli.main.main``, the function that the ``refpo`` command,
    ``python -m refpo_warp`` and ``tools/<tool>.py`` call, with its stdout, stderr and exit code captured as a
    subprocess's would be. Seconds faster per case than a new interpreter (the imports), with the same code path
    from the argument list on; what comes before it (the console script, ``tools/*.py``) runs as a subprocess in
    test_reliability_kill.py, tests/cli/test_play.py and tests/cli/test_installed_wheel.py."""
    from refpo_warp.cli.main import main

    argv = [tool.replace("_", "-"), *map(str, args)]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as stop:  # a command that exits instead of returning its code
            code = stop.code if isinstance(stop.code, int) else 1
    return subprocess.CompletedProcess(argv, code, out.getvalue(), err.getvalue())


def run_python(code: str, timeout: float = 180) -> subprocess.CompletedProcess:
    """``python -c code`` with the project importable (for runs with a fault patched in)."""
    return subprocess.run(
        [sys.executable, "-c", code],
        cwd=REPO,
        env=tool_env(),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


def start_tool(tool: str, *args: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, str(REPO / "tools" / f"{tool}.py"), *map(str, args)],
        cwd=REPO,
        env=tool_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def kill_when(proc: subprocess.Popen, condition, timeout: float = 120, poll_s: float = 0.0005) -> bool:
    """SIGKILL ``proc`` as soon as ``condition()`` is true; False if it exited or timed out first."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            proc.kill()
            proc.wait()
            return True
        if proc.poll() is not None:
            return False
        time.sleep(poll_s)
    proc.kill()
    proc.wait()
    return False


def assert_refused(proc: subprocess.CompletedProcess, code: int, *culprits: str) -> None:
    """Exit ``code``, every culprit named on stderr, and no traceback anywhere in the output."""
    out = proc.stdout + proc.stderr
    assert proc.returncode == code, f"exit {proc.returncode}, expected {code}\n{out[-3000:]}"
    for name in culprits:
        assert name in proc.stderr, f"'{name}' not named in stderr:\n{proc.stderr[-3000:]}"
    assert "Traceback (most recent call last)" not in out, out[-3000:]


def tree_hash(root: Path) -> dict[str, str]:
    """sha256 of every file under ``root`` (relative path -> digest); {} if ``root`` does not exist."""
    if not root.exists():
        return {}
    if root.is_file():
        return {root.name: hashlib.sha256(root.read_bytes()).hexdigest()}
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def copy_run(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


class Payload:
    """Unpickling this object runs ``touch <marker>``: the code a malicious checkpoint would execute."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch '{self.marker}'",))


def write_malicious(path: Path, marker: Path, kind: str) -> Path:
    """A checkpoint-looking file whose unpickling would create ``marker``: ``zip`` (torch.save), ``legacy``
    (torch's pre-1.6 format) or ``pickle`` (a bare pickle)."""
    data = {
        "actor_state_dict": {},
        "critic_state_dict": {},
        "optimizer_state_dict": {},
        "iter": 9,
        "infos": Payload(marker),
    }
    if kind == "zip":
        torch.save(data, path)
    elif kind == "legacy":
        torch.save(data, path, _use_new_zipfile_serialization=False)
    else:
        path.write_bytes(pickle.dumps(data))
    return path


def truncate(path: Path, fraction: float = 0.5) -> Path:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])
    return path
