"""A checkpoint's deterministic return rate on a registered mjlab task, for any of its algorithms (PPO or ReFPO):

    python -m refpo_warp.integrations.mjlab.evaluate <task id> <model_N.pt | run dir> [num_envs=64] [num_steps=200]

Given a run directory (``logs/rsl_rl/<experiment>/<run>``), every checkpoint of it is evaluated and its TensorBoard
curves of the training episode length and return are summarised (first and last iteration).

Built as mjlab's ``play`` builds it (the task's play env config, its runner class, the actor's weights), the policy
acts deterministically for ``num_steps`` steps from reset; the result is the mean reward per second of simulated
time (mjlab's rewards are per step times the step's dt). Why not the episode length: a task whose only
termination is the time-out (the cartpoles) has episodes of one length whatever the policy does.
"""

from __future__ import annotations

import json
import re
import sys
from dataclasses import asdict
from pathlib import Path

import torch
from mjlab.envs import ManagerBasedRlEnv
from mjlab.rl import MjlabOnPolicyRunner, RslRlVecEnvWrapper
from mjlab.tasks.registry import load_env_cfg, load_rl_cfg, load_runner_cls

from refpo_warp.utils.console import quiet_stdout

OPTIONS = {"num_envs": 64, "num_steps": 200, "seed": 0}


def evaluate(task_id: str, checkpoint: str, num_envs: int = 64, num_steps: int = 200, seed: int = 0,
             device: str = "cpu") -> dict[str, float]:  # fmt: skip
    """``{"reward_rate": mean reward per simulated second, "num_envs", "num_steps"}`` of ``checkpoint``'s policy."""
    env_cfg = load_env_cfg(task_id, play=True)
    env_cfg.scene.num_envs = num_envs
    env_cfg.seed = seed
    agent_cfg = load_rl_cfg(task_id)
    env = RslRlVecEnvWrapper(ManagerBasedRlEnv(cfg=env_cfg, device=device), clip_actions=agent_cfg.clip_actions)
    try:
        with quiet_stdout():  # rsl_rl prints the models
            runner = (load_runner_cls(task_id) or MjlabOnPolicyRunner)(env, asdict(agent_cfg), device=device)
        runner.load(checkpoint, load_cfg={"actor": True}, strict=True, map_location=device)
        policy = runner.get_inference_policy(device=device)
        obs, total = env.get_observations(), 0.0
        with torch.inference_mode():
            for _ in range(num_steps):
                obs, rewards, _, _ = env.step(policy(obs))
                total += float(rewards.mean())
        step_dt = float(env.unwrapped.step_dt)
    finally:
        env.close()
    return {"reward_rate": total / (num_steps * step_dt), "num_envs": num_envs, "num_steps": num_steps}


def summarize_run(task_id: str, run_dir: str | Path, **options) -> dict:
    """Every checkpoint of the run evaluated, and its training curves' first and last values."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run_dir = Path(run_dir)
    checkpoints = sorted(run_dir.glob("model_*.pt"), key=lambda p: int(re.findall(r"\d+", p.name)[-1]))
    if not checkpoints:
        raise FileNotFoundError(f"no model_<iteration>.pt in {run_dir}")
    events = EventAccumulator(str(run_dir))
    events.Reload()
    summary: dict = {"run": run_dir.name}
    for tag in ("Train/mean_episode_length", "Train/mean_reward"):
        values = [event.value for event in events.Scalars(tag)] if tag in events.Tags()["scalars"] else []
        summary[tag] = [values[0], values[-1]] if values else None
    for path in checkpoints:
        summary[f"reward_rate/{path.stem}"] = evaluate(task_id, str(path), **options)["reward_rate"]
    return summary


def main(argv: list[str]) -> int:
    positional = [a for a in argv if "=" not in a]
    if len(positional) != 2 or any(a in ("-h", "--help") for a in argv):
        print(__doc__)
        return 0 if any(a in ("-h", "--help") for a in argv) else 2
    options = dict(OPTIONS)
    for arg in (a for a in argv if "=" in a):
        key, _, value = arg.partition("=")
        if key not in OPTIONS:
            print(f"error: unknown option '{key}' (valid: {', '.join(OPTIONS)})", file=sys.stderr)
            return 2
        options[key] = int(value)
    task_id, target = positional
    run = Path(target).is_dir()
    result = summarize_run(task_id, target, **options) if run else evaluate(task_id, target, **options)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
