"""Warp, configured in one place: every module that uses Warp takes it from here,
``from refpo_warp.utils.warp_setup import wp``, so Warp's options are set before that module defines its first
kernel, whatever was imported before it (Warp freezes a module's options when it defines its first kernel). A task
copied from another inherits no import-order rule. ``init_warp`` initialises Warp without its no-driver warning.
"""

from __future__ import annotations

import os
import sys
import tempfile

import warp as wp

# RL needs no kernel adjoints; skipping them halves cold compile times.
wp.config.enable_backward = False
wp.config.log_level = wp.LOG_WARNING
if os.environ.get("REFPO_WARP_PORTABLE_CACHE"):
    # A generic CPU target keeps a restored kernel cache valid on another CPU model.
    wp.config.cpu_compiler_flags = ""

# Printed by Warp's native library (C stderr, no option turns it off) on every machine without a CUDA driver: on a
# CPU-only machine it is noise, and a requested CUDA device fails with its own clear error (resolve_device).
NO_DRIVER_WARNING = "Could not find or load the NVIDIA CUDA driver"

__all__ = ["NO_DRIVER_WARNING", "init_warp", "wp"]


def init_warp():
    """Initialise Warp (idempotent); returns the ``warp`` module.

    Warp's "no CUDA driver" warning is dropped; anything else the initialisation writes to stderr is passed on.
    """
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
