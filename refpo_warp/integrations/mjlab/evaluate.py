"""A checkpoint's deterministic return rate on a registered mjlab task, for any of its algorithms (PPO or ReFPO):

    python -m refpo_warp.integrations.mjlab.evaluate <task id> <model_N.pt | run dir> [num_envs=64] [num_steps=200]
        [seed=0] [initial_noise=zero|random|random,zero] [flow_steps=N]

Given a run directory (``logs/rsl_rl/<experiment>/<run>``), every checkpoint of it is evaluated and its TensorBoard
curves of the training episode length and return are summarised (first and last iteration).

Built as mjlab's ``play`` builds it (the task's play env config, its runner class, the actor's weights), the policy
acts for ``num_steps`` steps from reset: deterministically (a flow from zero initial noise, what ``play`` and the ONNX
export do; a Gaussian's mean), or, for a flow policy, from random initial noise (``initial_noise=random``; both:
``random,zero``, one rate each, the same protocols as ``eval.initial_noise``), with ``flow_steps`` Euler steps (0, the
default: the actor's own ``num_flow_steps``; 1 is the one-step deployment); the result is the mean reward per second
of simulated time (mjlab's rewards are per step times the step's dt). Why not the episode length: a task whose only
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

from refpo_warp.models.sampled_policy import INITIAL_NOISE, noise_protocols
from refpo_warp.utils.console import quiet_stdout
from refpo_warp.utils.errors import ConfigError

OPTIONS = {"num_envs": 64, "num_steps": 200, "seed": 0, "flow_steps": 0}  # flow_steps 0: the actor's own
PROTOCOLS = ["zero"]  # the deterministic policy mjlab's play runs


def evaluate(
    task_id: str,
    checkpoint: str,
    num_envs: int = 64,
    num_steps: int = 200,
    seed: int = 0,
    device: str = "cpu",
    initial_noise: str = "zero",
    flow_steps: int = 0,
) -> dict[str, float]:
    """``{"reward_rate": mean reward per simulated second, "num_envs", "num_steps"}`` of ``checkpoint``'s policy
    (a flow's initial noise ``zero`` or ``random`` and its Euler steps, ``flow_steps`` or 0 for its own; a Gaussian
    acts by its mean either way)."""
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
        if (initial_noise != "zero" or flow_steps) and hasattr(policy, "sample"):
            actor = policy
            policy = lambda obs: actor.sample(obs, num_steps=flow_steps or None, initial_noise=initial_noise)  # noqa: E731
        obs, total = env.get_observations(), 0.0
        with torch.inference_mode():
            for _ in range(num_steps):
                obs, rewards, _, _ = env.step(policy(obs))
                total += float(rewards.mean())
        step_dt = float(env.unwrapped.step_dt)
    finally:
        env.close()
    return {"reward_rate": total / (num_steps * step_dt), "num_envs": num_envs, "num_steps": num_steps}


def rates(task_id: str, checkpoint: str, protocols: list[str], **options) -> dict[str, float]:
    """``{"reward_rate": ...}`` for one protocol, ``{"reward_rate/random": ..., "reward_rate/zero": ...}`` for more."""
    if len(protocols) == 1:
        return {"reward_rate": evaluate(task_id, checkpoint, initial_noise=protocols[0], **options)["reward_rate"]}
    return {
        f"reward_rate/{p}": evaluate(task_id, checkpoint, initial_noise=p, **options)["reward_rate"] for p in protocols
    }


def summarize_run(task_id: str, run_dir: str | Path, protocols: list[str] = PROTOCOLS, **options) -> dict:
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
        for key, rate in rates(task_id, str(path), protocols, **options).items():
            summary[f"{key}/{path.stem}"] = rate
    return summary


def main(argv: list[str]) -> int:
    positional = [a for a in argv if "=" not in a]
    if len(positional) != 2 or any(a in ("-h", "--help") for a in argv):
        print(__doc__)
        return 0 if any(a in ("-h", "--help") for a in argv) else 2
    options, protocols = dict(OPTIONS), PROTOCOLS
    try:
        for arg in (a for a in argv if "=" in a):
            key, _, value = arg.partition("=")
            if key == "initial_noise":
                protocols = noise_protocols(key, value.strip("[]").replace(" ", "").split(","))
            elif key not in OPTIONS:
                raise ConfigError(f"unknown option '{key}' (valid: {', '.join([*OPTIONS, 'initial_noise'])})")
            elif not value.isdigit():
                raise ConfigError(f"{key}={value} is invalid; expected a whole number >= 0")
            else:
                options[key] = int(value)
    except ConfigError as err:
        print(
            f"error: {err} (initial_noise takes {', '.join(INITIAL_NOISE)} or both, comma-separated)", file=sys.stderr
        )
        return 2
    task_id, target = positional
    run = Path(target).is_dir()
    if run:
        result = summarize_run(task_id, target, protocols, **options)
    else:
        result = rates(task_id, target, protocols, **options)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
