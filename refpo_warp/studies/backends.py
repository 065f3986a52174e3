"""Which backend trains a study's runs, for ``refpo sweep`` and ``refpo tune`` alike: ``local`` (subprocesses of this
machine, ``grid/local.py``) or ``ray`` (one Ray task per run, ``ray/backend.py``); both run under the same executor
(``grid/executor.py``). Ray itself is imported only when a Ray launcher is made."""

from __future__ import annotations

from refpo_warp.studies.grid.executor import Launcher
from refpo_warp.studies.grid.local import LocalLauncher
from refpo_warp.studies.grid.spec import Sweep
from refpo_warp.studies.ray.backend import RayLauncher, RayOptions, run_resources
from refpo_warp.utils.errors import ConfigError, unknown

BACKENDS = ("local", "ray")


def check_backend(backend: str, sweep: Sweep, ray: RayOptions | None) -> None:
    """A known backend, Ray options only with Ray, and their own checks: before the study's configs are checked."""
    if backend not in BACKENDS:
        raise unknown("sweep backend", backend, BACKENDS)
    if ray is not None and backend != "ray":
        raise ConfigError("Ray options (--ray-address, --gpus-per-run, --cpus-per-run) need --backend ray")
    if backend == "ray":
        run_resources(sweep, ray or RayOptions())


def make_launcher(
    backend: str,
    sweep: Sweep,
    jobs: int | None,
    launcher: str,
    ray: RayOptions | None,
    echo=print,
    detach: bool = False,
) -> Launcher:
    """The backend's launcher; a CUDA sweep without a GPU, or a Ray cluster without room for a run, fails here.
    ``detach``: a local run dies with this process (a Ray run always does)."""
    if backend == "ray":
        return RayLauncher(sweep, ray or RayOptions(), jobs, launcher, echo)
    return LocalLauncher(sweep, jobs, launcher, detach)
