"""The flags that say where a study's runs train and how a failed one is retried, declared once for ``refpo sweep`` and
``refpo tune`` (both hand them to ``refpo_warp/studies/backends.py``)."""

from __future__ import annotations

from typing import Any

from refpo_warp.utils.command_line import Arguments, Flag

BACKEND_FLAGS = (
    Flag("--retries", int, "retries of a failed run"),
    Flag("--launcher", str, "a command that prefixes each training command"),
    Flag("--backend", str, "local or ray"),
    Flag("--ray-address", str, "auto or HOST:PORT"),
    Flag("--gpus-per-run", float, "GPUs per run on Ray"),
    Flag("--cpus-per-run", float, "CPUs per run on Ray"),
)
RAY_FLAGS = ("--ray-address", "--gpus-per-run", "--cpus-per-run")
BACKEND_USAGE = """[--retries N] [--launcher CMD] [--backend local|ray] [--ray-address ADDR]
      [--gpus-per-run G] [--cpus-per-run C]"""
BACKEND_HELP = """--retries N: retries of a failed run, each from scratch (default 1); --launcher "CMD" prefixes each
training command (e.g. "taskset -c 1").
--backend ray: every run is one Ray task, on the node and GPU Ray picks (pip install "refpo-warp[ray]"; every node
needs the package installed and must share the output folder and the working directory: docs/results/README.md, "On
a cluster"). --ray-address auto or HOST:PORT (default: RAY_ADDRESS, else a new local Ray); --gpus-per-run G (default
1 on CUDA, 0 on CPU; 0.5 packs two runs on a GPU); --cpus-per-run C (default 1: a CPU run's torch threads); --jobs
then defaults to the runs the cluster fits at once. A lost worker or node is re-run by Ray, not counted as one of the
run's --retries."""


def backend_arguments(args: Arguments) -> dict[str, Any]:
    """The backend keywords of ``run_sweep`` and ``Tuner``: retries, launcher, backend and its Ray options (given
    only with a Ray flag: without ``--backend ray`` they are refused)."""
    from refpo_warp.studies.ray.backend import RayOptions

    ray = None
    if any(f in args.flags for f in RAY_FLAGS):
        ray = RayOptions(args.flag("--ray-address"), args.flag("--gpus-per-run"), args.flag("--cpus-per-run", 1.0))
    return {
        "retries": args.flag("--retries", 1),
        "launcher": args.flag("--launcher", ""),
        "backend": args.flag("--backend", "local"),
        "ray": ray,
    }
