"""Device resolution and the one-time Warp configuration shared by every environment and tool."""

from __future__ import annotations

import os

import torch

_CONFIGURED = False


def resolve_device(device: str = "auto") -> str:
    """Map ``"auto"`` to ``"cuda:0"`` when a CUDA device is usable, else ``"cpu"``; validate explicit names."""
    if device == "auto":
        return "cuda:0" if torch.cuda.is_available() else "cpu"
    if device == "cuda":
        device = "cuda:0"
    if device.startswith("cuda") and not torch.cuda.is_available():
        raise RuntimeError(f"device={device} was requested but no CUDA device is available; use device=cpu or auto")
    if device != "cpu" and not device.startswith("cuda:"):
        raise ValueError(f"Unknown device '{device}': expected 'auto', 'cpu' or 'cuda:N'")
    return device


def set_torch_threads(cuda_cap: int | None = None) -> int:
    """Limit torch's CPU threads: 1 without CUDA (the CPU cores run the env kernels), else at most ``cuda_cap``.

    ``cuda_cap=None`` leaves the thread count unchanged when CUDA is available. Returns the count set.
    """
    n = torch.get_num_threads()
    n = 1 if not torch.cuda.is_available() else (min(n, cuda_cap) if cuda_cap else n)
    n = max(1, n)
    torch.set_num_threads(n)
    return n


def configure_warp():
    """Set Warp's global options; must run before any module defining kernels (ours, Newton's) is imported."""
    global _CONFIGURED
    import warp as wp

    if not _CONFIGURED:
        # Module options are frozen when a Python module first defines a kernel, so set them up front.
        # RL needs no kernel adjoints; skipping them halves cold compile times.
        wp.config.enable_backward = False
        wp.config.log_level = wp.LOG_WARNING
        wp.config.quiet = True
        if os.environ.get("REFPO_WARP_PORTABLE_CACHE"):
            # A generic CPU target keeps a restored kernel cache valid on another CPU model.
            wp.config.cpu_compiler_flags = ""
        _CONFIGURED = True
    return wp


def init_warp():
    """Configure and initialise Warp (idempotent); returns the ``warp`` module."""
    wp = configure_warp()
    wp.init()
    return wp
