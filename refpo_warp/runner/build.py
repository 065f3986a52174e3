"""Build what a run trains with from a resolved config: rsl_rl's train_cfg, the env and our ``Runner``.

Shared by training (``refpo_warp.training``), evaluation (``refpo_warp.evaluation``) and the benchmarks; it imports
none of them.
"""

from __future__ import annotations

import copy
import math
import random
from pathlib import Path
from typing import Any

import numpy as np
import torch

from refpo_warp.config.resolve import Resolution
from refpo_warp.envs.registry import make_env
from refpo_warp.runner.distributed import process_rank, rank_device
from refpo_warp.runner.runner import Runner
from refpo_warp.utils.device import set_torch_threads
from refpo_warp.utils.errors import ConfigError

__all__ = [
    "build_runner",
    "check_obs_groups",
    "env_steps_per_iteration",
    "num_iterations",
    "rsl_rl_config",
    "seed_everything",
]


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def rsl_rl_config(cfg: dict) -> dict:
    """The train_cfg dict rsl_rl's OnPolicyRunner expects, built from a resolved refpo_warp config."""
    runner = cfg["runner"]
    return {
        "num_steps_per_env": runner["num_steps_per_env"],
        "save_interval": runner["save_interval"],
        "logger": runner["logger"],
        "check_for_nan": runner["check_for_nan"],
        "torch_compile_mode": runner["torch_compile_mode"],
        "obs_groups": {k: list(v) for k, v in runner["obs_groups"].items()},
        "run_name": f"{cfg['task']}/{cfg['algo']}",
        # Deep copies: rsl_rl < 5.5 pops class_name out of these dicts and the nested distribution_cfg.
        "actor": copy.deepcopy(cfg["actor"]),
        "critic": copy.deepcopy(cfg["critic"]),
        "algorithm": copy.deepcopy(cfg["algorithm"]),
    }


def env_steps_per_iteration(cfg: dict, world_size: int = 1) -> int:
    """Env steps one training iteration takes on all ranks: envs x policy steps x ``env.action_chunk`` (a policy step
    of an action-chunk env runs that many env steps)."""
    chunk = int(cfg.get("env", {}).get("action_chunk", 1))
    return cfg["num_envs"] * cfg["runner"]["num_steps_per_env"] * chunk * world_size


def num_iterations(cfg: dict, world_size: int = 1) -> int:
    """Training iterations: ``max_iterations`` if set, else the env-step budget over the env steps of one iteration
    (``total_env_steps`` counts every rank's env steps, as the logged ``env_steps`` do)."""
    if cfg["max_iterations"]:
        return int(cfg["max_iterations"])
    return max(1, math.ceil(cfg["total_env_steps"] / env_steps_per_iteration(cfg, world_size)))


def check_obs_groups(cfg: dict, env) -> None:
    """Every observation group named in ``runner.obs_groups`` must be one the env provides."""
    available = sorted(env.get_observations().keys())
    for name, groups in cfg["runner"]["obs_groups"].items():
        missing = [g for g in groups if g not in available]
        if missing:
            raise ConfigError(
                f"runner.obs_groups.{name}={groups}: the {cfg['task']} env has no observation group "
                f"{', '.join(map(repr, missing))}; its groups are {', '.join(available)}"
            )


def build_runner(run: Resolution, log_dir: Path | None, env: Any = None) -> tuple[Any, Runner]:
    """Env + rsl_rl runner (with our extensions) for a resolved config (``run.cfg``, the env of ``run.task``); ``env``
    hosts the runner instead of a new one.

    Nothing is written to ``log_dir`` until training starts. Under torchrun: this rank's device and env seed
    (``seed + RANK``), and a run dir for rank 0 only.
    """
    cfg, rank = run.cfg, process_rank()
    device = rank_device(cfg["device"], rank)
    if cfg["torch_threads"] is not None:
        set_torch_threads(threads=cfg["torch_threads"])
    if env is None:
        env = make_env(run.task, num_envs=cfg["num_envs"], device=device, seed=cfg["seed"] + rank.rank, **cfg["env"])
    check_obs_groups(cfg, env)
    log_dir = log_dir if rank.is_main else None
    run_info = {"task": cfg["task"], "algo": cfg["algo"]}  # written into and checked against every checkpoint
    runner = Runner(
        env,
        rsl_rl_config(cfg),
        log_dir=str(log_dir) if log_dir else None,
        device=device,
        log_full=cfg["runner"]["log_full"],
        run_info=run_info,
        verbose=cfg["verbose"],
    )
    return env, runner
