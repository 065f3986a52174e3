"""``refpo play``: a video of what a trained policy (or a zero / random agent) does in its task.

A run is loaded as ``refpo eval`` loads it (its saved config with the run options given over it, the newest usable
checkpoint or ``checkpoint=``, read with ``weights_only``) and plays its evaluation protocol (``eval.env``,
``eval.initial_noise``: one panel per N and protocol, ``eval.perturbation``); the video goes to
``<run dir>/videos/``, without a run to ``out=`` (default ``runs/videos``). The names are ``refpo train``'s: the video
options ``video.<key>`` (``refpo_warp/render/options.py``), env options ``env.<key>``, the evaluation's
``eval.<key>``. Every option is checked before anything is built.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refpo_warp.config.dotted import parse_overrides
from refpo_warp.render.options import VideoOptions
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError, unknown

SUMMARY = "a video of a trained policy (one flow step beside ten) or of a zero / random agent"
USAGE = """A video of a policy: refpo play run_dir=PATH [checkpoint=PATH] [video.flow_steps=[1,10]]
                   [eval.initial_noise=[random,zero]] [video.num_envs=4] [run options] [video options]
                   or: refpo play task=<task id> agent=zero|random [env.<option>=...] [out=DIR] [video options]

Writes <run dir>/videos/<name>.mp4 (video.format=gif or both for a GIF) and prints its path.
video.flow_steps=[1,10] shows the 1-step and the 10-step policy side by side from the same initial states;
eval.initial_noise=[random,zero] each N under both initial-noise protocols (the run's by default); any other run
option (device=, eval.env.<option>=, ...) applies over the run's saved config, as in refpo eval. Video options, named
as in refpo train: [video.length=300] [video.width=640] [video.height=480] [video.camera=track]
[video.format=mp4|gif|both] [video.fps=30] [video.seed=3] [video.name=NAME] [video.shadows=false]
[video.reference=true] (refpo_warp/render/options.py, docs/videos.md).
"""
FLAGS = ()
SUBJECTS = 0
AGENTS = ("zero", "random")
RUN_KEYS = ("run_dir", "checkpoint")  # the rest of a run's arguments are run options over its saved config
AGENT_KEYS = ("task", "agent", "device", "out")
VIDEO_KEYS = tuple(k for k in VideoOptions.__dataclass_fields__ if k not in ("at_end", "interval"))  # not training's


def _old_spelling(key: str, env_keys: tuple[str, ...]) -> str | None:
    """The name a key has now, for a key spelled the way refpo play once took it (refused, with the new name)."""
    if key in VIDEO_KEYS:
        return f"video.{key}"
    if key == "initial_noise":
        return "eval.initial_noise"
    return f"env.{key}" if key in env_keys else None


def split_arguments(args: list[str]) -> tuple[dict[str, Any], VideoOptions, dict[str, Any]]:
    """(the run or agent keys, the video options, the rest: a run's run options or an agent's env options), all
    checked."""
    flat = parse_overrides(args)
    has_run, has_task = "run_dir" in flat, "task" in flat
    if has_run == has_task:
        raise ConfigError("refpo play needs run_dir=PATH (a trained run) or task=ID agent=zero|random, not both")
    spec = None
    if has_task:
        from refpo_warp.envs.registry import get_task, list_tasks

        if str(flat["task"]) not in list_tasks():
            raise unknown("task", str(flat["task"]), list_tasks())
        spec = get_task(str(flat["task"]))
    env_keys = tuple(spec.cfg_class.defaults()) if spec is not None else ()
    own = RUN_KEYS if has_run else AGENT_KEYS
    for key in (k for k in flat if k not in own):  # an env option may share a name of ours (DMC's `task`)
        new = _old_spelling(key, env_keys)
        if new is not None:
            raise ConfigError(f"'{key}=' is spelled '{new}=' (refpo play names options as refpo train does)")
    if any(k.startswith("video.") and k[6:] in ("at_end", "interval") for k in flat):
        raise ConfigError("video.at_end and video.interval say when a training run records; refpo play records now")
    video = VideoOptions.from_dict({k[6:]: flat.pop(k) for k in list(flat) if k.startswith("video.")})
    picked = {k: flat.pop(k) for k in list(flat) if k in own}
    if has_run:
        return picked, video, flat  # run options: checked over the saved config (load_run)
    agent = picked.get("agent")
    if agent not in AGENTS:
        raise ConfigError(
            f"agent={agent!r} is invalid; expected one of {', '.join(AGENTS)} (or run_dir=PATH for a trained policy)"
        )
    env = {k[4:]: flat.pop(k) for k in list(flat) if k.startswith("env.")}
    for key in [*flat, *(f"env.{k}" for k in env if k not in env_keys)]:
        raise unknown(
            f"play option of an agent on task '{picked['task']}'",
            key,
            [*own, *(f"video.{k}" for k in VIDEO_KEYS), *(f"env.{k}" for k in env_keys)],
        )
    assert spec is not None  # an agent plays a task=ID (has_task)
    spec.cfg_class(**{**spec.cfg_overrides, **env})  # the env options' rules
    return picked, video, env


def run(args: Arguments) -> None:
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads(cuda_cap=4)
    for path in play(args.options):
        print(f"{path}  ({path.stat().st_size / 1024:.0f} KiB)", flush=True)


def play(args: list[str]) -> list[Path]:
    """Write the video the arguments ask for; returns its files."""
    picked, video, rest = split_arguments(args)
    from refpo_warp.render.gl import select_gl_platform

    select_gl_platform()  # before anything imports MuJoCo
    if "run_dir" in picked:
        return _play_run(Path(str(picked["run_dir"])), picked.get("checkpoint"), rest, video)
    return _play_agent(
        str(picked["task"]),
        str(picked["agent"]),
        str(picked.get("device", "cpu")),
        Path(str(picked.get("out", "runs/videos"))),
        video,
        rest,
    )


def _play_run(run_dir: Path, checkpoint, overrides: dict, video: VideoOptions) -> list[Path]:
    from refpo_warp.config.saved import load_run
    from refpo_warp.evaluation.videos import VIDEO_DIR, policy_panels, record
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest
    from refpo_warp.utils.device import resolve_device

    if checkpoint is not None and not isinstance(checkpoint, str):
        raise ConfigError(f"checkpoint={checkpoint!r} is invalid; expected a path to a model_<iteration>.pt file")
    run = load_run(run_dir, overrides)
    cfg, task = run.cfg, run.task
    env_options = {**cfg["env"], **cfg["eval"]["env"]}
    from refpo_warp.envs.registry import make_env

    host = make_env(
        task, num_envs=video.num_envs, device=resolve_device(cfg["device"]), seed=cfg["seed"], **env_options
    )
    _, runner = build_runner(run, None, env=host)
    if checkpoint is not None:
        runner.load(checkpoint, map_location=runner.device)
    else:
        load_latest(runner, run_dir, cfg["task"], cfg["algo"])
    iteration = runner.current_learning_iteration
    panels, tag = policy_panels(cfg, runner.get_inference_policy(device=runner.device), video)
    seed = cfg["seed"] if video.seed is None else video.seed
    return record(
        task, env_options, runner.device, panels, video, run_dir / VIDEO_DIR, f"model_{iteration}_{tag}", seed
    )


def _play_agent(task: str, agent: str, device: str, out: Path, video: VideoOptions, env_options: dict) -> list[Path]:
    from refpo_warp.evaluation.videos import agent_policy, record
    from refpo_warp.utils.device import resolve_device

    seed = 0 if video.seed is None else video.seed
    policies = {f"{agent} agent": agent_policy(agent, seed)}
    return record(task, env_options, resolve_device(device), policies, video, out, f"{task}_{agent}", seed)
