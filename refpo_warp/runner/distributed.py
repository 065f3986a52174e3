"""Multi-process training with torchrun: this process's rank, its device and seed, and the process group.

``torchrun --nproc_per_node=K -m refpo_warp train ...`` starts K processes and sets ``WORLD_SIZE``, ``RANK`` and
``LOCAL_RANK`` in each. Every rank steps its own envs (``num_envs`` per rank) on its own device, with its own seed
(``seed + RANK``), and rsl_rl averages the gradients across ranks; rank 0 alone writes logs, checkpoints, the
config and the evaluation. See docs/multi_gpu.md.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass

import torch
import torch.distributed as dist

from refpo_warp.utils.device import resolve_device
from refpo_warp.utils.errors import ConfigError


@dataclass(frozen=True)
class RankInfo:
    """Where this process sits in a torchrun launch (a plain run is rank 0 of 1)."""

    rank: int = 0
    local_rank: int = 0
    world_size: int = 1

    @property
    def is_main(self) -> bool:
        return self.rank == 0

    @property
    def is_distributed(self) -> bool:
        return self.world_size > 1


def _env_int(name: str, default: int) -> int:
    value = os.environ.get(name, str(default))
    try:
        return int(value)
    except ValueError:
        raise ConfigError(f"environment variable {name}={value!r} is not an integer (set by torchrun)") from None


def process_rank() -> RankInfo:
    """This process's rank from torchrun's environment variables (``WORLD_SIZE``, ``RANK``, ``LOCAL_RANK``)."""
    world_size = _env_int("WORLD_SIZE", 1)
    if world_size <= 1:
        return RankInfo()
    info = RankInfo(rank=_env_int("RANK", 0), local_rank=_env_int("LOCAL_RANK", 0), world_size=world_size)
    if not (0 <= info.rank < world_size and 0 <= info.local_rank < world_size):
        raise ConfigError(f"RANK={info.rank} / LOCAL_RANK={info.local_rank} must lie in [0, WORLD_SIZE={world_size})")
    return info


def rank_device(device: str, rank: RankInfo) -> str:
    """The torch device of this rank: ``auto``/``cuda`` mean ``cuda:LOCAL_RANK`` under torchrun (``auto`` falls back
    to ``cpu`` without CUDA); an explicit ``cuda:N`` must be that device."""
    if not rank.is_distributed:
        return resolve_device(device)
    if device == "auto":
        device = "cuda" if torch.cuda.is_available() else "cpu"
    if device == "cuda":
        device = f"cuda:{rank.local_rank}"
    resolved = resolve_device(device)
    if resolved.startswith("cuda") and resolved != f"cuda:{rank.local_rank}":
        raise ConfigError(
            f"device={device} on local rank {rank.local_rank}: under torchrun each rank trains on cuda:LOCAL_RANK; "
            "pass device=auto (or cuda), or device=cpu"
        )
    return resolved


def init_process_group(rank: RankInfo, device: str) -> str:
    """Join the default process group (NCCL for a CUDA device, gloo for a CPU) unless it exists; returns the
    backend. rsl_rl itself always asks for NCCL, which has no CPU implementation."""
    backend = "nccl" if torch.device(device).type == "cuda" else "gloo"
    if not dist.is_initialized():
        dist.init_process_group(backend=backend, rank=rank.rank, world_size=rank.world_size)
    elif dist.get_backend() != backend:
        raise RuntimeError(f"the process group uses {dist.get_backend()}, but device {device} needs {backend}")
    if backend == "nccl":
        torch.cuda.set_device(device)
    return backend


def close_process_group() -> None:
    """Leave the default process group (if this process joined one)."""
    if dist.is_available() and dist.is_initialized():
        dist.destroy_process_group()


@contextlib.contextmanager
def main_rank_stdout(rank: RankInfo):
    """Let only rank 0 print (rsl_rl prints model summaries and sync messages on every rank); stderr stays."""
    if rank.is_main:
        yield
        return
    with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink):
        yield
