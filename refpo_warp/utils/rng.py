"""Random streams of their own for work beside training (evaluation, diagnostics, videos, export), so that a run
trains the same with or without it.

Training draws from the process's global generators (torch's on the CPU and on the run's CUDA device, numpy's,
Python's), seeded once from the run's seed. ``own_random_streams(seed)`` runs a block with those generators seeded
from ``seed`` and puts each back as it was afterwards: whatever the block draws, directly or deep inside a library,
training's streams continue where they stopped, and the block's own draws depend only on ``seed``.
"""

from __future__ import annotations

import contextlib
import random
from collections.abc import Iterator

import numpy as np
import torch

_MIX = 0x9E3779B1  # an odd 32-bit constant (the golden ratio's), to spread small seeds over the 63-bit range

# What a stream is for: the second part of its seed, so that each purpose draws other numbers from the same run seed.
PERIODIC_EVALUATION, FINAL_EVALUATION, VIDEO = 1, 2, 3


def stream_seed(*parts: int) -> int:
    """One seed from several integers (a run's seed, a purpose, an iteration): different parts, different seeds."""
    value = 0
    for part in parts:
        value = ((value ^ int(part)) * _MIX + 0x7F4A7C15) % (2**63 - 1)
    return value


@contextlib.contextmanager
def own_random_streams(seed: int, device: str | torch.device = "cpu") -> Iterator[None]:
    """Run the block on generators seeded with ``seed`` (torch's CPU one and ``device``'s CUDA one, numpy's and
    Python's global ones); afterwards every generator is back in the state it had before the block."""
    device = torch.device(device)
    cuda = [device] if device.type == "cuda" else []
    numpy_state, python_state = np.random.get_state(), random.getstate()
    with torch.random.fork_rng(devices=cuda):
        torch.default_generator.manual_seed(seed)
        for d in cuda:
            with torch.cuda.device(d):
                torch.cuda.manual_seed(seed)
        np.random.seed(seed % 2**32)
        random.seed(seed)
        try:
            yield
        finally:
            np.random.set_state(numpy_state)
            random.setstate(python_state)
