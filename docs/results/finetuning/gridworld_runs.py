"""tables.py --keep: the GridWorld runs' small files copied here, and where the Gaussian clone's time-outs end (the
clone rolled out again from its checkpoint)."""

from __future__ import annotations

import json
import shutil
from collections import Counter
from pathlib import Path

from study_layout import FILES, KEPT, ROWS, TIMEOUTS


# ------------------------------------------------------------------------------------------------ GridWorld
def keep(runs: Path) -> None:
    for name, _ in ROWS:
        for file in FILES:
            if (runs / name / file).exists():
                (KEPT / name).mkdir(parents=True, exist_ok=True)
                shutil.copyfile(runs / name / file, KEPT / name / file)
    if (runs / "data" / "metadata.json").exists():
        (KEPT / "data").mkdir(parents=True, exist_ok=True)
        shutil.copyfile(runs / "data" / "metadata.json", KEPT / "data" / "metadata.json")
    if (runs / "clone_gauss" / "model_0.pt").exists():
        rows = timeout_rows(runs / "clone_gauss")
        TIMEOUTS.write_text(json.dumps({str(y): k for y, k in sorted(rows.items())}, indent=2) + "\n")


def timeout_rows(run: Path, episodes: int = 200) -> Counter:
    """Where the Gaussian clone's time-outs stand: the row (y) of each episode the time-out ended."""
    import torch

    from refpo_warp.config.saved import load_run
    from refpo_warp.envs.registry import make_env
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    resolved = load_run(run, {"device": "cpu"})
    cfg = resolved.cfg
    env = make_env(resolved.task, num_envs=episodes, device="cpu", seed=cfg["seed"] + 10_000, **cfg["env"])
    _, runner = build_runner(resolved, None, env=env)
    load_latest(runner, run, cfg["task"], cfg["algo"])
    actor = runner.get_inference_policy(device="cpu")
    rows: Counter[int] = Counter()
    obs, ended = env.reset(), torch.zeros(episodes, dtype=torch.bool)
    with torch.inference_mode():
        for _ in range(int(env.max_episode_length)):
            before = env.positions.clone()
            obs, _, dones, extras = env.step(actor(obs))
            timed_out = extras["time_outs"] & ~ended
            for i in timed_out.nonzero().flatten().tolist():
                rows[int(before[i, 1])] += 1
            ended |= dones
            if bool(ended.all()):
                break
    return rows
