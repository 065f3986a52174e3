"""Device resolution, torch's CPU threads and its CPU float mode, shared by every environment and tool (Warp's set-up:
``refpo_warp/utils/warp_setup.py``)."""

from __future__ import annotations

import torch

from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import DEVICE_RULE


def check_device_name(device: str) -> str:
    """``device`` if it is a device name (auto, cpu, cuda, cuda:N), whether or not this machine has it."""
    return DEVICE_RULE.check("device", device)


def resolve_device(device: str = "auto") -> str:
    """Map ``"auto"`` to ``"cuda:0"`` when a CUDA device is usable, else ``"cpu"``; validate explicit names.

    Raises ``ConfigError`` (naming the ``device`` option) for an unknown name or a device that is not available.
    """
    check_device_name(device)
    if device == "auto":
        return "cuda:0" if torch.cuda.is_available() else "cpu"
    if device == "cuda":
        device = "cuda:0"
    index = device[5:] if device.startswith("cuda:") else None
    if index is not None:
        if not torch.cuda.is_available():
            raise ConfigError(
                f"device={device} was requested but no CUDA device is available; use device=cpu or device=auto"
            )
        if int(index) >= torch.cuda.device_count():
            raise ConfigError(
                f"device={device} is not available: this machine has {torch.cuda.device_count()} "
                f"CUDA device(s), cuda:0 .. cuda:{torch.cuda.device_count() - 1}"
            )
    return device


def set_torch_threads(cuda_cap: int | None = None, threads: int | None = None) -> int:
    """Set torch's CPU threads: ``threads`` when given (a run's ``torch_threads``), else 1 without CUDA (the CPU cores
    run the env kernels) and at most ``cuda_cap`` with it.

    ``cuda_cap=None`` leaves the thread count unchanged when CUDA is available. Returns the count set.
    """
    if threads is None:
        n = torch.get_num_threads()
        n = 1 if not torch.cuda.is_available() else (min(n, cuda_cap) if cuda_cap else n)
    else:
        n = threads
    n = max(1, n)
    torch.set_num_threads(n)
    return n


def flush_denormals_on_cpu(device: str | torch.device) -> None:
    """On the CPU, have torch compute float32 denormals (magnitudes below 1.2e-38) as zero, for this process.

    A SiLU or ELU unit far below zero has a denormal derivative, and x86 CPUs compute with denormals many times
    slower: a DMC critic fitting returns in the hundreds spent more than half of its backward pass on them. Values
    that small vanish when added to any normal number, so the learning checks' runs train to the same bits with and
    without it (``docs/results/learning_checks.md``). Nothing changes on CUDA.
    """
    if torch.device(device).type == "cpu":
        torch.set_flush_denormal(True)


def cpu_has_native_bfloat16() -> bool:
    """Whether this CPU multiplies bfloat16 matrices in hardware (AVX512-BF16 or AMX). Without either, torch emulates
    bfloat16 matrix products: on a 2-core AMD EPYC with AVX2 an iteration of the CPU profile under bfloat16 autocast
    took 12 to 21 times as long as in float32 (``docs/results/throughput/``)."""
    return bool(torch.cpu._is_avx512_bf16_supported() or torch.cpu._is_amx_tile_supported())
