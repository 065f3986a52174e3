"""Train a policy from a resolved config: the implementation behind ``tools/train.py``.

``train(["task=gridworld", "algo=refpo", "seed=1"])`` builds the env and rsl_rl's runner (extended in
``refpo_warp.runner``), writes the resolved config next to the checkpoints, trains (or resumes), evaluates at the
end and returns the evaluation results (also written to ``eval.json`` in the run dir).

Under torchrun every rank trains on its own device (``cuda:LOCAL_RANK``, or the CPU) with seed ``seed + RANK``;
rank 0 alone writes the run dir (config, checkpoints, logs) and evaluates (``refpo_warp.distributed``).
"""

from __future__ import annotations

import copy
import math
import random
from pathlib import Path
from typing import Any

import numpy as np
import torch

from refpo_warp.config import LEAF_KEYS, dump_config, load_yaml, resolve_config
from refpo_warp.distributed import process_rank, rank_device
from refpo_warp.errors import ConfigError
from refpo_warp.registry import make_env
from refpo_warp.runner import Runner, latest_checkpoint

RUN_CONFIG = "config.yaml"


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


def num_iterations(cfg: dict, world_size: int = 1) -> int:
    """Training iterations: ``max_iterations`` if set, else the env-step budget over the batch size of all ranks
    (``total_env_steps`` counts every rank's env steps, as the logged ``env_steps`` do)."""
    if cfg["max_iterations"]:
        return int(cfg["max_iterations"])
    batch = cfg["num_envs"] * cfg["runner"]["num_steps_per_env"] * world_size
    return max(1, math.ceil(cfg["total_env_steps"] / batch))


def default_run_dir(cfg: dict) -> Path:
    return Path("runs") / cfg["task"] / f"{cfg['algo']}_seed{cfg['seed']}"


def flatten(cfg: dict, prefix: str = "") -> dict[str, Any]:
    """Dotted-key view of a nested config (``LEAF_KEYS`` mappings stay whole)."""
    out: dict[str, Any] = {}
    for key, value in cfg.items():
        if isinstance(value, dict) and value and key not in LEAF_KEYS:
            out.update(flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def load_run_config(run_dir: Path, overrides: dict[str, Any]) -> dict:
    """The saved config of a run with ``overrides`` applied on top (used to resume and to evaluate)."""
    saved = run_dir / RUN_CONFIG
    if not saved.exists():
        raise ConfigError(f"{saved} not found: '{run_dir}' is not a refpo_warp run directory")
    flat = flatten(load_yaml(saved))
    flat.update(overrides)
    return resolve_config(flat)


def build_runner(cfg: dict, log_dir: Path | None, env=None):
    """Env + rsl_rl runner (with our extensions) for a resolved config; ``env`` hosts the runner instead of a new one.

    Under torchrun: this rank's device and env seed (``seed + RANK``), and a run dir for rank 0 only.
    """
    rank = process_rank()
    device = rank_device(cfg["device"], rank)
    if env is None:
        env = make_env(cfg["task"], num_envs=cfg["num_envs"], device=device, seed=cfg["seed"] + rank.rank,
                       **cfg["env"])  # fmt: skip
    log_dir = log_dir if rank.is_main else None
    runner = Runner(env, rsl_rl_config(cfg), log_dir=str(log_dir) if log_dir else None, device=device,
                    log_full=cfg["runner"]["log_full"])  # fmt: skip
    return env, runner


def train(overrides: list[str] | dict[str, Any] | None = None) -> dict:
    """Train (or resume) a run and evaluate it; returns the evaluation results (``{}`` if ``eval.at_end`` is off)."""
    from refpo_warp.config import parse_overrides
    from refpo_warp.report import evaluate_run, periodic_evaluator

    flat = parse_overrides(overrides) if isinstance(overrides, list) else dict(overrides or {})
    resume = bool(flat.get("resume", False))
    if resume and flat.get("run_dir") and (Path(flat["run_dir"]) / RUN_CONFIG).exists():
        cfg = load_run_config(Path(flat["run_dir"]), flat)
    else:
        cfg = resolve_config(flat)
    run_dir = Path(cfg["run_dir"] or default_run_dir(cfg))
    cfg["run_dir"] = str(run_dir)
    checkpoint = latest_checkpoint(run_dir) if run_dir.exists() else None
    if checkpoint is not None and not resume:
        raise ConfigError(
            f"{run_dir} already holds checkpoints ({checkpoint.name}); pass resume=true to continue that run, "
            "or choose another run_dir"
        )
    rank = process_rank()
    if rank.is_main:
        run_dir.mkdir(parents=True, exist_ok=True)
        if not resume:
            for stale in ("progress.jsonl", "eval.json"):
                (run_dir / stale).unlink(missing_ok=True)

    seed_everything(cfg["seed"] + rank.rank)
    env, runner = build_runner(cfg, run_dir)
    if rank.is_main:
        dump_config(cfg, run_dir / RUN_CONFIG)
    start = runner.resume_from(checkpoint) if (resume and checkpoint is not None) else 0
    total = num_iterations(cfg, rank.world_size)
    notice = cfg["notice"].format(task=cfg["task"], algo=cfg["algo"]) if cfg["notice"] else None
    if notice:
        print(f"[refpo_warp] NOTE: {notice}", flush=True)
    ranks = f" x {rank.world_size} ranks" if rank.is_distributed else ""
    steps = total * env.num_envs * cfg["runner"]["num_steps_per_env"] * rank.world_size
    print(f"[refpo_warp] {cfg['task']} / {cfg['algo']} on {env.device}: {env.num_envs} envs{ranks}, "
          f"iterations {start}..{total - 1} ({steps:,} env steps), run dir {run_dir}", flush=True)  # fmt: skip
    if cfg["eval"]["interval"] is None:  # periodic evaluation on by default: 10 evaluations per run
        cfg["eval"]["interval"] = max(1, math.ceil(total / 10))
    if cfg["eval"]["interval"] > 0 and rank.is_main:
        runner.logger.on_iteration = periodic_evaluator(cfg, runner)
    if total > start:
        runner.learn(total - start, init_at_random_ep_len=cfg["runner"]["init_at_random_ep_len"])
    results = {}
    if cfg["eval"]["at_end"] and rank.is_main:
        results = evaluate_run(run_dir, cfg=cfg, runner=runner)
        log_final_evaluation(runner, results)
    if notice:
        print(f"[refpo_warp] NOTE: {notice}", flush=True)
    return results


def log_final_evaluation(runner, results: dict) -> None:
    """The final evaluation's returns, task metrics and scalar diagnostics as TensorBoard scalars (``Eval/...``)."""
    writer = runner.logger.writer
    if writer is None:
        return
    it = results["checkpoint_iteration"]
    for setting, summary in results["results"].items():
        for key, value in summary.items():
            if isinstance(value, float):
                writer.add_scalar(f"Eval/{setting}/{key}", value, it)
    for key, value in results.get("diagnostics", {}).items():
        if isinstance(value, float):
            writer.add_scalar(f"Eval/diagnostics/{key}", value, it)
    if hasattr(writer, "flush"):
        writer.flush()
