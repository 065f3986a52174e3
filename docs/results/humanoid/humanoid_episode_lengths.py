"""How long untrained training episodes last (docs/humanoid.md, "Residual actions"):
``python docs/results/humanoid/humanoid_episode_lengths.py [--num-envs 32] [--steps 120]``.

``humanoid_all`` training episodes (reference-state initialisation, 0.25 m termination) under zero actions and under
N(0, 0.05^2) actions (the start of a reference-initialised policy), with ``residual_actions`` off and on, on the
shipped standing clip and on the default (all shipped) clips. Prints one JSON line per setting: the episodes that
ended during the run, how many of them ended by time-out, their mean length in control steps, and the mean that also
counts the episodes still running at the end (cut at their current length).
"""

from __future__ import annotations

import argparse
import json

import numpy as np
import torch

from refpo_warp.envs.registry import make_env
from refpo_warp.tasks.humanoid.motions import SHIPPED_MOTIONS

CLIPS = {"standing": str(SHIPPED_MOTIONS / "stand_sway_poses.npz"), "default": ""}


def probe(motion_file: str, residual: bool, action_std: float, num_envs: int, steps: int, seed: int = 0) -> dict:
    env = make_env(
        "humanoid_all", num_envs=num_envs, device="cpu", seed=seed, motion_file=motion_file, residual_actions=residual
    )
    generator = torch.Generator().manual_seed(seed)
    lengths, time_outs = [], 0
    for _ in range(steps):
        _, _, dones, extras = env.step(action_std * torch.randn(num_envs, env.num_actions, generator=generator))
        if dones.any():
            lengths += extras["log"]["Episode/alive_steps"].tolist()
            time_outs += int(extras["time_outs"][dones].sum())
    running = env.episode_length_buf.tolist()
    return {
        "episodes": len(lengths),
        "time_outs": time_outs,
        "mean_length": float(np.mean(lengths)) if lengths else None,
        "mean_length_incl_running": float(np.mean(lengths + running)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        prog="python docs/results/humanoid/humanoid_episode_lengths.py", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--num-envs", type=int, default=32)
    parser.add_argument("--steps", type=int, default=120)
    args = parser.parse_args()
    torch.set_num_threads(1)
    for clips, motion_file in CLIPS.items():
        for residual in (False, True):
            for action_std in (0.0, 0.05):
                result = probe(motion_file, residual, action_std, args.num_envs, args.steps)
                print(
                    json.dumps({"clips": clips, "residual_actions": residual, "action_std": action_std, **result}),
                    flush=True,
                )


if __name__ == "__main__":
    main()
