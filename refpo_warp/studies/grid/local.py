"""The local backend of the executor (the default): ``jobs`` runs at a time as subprocesses of this machine, one per GPU
(more share the GPUs round-robin) or one per CPU core with one torch thread each. ``detach``: each run in its own
process group, killed when this process dies however it dies (a tuning study's runs: a restart clears their folders)."""

from __future__ import annotations

import os
import shlex
import subprocess
import time

from refpo_warp.studies.grid.executor import Job, Launcher, Outcome
from refpo_warp.studies.grid.launch import hostname, start_training, stop_training, train_command, train_env
from refpo_warp.studies.grid.spec import Run, Sweep, device_type
from refpo_warp.utils.errors import ConfigError


class LocalLauncher(Launcher):
    def __init__(self, sweep: Sweep, jobs: int | None = None, launcher: str = "", detach: bool = False) -> None:
        self.sweep, self.prefix, self.detach = sweep, shlex.split(launcher), detach
        self.gpus = cuda_devices(sweep)
        if jobs is None:  # one run per GPU, or one per CPU core (one torch thread each)
            jobs = self.gpus or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count())
        self.jobs = max(1, jobs or 1)
        self.where = f"on {sweep.device}"
        self.host = hostname()

    def _device(self, slot: int) -> str:
        if not self.gpus:
            return self.sweep.device if self.sweep.device != "auto" else "cpu"
        return self.sweep.device if ":" in self.sweep.device else f"cuda:{slot % self.gpus}"

    def start(self, run: Run, attempt: int, slot: int, origin: str) -> subprocess.Popen:
        cmd = train_command(run.args, self._device(slot), self.prefix)
        env = train_env(os.environ, None if self.gpus else 1)  # CPU: one torch thread per run
        header = f"{origin}, attempt {attempt} on {self.host}"
        return start_training(run.run_dir, header, cmd, env, os.getcwd(), detach=self.detach, resume=run.resume)

    def wait(self, jobs: list[Job], timeout: float) -> list[tuple[Job, Outcome]]:
        time.sleep(timeout)
        ended = [j for j in jobs if j.handle.poll() is not None]
        return [(j, Outcome(j.handle.returncode, time.monotonic() - j.started, self.host)) for j in ended]

    def stop(self, jobs: list[Job]) -> None:
        stop_training([j.handle for j in jobs])


def cuda_devices(sweep: Sweep) -> int:
    """GPUs the sweep's runs share (0 for a CPU sweep); a CUDA sweep without a GPU is an error."""
    if device_type(sweep.device) != "cuda":
        return 0
    import torch

    if not torch.cuda.device_count():
        raise ConfigError(
            f"Sweep '{sweep.name}' trains on CUDA (device: {sweep.device}) but no CUDA device is "
            "available here (--dry-run validates it without training)"
        )
    return torch.cuda.device_count()
