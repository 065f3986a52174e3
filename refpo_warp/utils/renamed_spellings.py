"""The one table of spellings a command once took and the names they have now (``docs/cli.md``, "One spelling per
concept"). The command-line parsers (``refpo_warp/utils/command_line.py`` for ``--flags``,
``refpo_warp/config/command_options.py`` for ``key=``) refuse an old spelling with its new name (exit 2)."""

from __future__ import annotations

from refpo_warp.utils.errors import ConfigError


def _keys(*names: str) -> dict[str, str]:
    """``--num-envs`` -> ``num_envs=``: flags that became options of the same name."""
    return {f"--{n.replace('_', '-')}": f"{n}=" for n in names}


_BENCH = _keys("device", "num_envs") | {"--envs": "num_envs="}

# command -> {old spelling -> its name now}; a flag is written --flag, an option key=
RENAMED: dict[str, dict[str, str]] = {
    "train": {"--tasks": "--list-tasks"},
    "report": {
        **_keys("out", "latency", "curve_methods", "ratio_tasks", "ratio_methods"),
        "--seed": "ratio_seed=",
        "seed=": "ratio_seed=",
    },
    "plot": {"sweep=": "refpo plot <sweep dir>", "run_dir=": "run_dirs=[A,B]", "--out": "out="},
    "play": {"initial_noise=": "eval.initial_noise="},
    "collect": {"sample=": "initial_noise= (random or zero, as eval.initial_noise)"},
    "sweep": {"task=": "tasks=", "algo=": "methods=", "seed=": "seeds=", "run_dir=": "out="},
    "tune": {"task=": "the tuning file's tasks", "algo=": "methods=", "seed=": "the tuning file's seed"},
    "bench dmc": {**_BENCH, **_keys("tasks"), "--seconds": "timed_seconds=", "--no-mujoco-c": "mujoco_c=false"},
    "bench humanoid": {
        **_BENCH,
        **_keys("task"),
        "--steps": "timed_steps=",
        "--warmup": "warmup_steps=",
        "--no-mujoco-c": "mujoco_c=false",
        "--json": "out=PATH (the result as JSON)",
        "--env": "env.<option>=",
    },
    "bench train": {"run_dir=": "out= (the result as JSON; the timed runs live in a temporary folder)"},
    "bench gridworld": {**_BENCH, **_keys("gym_steps")},
    "bench latency": {
        **_BENCH,
        **_keys("tasks", "algos", "flow_steps", "repeats"),
        "--batch": "batch_sizes=",
        "--json": "out=",
    },
    "bench algorithms": {
        **_BENCH,
        **_keys("task", "algos", "repeats"),
        "--steps": "num_steps_per_env=",
        "--minibatches": "num_mini_batches=",
        "--passes": "num_learning_epochs=",
    },
    "bench render": {
        **_keys("width", "height"),
        "--frames": "timed_frames=",
        "--seconds": "video_seconds=",
    },
    "convert-amass": _keys("fps"),
    "make-clips": _keys("random", "seed", "schema", "fps", "float32"),
    "mjlab evaluate": {},
}


def renamed_error(command: str, spelling: str) -> ConfigError | None:
    """The error for ``spelling`` (``--flag`` or ``key=``) if ``command`` once took it, else None."""
    new = RENAMED.get(command, {}).get(spelling)
    if new is None:
        return None
    return ConfigError(f"refpo {command}: '{spelling}' is spelled '{new}' now; see refpo {command} --help")
