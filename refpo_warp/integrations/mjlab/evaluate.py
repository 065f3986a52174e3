"""A checkpoint's deterministic return rate on a registered mjlab task, for any of its algorithms (PPO or ReFPO):

    python -m refpo_warp.integrations.mjlab.evaluate task=<task id> checkpoint=<model_N.pt> | run_dir=<run dir>
        [num_envs=64] [num_steps=200] [seed=0] [initial_noise=zero|random|[random,zero]] [flow_steps=N] [device=auto]

Given a run directory (``logs/rsl_rl/<experiment>/<run>``), every checkpoint of it is evaluated and its TensorBoard
curves of the training episode length and return are summarised (first and last iteration).

Built as mjlab's ``play`` builds it (the task's play env config, its runner class, the actor's weights), the policy
acts for ``num_steps`` steps from reset: deterministically (a flow from zero initial noise, what ``play`` and the ONNX
export do; a Gaussian's mean), or, for a flow policy, from random initial noise (``initial_noise=random``; both:
``[random,zero]``, one rate each, the same protocols as ``eval.initial_noise``), with ``flow_steps`` Euler steps (null,
the default: the actor's own ``num_flow_steps``; 1 is the one-step deployment); the result is the mean reward per second
of simulated time (mjlab's rewards are per step times the step's dt). Why not the episode length: a task whose only
termination is the time-out (the cartpoles) has episodes of one length whatever the policy does.
"""

from __future__ import annotations

import json
import re
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

import torch
from mjlab.envs import ManagerBasedRlEnv
from mjlab.rl import MjlabOnPolicyRunner, RslRlVecEnvWrapper
from mjlab.tasks.registry import load_env_cfg, load_rl_cfg, load_runner_cls

from refpo_warp.config.command_options import EXPLAIN, command_help, options_or_explain
from refpo_warp.models.sampled_policy import NOISE_PROTOCOLS_RULE
from refpo_warp.utils.command_line import parse_arguments, wants_help
from refpo_warp.utils.console import quiet_stdout
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import DEVICE_DOC, DEVICE_RULE, Int, Text
from refpo_warp.utils.options import option

PROTOCOLS = ["zero"]  # the deterministic policy mjlab's play runs


@dataclass(frozen=True)
class EvaluateOptions:
    task: str = option(rule=Text(), doc="a registered mjlab task id (the one the checkpoint was trained on)")
    checkpoint: str | None = option(None, Text(optional=True), "a model_<iteration>.pt file (or run_dir=)")
    run_dir: str | None = option(None, Text(optional=True), "a run directory: every checkpoint of it (or checkpoint=)")
    num_envs: int = option(64, Int(1, 1 << 22), "envs")
    num_steps: int = option(200, Int(1), "env steps from reset")
    seed: int = option(0, Int(0, 2**32 - 1), "the envs' seed")
    initial_noise: list[str] = option(
        PROTOCOLS,
        NOISE_PROTOCOLS_RULE,
        "initial-noise protocols of a flow policy, one rate each (eval.initial_noise's)",
    )
    flow_steps: int | None = option(
        None, Int(1, 1000, optional=True), "Euler steps of a flow policy (null: the actor's own num_flow_steps)"
    )
    device: str = option("auto", DEVICE_RULE, DEVICE_DOC)


USAGE = command_help(
    "python -m refpo_warp.integrations.mjlab.evaluate task=<task id> checkpoint=<model_N.pt> | run_dir=<run dir> "
    "[key=value ...]",
    __doc__.split("\n\n", 2)[2],
    EvaluateOptions,
)


def evaluate(
    task_id: str,
    checkpoint: str,
    num_envs: int = 64,
    num_steps: int = 200,
    seed: int = 0,
    device: str = "cpu",
    initial_noise: str = "zero",
    flow_steps: int | None = None,
) -> dict[str, float]:
    """``{"reward_rate": mean reward per simulated second, "num_envs", "num_steps"}`` of ``checkpoint``'s policy
    (a flow's initial noise ``zero`` or ``random`` and its Euler steps, ``flow_steps`` or None for its own; a Gaussian
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
        if (initial_noise != "zero" or flow_steps is not None) and hasattr(policy, "sample"):
            actor = policy
            policy = lambda obs: actor.sample(obs, num_steps=flow_steps, initial_noise=initial_noise)  # noqa: E731
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
    if wants_help(argv):
        print(USAGE)
        return 0
    try:
        _run(argv)
    except ConfigError as err:  # a bad option: one message, exit code 2 (refpo's, docs/cli.md)
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


def _run(argv: list[str]) -> None:
    from refpo_warp.utils.device import resolve_device

    command = "mjlab evaluate"
    parsed = options_or_explain(command, EvaluateOptions, parse_arguments(command, argv, (EXPLAIN,)))
    if parsed is None:
        return
    options = parsed[0]
    if (options.checkpoint is None) == (options.run_dir is None):
        raise ConfigError("mjlab evaluate needs checkpoint=<model_N.pt> or run_dir=<run dir>, one of them")
    kwargs = {
        "num_envs": options.num_envs,
        "num_steps": options.num_steps,
        "seed": options.seed,
        "flow_steps": options.flow_steps,
        "device": resolve_device(options.device),
    }
    if options.run_dir is not None:
        result = summarize_run(options.task, options.run_dir, options.initial_noise, **kwargs)
    else:
        assert options.checkpoint is not None
        result = rates(options.task, options.checkpoint, options.initial_noise, **kwargs)
    print(json.dumps(result))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
