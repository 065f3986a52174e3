"""``refpo play``: a video of what a trained policy (or a zero / random agent) does in its task.

A run is loaded as ``refpo eval`` loads it (its saved config with the run options given over it, the newest usable
checkpoint or ``checkpoint=``, read with ``weights_only``) and plays its evaluation protocol (``eval.env``,
``eval.initial_noise``: one panel per N and protocol, ``eval.perturbation``); the video goes to
``<run dir>/videos/``, without a run to ``out=`` (default ``runs/videos``). The names are ``refpo train``'s: the video
options ``video.<key>`` (``refpo_warp/render/options.py``), env options ``env.<key>``, the evaluation's
``eval.<key>``. Every option is checked before anything is built.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from refpo_warp.config.command_options import EXPLAIN, command_help, explain_options, option_names, parse_options
from refpo_warp.config.dotted import parse_overrides
from refpo_warp.render.options import VideoOptions
from refpo_warp.utils.command_line import Arguments
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import DEVICE_DOC, DEVICE_RULE, OneOf, Text
from refpo_warp.utils.options import option
from refpo_warp.utils.renamed_spellings import renamed_error

AGENTS = ("zero", "random")


@dataclass(frozen=True)
class PlayOptions:
    run_dir: str | None = option(None, Text(optional=True), "a trained run whose policy plays (refpo train's run dir)")
    checkpoint: str | None = option(
        None, Text(optional=True), "a checkpoint of the run (default: its newest usable one)"
    )
    task: str | None = option(None, Text(optional=True), "the task an agent plays (with agent=; a run plays its own)")
    agent: str | None = option(None, OneOf(None, *AGENTS), "zero or random: an agent instead of a trained policy")
    device: str = option("auto", DEVICE_RULE, DEVICE_DOC + "; a run's: its config's unless given")
    out: str = option("runs/videos", Text(), "the folder of an agent's video (a run's go to <run dir>/videos)")


SUMMARY = "a video of a trained policy (one flow step beside ten) or of a zero / random agent"
USAGE = command_help(
    """A video of a policy: refpo play run_dir=PATH [checkpoint=PATH] [video.flow_steps=[1,10]]
                   [eval.initial_noise=[random,zero]] [video.num_envs=4] [run options] [video options]
                   or: refpo play task=<task id> agent=zero|random [env.<option>=...] [out=DIR] [video options]""",
    """Writes <run dir>/videos/<name>.mp4 (video.format=gif or both for a GIF) and prints its path.
video.flow_steps=[1,10] shows the 1-step and the 10-step policy side by side from the same initial states;
eval.initial_noise=[random,zero] each N under both initial-noise protocols (the run's by default); any other run
option (device=, eval.env.<option>=, ...) applies over the run's saved config, as in refpo eval. Video options, named
as in refpo train: [video.length=300] [video.width=640] [video.height=480] [video.camera=track]
[video.format=mp4|gif|both] [video.fps=30] [video.seed=3] [video.name=NAME] [video.shadows=false]
[video.reference=true] (refpo_warp/render/options.py, docs/videos.md).""",
    PlayOptions,
)
FLAGS = (EXPLAIN,)
SUBJECTS = 0
RUN_KEYS = ("run_dir", "checkpoint", "device")  # a run's; the rest of its arguments are run options over its config
AGENT_KEYS = ("task", "agent", "device", "out")
TRAINING_ONLY = ("at_end", "interval")  # video options that say when a training run records
VIDEO_KEYS = tuple(k for k in VideoOptions.__dataclass_fields__ if k not in TRAINING_ONLY)


def spelling_error(key: str, env_keys: tuple[str, ...]) -> ConfigError | None:
    """The refusal, naming what to write instead, of a key spelled the way refpo play once took it (a bare video or env
    option, a renamed one) or of a video option that only a training run takes (``video.at_end``, bare ``at_end``)."""
    renamed = renamed_error("play", f"{key}=")
    if renamed is not None:
        return renamed
    name = key.removeprefix("video.")
    if name in TRAINING_ONLY:
        return ConfigError(
            f"'{key}=': video.{name} says when a training run records (refpo train ... video.{name}=...); refpo play "
            f"records now: leave it out (the video options refpo play takes: "
            f"{', '.join(f'video.{k}' for k in VIDEO_KEYS)})"
        )
    if key in VIDEO_KEYS:
        return ConfigError(f"'{key}=' is spelled 'video.{key}=' (refpo play names options as refpo train does)")
    if key in env_keys:
        return ConfigError(f"'{key}=' is spelled 'env.{key}=' (refpo play names options as refpo train does)")
    return None


def check_spellings(flat: dict[str, Any], own: tuple[str, ...], env_keys: tuple[str, ...] = ()) -> None:
    """Every key but the command's own (``own``) checked by ``spelling_error``; the first refused raises."""
    for key in (k for k in flat if k not in own):  # an env option may share a name of ours (DMC's `task`)
        error = spelling_error(key, env_keys)
        if error is not None:
            raise error


def split_arguments(args: list[str]) -> tuple[PlayOptions, VideoOptions, dict[str, Any]]:
    """(the play options, the video options, the rest: a run's run options or an agent's env options), all
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
    check_spellings(flat, own, env_keys)
    video = VideoOptions.from_dict({k[6:]: flat.pop(k) for k in list(flat) if k.startswith("video.")})
    if has_run:  # every other key is a run option, checked over the saved config (load_run)
        options, rest = parse_options("play", PlayOptions, flat, lambda key: key not in RUN_KEYS)
        if "device" in flat:
            rest["device"] = options.device
        return options, video, rest
    choices = [*own, *(f"video.{k}" for k in VIDEO_KEYS), *(f"env.{k}" for k in env_keys)]
    for key in flat:
        if key not in own and not (key.startswith("env.") and key[4:] in env_keys):
            raise unknown(f"play option of an agent on task '{flat['task']}'", key, choices)
    options, passed = parse_options("play", PlayOptions, flat, lambda key: key.startswith("env."))
    if options.agent is None:
        raise ConfigError("refpo play task=... needs agent=zero|random (or run_dir=PATH for a trained policy)")
    env = {k[4:]: v for k, v in passed.items()}
    assert spec is not None  # an agent plays a task=ID (has_task)
    spec.cfg_class(**{**spec.cfg_overrides, **env})  # the env options' rules
    return options, video, env


def run(args: Arguments) -> None:
    if "--explain" in args.flags:
        own = tuple(option_names(PlayOptions))
        check_spellings(parse_overrides(args.options), own)  # what refpo play would refuse, refused here too
        rest = lambda key: key not in own  # noqa: E731  (run, video and env options: passed on)
        print(explain_options("play", PlayOptions, args.options, args.flag("--explain") or "", rest))
        return
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads(cuda_cap=4)
    for path in play(args.options):
        print(f"{path}  ({path.stat().st_size / 1024:.0f} KiB)", flush=True)


def play(args: list[str]) -> list[Path]:
    """Write the video the arguments ask for; returns its files."""
    options, video, rest = split_arguments(args)
    from refpo_warp.render.gl import select_gl_platform

    select_gl_platform()  # before anything imports MuJoCo
    if options.run_dir is not None:
        return _play_run(Path(options.run_dir), options.checkpoint, rest, video)
    assert options.task is not None and options.agent is not None  # split_arguments: an agent on a task
    return _play_agent(options.task, options.agent, options.device, Path(options.out), video, rest)


def _play_run(run_dir: Path, checkpoint, overrides: dict, video: VideoOptions) -> list[Path]:
    from refpo_warp.config.saved import load_run
    from refpo_warp.evaluation.evaluate_policy import eval_env_options
    from refpo_warp.evaluation.videos import VIDEO_DIR, policy_panels, record
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest
    from refpo_warp.utils.device import resolve_device

    run = load_run(run_dir, overrides)
    cfg, task = run.cfg, run.task
    env_options = eval_env_options(cfg)
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
