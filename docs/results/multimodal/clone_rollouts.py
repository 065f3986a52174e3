"""The clones' rollouts on the two-way task (clones.py --measure): the arena's geometry, each episode's way past the
wall, success and where a failure ends, the data's and each clone setting's episodes, and the machine they ran on;
written to clones.json and machine.json. Definitions: clones.py's docstring."""

from __future__ import annotations

import json
import os
import platform
import re
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
RESULTS, MACHINE, FIGURE = HERE / "clones.json", HERE / "machine.json", HERE / "trajectories.png"
TASK = "dmc_point_mass_wall"
CLONES = {"clone_flow": "refpo", "clone_gauss": "ppo"}  # run folder -> algo
SMALL_FILES = ("config.yaml", "eval.json", "progress.jsonl")
# (key, run folder or None for the data, label on the page)
SETTINGS = (
    ("data", None, "data (the demonstrator)"),
    ("flow_N10", "clone_flow", "flow clone, N = 10"),
    ("flow_N1", "clone_flow", "flow clone, N = 1"),
    ("gauss_mean", "clone_gauss", "Gaussian clone, mean action"),
    ("gauss_sample", "clone_gauss", "Gaussian clone, sampled"),
)
EPISODES = 500  # per clone setting (one env per episode, all stepped together)
MEASURE_SEED = 10_001  # the runs' evaluation seed (seed 1 + EVAL_SEED_OFFSET): the same starts for every setting
KEEP_PATHS, EVERY = 12, 10  # trajectories kept per setting for the figure, every EVERY-th position
KEEP_FAILED = 3  # and the first failed episodes' trajectories
DIGITS = 4  # positions in clones.json rounded to 0.1 mm
WALL_TOUCH = 0.01  # a failure within this of the grown wall's start-side face ends "against the wall"


def geometry() -> dict:
    """The arena's fixed geometry and the default wall (what the runs used: no env options on their lines)."""
    from refpo_warp.tasks.dmc.point_mass_wall_cfg import (
        ARENA,
        MASS_RADIUS,
        START_X,
        TARGET_RADIUS,
        TARGET_X,
        PointMassWallCfg,
    )

    cfg = PointMassWallCfg()
    a, b = cfg.wall_box()
    return {
        "arena": ARENA,
        "mass_radius": MASS_RADIUS,
        "start_x": START_X,
        "start_spread": cfg.start_spread,
        "target_x": TARGET_X,
        "target_radius": TARGET_RADIUS,
        "wall_half_thickness": cfg.wall_half_thickness,
        "wall_half_length": cfg.wall_half_length,
        "grown_a": a,
        "grown_b": b,
        "horizon": cfg.max_episode_length,
    }


# ------------------------------------------------------------------------------------------------ measuring
def traverses(x: np.ndarray, a: float) -> np.ndarray:
    """Per episode (rows of x positions), how often it went from before the wall (x < -a) to past it (x > a)."""
    side = np.zeros(len(x), dtype=int)  # -1 before the wall, 1 past it, 0 not yet either
    count = np.zeros(len(x), dtype=int)
    for column in x.T:
        now = np.where(column < -a, -1, np.where(column > a, 1, side))
        count += (side == -1) & (now == 1)
        side = now
    return count


def episode_summary(paths: np.ndarray, returns: np.ndarray, geo: dict) -> dict:
    """paths (episodes, T + 1, 2): every position of every episode (the last one after the last step)."""
    a, b = geo["grown_a"], geo["grown_b"]
    final = paths[:, -1]
    distance = np.hypot(final[:, 0] - geo["target_x"], final[:, 1])
    success = distance <= geo["target_radius"]
    past = paths[:, :, 0] > 0
    crossed = past.any(axis=1)
    first = past.argmax(axis=1)
    y_at = paths[np.arange(len(paths)), first, 1]
    way = np.where(crossed, np.sign(y_at), 0).astype(int)
    at_wall = (final[:, 0] < 0) & (final[:, 0] >= -a - WALL_TOUCH) & (np.abs(final[:, 1]) <= b)
    beyond = final[:, 0] > a
    fail = ~success
    ends = {
        "at_wall": int((fail & at_wall).sum()),
        "past_wall": int((fail & beyond).sum()),
        "back_before_wall": int((fail & ~at_wall & ~beyond & crossed).sum()),
        "never_passed": int((fail & ~at_wall & ~beyond & ~crossed).sum()),
    }
    passes = traverses(paths[:, :, 0], a)
    wall_y = np.abs(final[fail & at_wall, 1])
    return {
        "episodes": len(paths),
        "success": int(success.sum()),
        "left": int((way == 1).sum()),
        "right": int((way == -1).sum()),
        "none": int((way == 0).sum()),
        "success_left": int((success & (way == 1)).sum()),
        "success_right": int((success & (way == -1)).sum()),
        "returns": [round(float(r), 2) for r in returns],
        "failure_ends": ends,
        "failure_at_wall_abs_y": {
            "median": round(float(np.median(wall_y)), DIGITS) if wall_y.size else None,
            "max": round(float(wall_y.max()), DIGITS) if wall_y.size else None,
        },
        "failure_past_wall_distance_median": (
            round(float(np.median(distance[fail & beyond])), DIGITS) if (fail & beyond).any() else None
        ),
        "passed_more_than_once": int((passes > 1).sum()),
        "failures_passed_more_than_once": int((fail & (passes > 1)).sum()),
        "final": np.round(final, DIGITS).tolist(),
        "way": way.tolist(),
        "paths": np.round(paths[:KEEP_PATHS, ::EVERY], DIGITS).tolist(),
        "failed_paths": np.round(paths[np.flatnonzero(fail)[:KEEP_FAILED], ::EVERY], DIGITS).tolist(),
        "failed_way": way[np.flatnonzero(fail)[:KEEP_FAILED]].tolist(),
    }


def data_paths(runs: Path) -> tuple[np.ndarray, np.ndarray]:
    from refpo_warp.demonstrations.dataset_file import read_dataset

    dataset = read_dataset(runs / "data")
    paths = np.stack([e.observations[:, :2] for e in dataset.episodes]).astype(np.float64)
    returns = np.array([float(e.rewards.sum()) for e in dataset.episodes])
    return paths, returns


def clone_paths(run_dir: Path, setting: str) -> tuple[np.ndarray, np.ndarray, float]:
    """Roll the clone of ``run_dir`` out for EPISODES whole episodes in one setting; (paths, returns, seconds)."""
    import torch

    from refpo_warp.config.saved import load_run
    from refpo_warp.envs.registry import make_env
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest

    run = load_run(run_dir, {"device": "cpu"})
    cfg = run.cfg
    env = make_env(run.task, num_envs=EPISODES, device="cpu", seed=MEASURE_SEED, **cfg["env"])
    _, runner = build_runner(run, None, env=env)
    load_latest(runner, run_dir, cfg["task"], cfg["algo"])
    actor = runner.get_inference_policy(device="cpu")
    policies = {
        "flow_N10": lambda obs: actor.sample(obs, 10, "random", perturbation=False),
        "flow_N1": lambda obs: actor.sample(obs, 1, "random", perturbation=False),
        "gauss_mean": lambda obs: actor(obs, stochastic_output=False),
        "gauss_sample": lambda obs: actor(obs, stochastic_output=True),
    }
    policy = policies[setting]
    torch.manual_seed(MEASURE_SEED)
    started = time.monotonic()
    with torch.inference_mode():
        env.enable_final_observations()
        obs = env.reset()
        seen = [obs["policy"][:, :2].clone()]
        total = torch.zeros(env.num_envs)
        for _ in range(int(env.max_episode_length)):
            obs, rewards, dones, _ = env.step(policy(obs))
            total += rewards
            p = obs["policy"][:, :2]
            if bool(dones.any()):
                p = torch.where(dones[:, None], env.final_observations["policy"][:, :2], p)
            seen.append(p.clone())
        if not bool(dones.all()):
            raise RuntimeError(f"{run_dir}: not every episode ended at the time limit")
    return torch.stack(seen, dim=1).double().numpy(), total.double().numpy(), time.monotonic() - started


def gnu_time_wall(path: Path) -> float | None:
    """The wall time GNU time wrote: ``-v``'s 'Elapsed (wall clock) time' (h:mm:ss or m:ss) or ``-f '%e ...'``."""
    if not path.is_file():
        return None
    text = path.read_text()
    found = re.search(r"Elapsed \(wall clock\) time.*?: ([\d:.]+)", text)
    if found:
        return round(sum(float(p) * 60**i for i, p in enumerate(reversed(found.group(1).split(":")))), 2)
    found = re.match(r"\s*([\d.]+) s wall", text)
    return float(found.group(1)) if found else None


def machine() -> dict:
    import torch
    import warp

    from refpo_warp.utils.machine import cpu_model

    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], check=False, capture_output=True, text=True, cwd=ROOT
    )
    return {
        "cpu_model": cpu_model(),
        "cpu_count": os.cpu_count(),
        "load_average_1_5_15": [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]],
        "python": platform.python_version(),
        "torch": torch.__version__,
        "warp": warp.__version__,
        "platform": platform.platform(),
        "commit": commit.stdout.strip(),
        "device": "cpu",
    }


def measure(runs: Path) -> None:
    geo = geometry()
    (HERE / "data").mkdir(parents=True, exist_ok=True)
    shutil.copy2(runs / "data" / "metadata.json", HERE / "data" / "metadata.json")
    for name in CLONES:
        (HERE / name).mkdir(exist_ok=True)
        for f in SMALL_FILES:
            shutil.copy2(runs / name / f, HERE / name / f)
    out: dict = {"geometry": geo, "episodes_per_clone_setting": EPISODES, "measure_seed": MEASURE_SEED}
    out["settings"], out["rollout_s"] = {}, {}
    mach = machine()  # the load before this script's own rollouts
    for key, run, _ in SETTINGS:
        if run is None:
            paths, returns = data_paths(runs)
        else:
            paths, returns, seconds = clone_paths(runs / run, key)
            out["rollout_s"][key] = round(seconds, 1)
        out["settings"][key] = episode_summary(paths, returns, geo)
        s = out["settings"][key]
        print(f"{key}: success {s['success']}/{s['episodes']}, left {s['left']}, right {s['right']}, none {s['none']}")
    names = {"collect": "collect", **{n: n for n in CLONES}}
    out["process_wall_s"] = {k: gnu_time_wall(runs / f"{v}.time") for k, v in names.items()}
    RESULTS.write_text(json.dumps(out, separators=(",", ":")) + "\n")
    MACHINE.write_text(json.dumps(mach, indent=1) + "\n")
