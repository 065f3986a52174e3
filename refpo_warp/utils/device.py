"""Device resolution and the one-time Warp configuration shared by every environment and tool."""

from __future__ import annotations

import os
import sys
import tempfile

import torch

from refpo_warp.utils.errors import ConfigError

_CONFIGURED = False


def check_device_name(device: str) -> str:
    """``device`` if it is a device name (auto, cpu, cuda, cuda:N), whether or not this machine has it."""
    if not (isinstance(device, str) and (device in ("auto", "cpu", "cuda") or
                                         (device.startswith("cuda:") and device[5:].isdigit()))):  # fmt: skip
        raise ConfigError(f"device={device!r} is invalid; expected auto, cpu, cuda or cuda:N")
    return device


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
            raise ConfigError(f"device={device} was requested but no CUDA device is available; use device=cpu or "
                              f"device=auto")  # fmt: skip
        if int(index) >= torch.cuda.device_count():
            raise ConfigError(f"device={device} is not available: this machine has {torch.cuda.device_count()} "
                              f"CUDA device(s), cuda:0 .. cuda:{torch.cuda.device_count() - 1}")  # fmt: skip
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


# Printed by Warp's native library (C stderr, no option turns it off) on every machine without a CUDA driver: on a
# CPU-only machine it is noise, and a requested CUDA device fails with its own clear error (resolve_device).
NO_DRIVER_WARNING = "Could not find or load the NVIDIA CUDA driver"


def init_warp():
    """Configure and initialise Warp (idempotent); returns the ``warp`` module.

    Warp's "no CUDA driver" warning is dropped; anything else the initialisation writes to stderr is passed on.
    """
    wp = configure_warp()
    try:
        from warp._src.context import runtime
    except ImportError:  # another Warp layout: initialise through the filter every time (cheap when done)
        runtime = None
    if runtime is not None:  # initialised already: nothing would be printed
        return wp
    with _stderr_without(NO_DRIVER_WARNING):
        wp.init()
    return wp


class _stderr_without:
    """Capture file descriptor 2 (native code writes there directly) and re-emit every line but ``message``'s."""

    def __init__(self, message: str) -> None:
        self.message = message

    def __enter__(self) -> None:
        sys.stderr.flush()
        self.saved = os.dup(2)
        self.capture = tempfile.TemporaryFile()
        os.dup2(self.capture.fileno(), 2)

    def __exit__(self, *exc) -> None:
        sys.stderr.flush()
        os.dup2(self.saved, 2)
        os.close(self.saved)
        self.capture.seek(0)
        text = self.capture.read().decode("utf-8", errors="replace")
        self.capture.close()
        sys.stderr.write("".join(line for line in text.splitlines(keepends=True) if self.message not in line))
        sys.stderr.flush()
