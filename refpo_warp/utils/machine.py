"""The machine a measurement or a run came from: its CPU model, cores, torch build and threads, and how busy it was.
Another CPU moves a training run as another seed does (its vector kernels round differently) and sets its wall time,
so a run's ``eval.json`` and every benchmark file record this beside their numbers."""

from __future__ import annotations

import contextlib
import os
import platform
from pathlib import Path
from typing import Any

import torch

from refpo_warp.utils.device import cpu_has_native_bfloat16


def cpu_model() -> str:
    """Linux: the CPU model (``/proc/cpuinfo``); elsewhere the platform's word for it."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine() or "cpu"


def machine() -> dict[str, Any]:
    out: dict[str, Any] = {
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "torch": torch.__version__,
        # the widest vector instructions torch's CPU kernels use, and whether bfloat16 matrix products run natively
        "cpu_capability": torch.backends.cpu.get_cpu_capability(),
        "native_bfloat16": cpu_has_native_bfloat16(),
    }
    with contextlib.suppress(OSError):  # how busy the machine was (other work may share it): 1, 5, 15 minutes
        out["load_average"] = [round(x, 2) for x in os.getloadavg()]
    if torch.cuda.is_available():
        out["gpu"] = torch.cuda.get_device_name()
    return out
