"""``refpo play``: a video of what a trained policy (or a zero / random agent) does in its task.

A run is loaded as ``refpo eval`` loads it (its saved config, the newest usable checkpoint or ``checkpoint=``,
read with ``weights_only``) and plays its evaluation protocol (``eval.env``, ``eval.initial_noise``,
``eval.perturbation``; ``initial_noise=`` replaces the run's protocols, one panel per N and protocol); the video goes
to ``<run dir>/videos/``, without a run to ``out=`` (default ``runs/videos``). Every option is checked before anything
is built; the video options are ``refpo_warp/render/options.py``'s.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refpo_warp.cli.arguments import Arguments
from refpo_warp.config.dotted import parse_overrides
from refpo_warp.render.options import VideoOptions
from refpo_warp.utils.errors import ConfigError, unknown

SUMMARY = "a video of a trained policy (one flow step beside ten) or of a zero / random agent"
USAGE = """A video of a policy: refpo play run_dir=PATH [checkpoint=PATH] [flow_steps=[1,10]]
                   [initial_noise=[random,zero]] [num_envs=4] [...]
                   or: refpo play task=<task id> agent=zero|random [env options] [out=DIR] [...]

Writes <run dir>/videos/<name>.mp4 (format=gif or both for a GIF) and prints its path. flow_steps=[1,10] shows the
1-step and the 10-step policy side by side from the same initial states; initial_noise=[random,zero] each N under
both initial-noise protocols (the run's eval.initial_noise by default). Video options: [length=300] [width=640]
[height=480] [camera=track] [format=mp4|gif|both] [fps=30] [seed=3] [name=NAME] [shadows=false] [reference=true]
[device=cpu] (refpo_warp/render/options.py, docs/videos.md).
"""
FLAGS = ()
SUBJECTS = 0
AGENTS = ("zero", "random")
RUN_KEYS = ("run_dir", "checkpoint", "device", "initial_noise")
AGENT_KEYS = ("task", "agent", "device", "out")


def split_arguments(args: list[str]) -> tuple[dict[str, Any], VideoOptions, dict[str, Any]]:
    """(the run or agent keys, the video options, the rest: env options of an agent's task), all checked."""
    flat = parse_overrides(args)
    video_keys = set(VideoOptions.__dataclass_fields__) - {"at_end", "interval"}
    has_run, has_task = "run_dir" in flat, "task" in flat
    if has_run == has_task:
        raise ConfigError("refpo play needs run_dir=PATH (a trained run) or task=ID agent=zero|random, not both")
    own = RUN_KEYS if has_run else AGENT_KEYS
    picked = {k: flat.pop(k) for k in list(flat) if k in own}
    video = VideoOptions.from_dict({k: flat.pop(k) for k in list(flat) if k in video_keys}, prefix="")
    if has_run and flat:
        key = next(iter(flat))
        raise unknown("play option", key, [*own, *sorted(video_keys)])
    if not has_run:
        from refpo_warp.envs.registry import get_task, list_tasks

        if str(picked["task"]) not in list_tasks():
            raise unknown("task", str(picked["task"]), list_tasks())
        agent = picked.get("agent")
        if agent not in AGENTS:
            raise ConfigError(f"agent={agent!r} is invalid; expected one of {', '.join(AGENTS)} (or run_dir=PATH for "
                              f"a trained policy)")  # fmt: skip
        cfg_class = get_task(str(picked["task"])).cfg_class
        for key in flat:
            if key not in cfg_class.defaults():
                raise unknown(f"play option or env option of task '{picked['task']}'", key,
                              [*own, *sorted(video_keys), *cfg_class.defaults()])  # fmt: skip
        cfg_class(**{**get_task(str(picked["task"])).cfg_overrides, **flat})  # the env options' rules
    return picked, video, flat


def run(args: Arguments) -> None:
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads(cuda_cap=4)
    for path in play(args.options):
        print(f"{path}  ({path.stat().st_size / 1024:.0f} KiB)", flush=True)


def play(args: list[str]) -> list[Path]:
    """Write the video the arguments ask for; returns its files."""
    picked, video, env_options = split_arguments(args)
    from refpo_warp.render.gl import select_gl_platform

    select_gl_platform()  # before anything imports MuJoCo
    if "run_dir" in picked:
        overrides = {f"eval.{k}" if k == "initial_noise" else k: picked[k] for k in ("device", "initial_noise")
                     if picked.get(k) is not None}  # fmt: skip
        return _play_run(Path(str(picked["run_dir"])), picked.get("checkpoint"), overrides, video)
    return _play_agent(str(picked["task"]), str(picked["agent"]), str(picked.get("device", "cpu")),
                       Path(str(picked.get("out", "runs/videos"))), video, env_options)  # fmt: skip


def _play_run(run_dir: Path, checkpoint, overrides: dict, video: VideoOptions) -> list[Path]:
    from refpo_warp.config.saved import load_run_config
    from refpo_warp.evaluation.videos import VIDEO_DIR, policy_panels, record
    from refpo_warp.runner.build import build_runner
    from refpo_warp.runner.checkpoints import load_latest
    from refpo_warp.utils.device import resolve_device

    if checkpoint is not None and not isinstance(checkpoint, str):
        raise ConfigError(f"checkpoint={checkpoint!r} is invalid; expected a path to a model_<iteration>.pt file")
    cfg = load_run_config(run_dir, overrides)
    env_options = {**cfg["env"], **cfg["eval"]["env"]}
    from refpo_warp.envs.registry import make_env

    host = make_env(cfg["task"], num_envs=video.num_envs, device=resolve_device(cfg["device"]), seed=cfg["seed"],
                    **env_options)  # fmt: skip
    _, runner = build_runner(cfg, None, env=host)
    if checkpoint is not None:
        runner.load(checkpoint, map_location=runner.device)
    else:
        load_latest(runner, run_dir, cfg["task"], cfg["algo"])
    iteration = runner.current_learning_iteration
    panels, tag = policy_panels(cfg, runner.get_inference_policy(device=runner.device), video)
    seed = cfg["seed"] if video.seed is None else video.seed
    return record(cfg["task"], env_options, runner.device, panels, video, run_dir / VIDEO_DIR,
                  f"model_{iteration}_{tag}", seed)  # fmt: skip


def _play_agent(task: str, agent: str, device: str, out: Path, video: VideoOptions, env_options: dict) -> list[Path]:
    from refpo_warp.evaluation.videos import agent_policy, record
    from refpo_warp.utils.device import resolve_device

    seed = 0 if video.seed is None else video.seed
    policies = {f"{agent} agent": agent_policy(agent, seed)}
    return record(task, env_options, resolve_device(device), policies, video, out, f"{task}_{agent}", seed)
