"""Run by tests/runner/test_multi_gpu.py under torchrun (not a test itself): one short ReFPO run per rank through
``refpo_warp.runner.build.build_runner``, twice: with rsl_rl's gradient all-reduce and with it switched off. Each rank
saves its final actor/critic state, learning rate, device and env seed to ``OUT_DIR/<mode>_rank<r>.pt``.

    torchrun --standalone --nproc_per_node=2 tests/runner/multi_gpu_worker.py OUT_DIR key=value ...
"""

import sys
from pathlib import Path

import torch

from refpo_warp.config.dotted import parse_overrides
from refpo_warp.config.resolve import Resolution, resolve
from refpo_warp.runner.build import build_runner, seed_everything
from refpo_warp.runner.distributed import close_process_group, process_rank


def run(resolved: Resolution, reduce_gradients: bool) -> dict:
    cfg, rank = resolved.cfg, process_rank()
    seed_everything(cfg["seed"] + rank.rank)
    env, runner = build_runner(resolved, None)
    if not reduce_gradients:
        runner.alg.reduce_parameters = lambda: None  # every rank steps on its own gradients
    runner.learn(cfg["max_iterations"])
    alg = runner.alg
    return {
        "parameters": {
            f"{name}.{k}": v.detach().clone()
            for name, model in (("actor", alg.actor), ("critic", alg.critic))
            for k, v in model.named_parameters()
        },
        "buffers": {
            f"{name}.{k}": v.detach().clone()
            for name, model in (("actor", alg.actor), ("critic", alg.critic))
            for k, v in model.named_buffers()
        },
        "learning_rate": alg.learning_rate,
        "device": str(env.device),
        "env_seed": env.seed,
        "multi_gpu": runner.cfg["multi_gpu"],
        "backend": torch.distributed.get_backend(),
    }


def main(out_dir: Path, overrides: list[str]) -> None:
    resolved = resolve(parse_overrides(overrides))
    rank = process_rank().rank
    for mode, reduce_gradients in (("reduced", True), ("unreduced", False)):
        torch.save(run(resolved, reduce_gradients), out_dir / f"{mode}_rank{rank}.pt")
    close_process_group()


if __name__ == "__main__":
    main(Path(sys.argv[1]), sys.argv[2:])
