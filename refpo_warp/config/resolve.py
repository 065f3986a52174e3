"""A run's config: the YAML layers (``refpo_warp/config/layers.py``) and the command line's ``key=value``
overrides merged into one config and validated key by key (``refpo_warp/config/validate.py``), before anything
is built or written. The task, algo and base files are found along the config path: the folder of the run option
``config_dir`` and those of ``REFPO_CONFIG_PATH``, then the shipped ``configs/`` (``refpo_warp/config/config_path.py``).

``resolve_config(["task=dmc_cheetah_run", "algo=fpo", "algorithm.learning_rate=1e-4"])`` returns the config as a
nested dict; ``resolve(...)`` also says which layer set each key (``refpo train ... --explain KEY``).
Env options may be given without their ``env.`` prefix (``motion_file=...``). A key given twice (on the command line
or in one YAML mapping) is an error.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from refpo_warp.config.config_set import ConfigFile, ConfigSet, config_set
from refpo_warp.config.dotted import flatten, merge, parse_overrides, set_dotted
from refpo_warp.config.layers import PROFILE_KEYS, Layer, run_layers
from refpo_warp.config.run_options import check_combinations, run_defaults
from refpo_warp.config.validate import validate
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.utils.errors import ConfigError

COMMAND_LINE = "command line"


@dataclass
class Resolution:
    """A resolved config and the spec of its task (``task``), resolved once and handed down together to whatever
    builds, trains, evaluates or records the run; and, per dotted key, every layer that set it with the value it gave
    (in order) and the comment the last of them gives it on its line (``notes``)."""

    cfg: dict
    task: TaskSpec
    sources: dict[str, list[tuple[str, Any]]] = field(default_factory=dict)
    layers: list[Layer] = field(default_factory=list)
    notes: dict[str, str] = field(default_factory=dict)


def run_config_set(flat: dict[str, Any]) -> ConfigSet:
    """The config files of a run: those of its ``config_dir`` option, of ``REFPO_CONFIG_PATH`` and the shipped ones."""
    config_dir = flat.get("config_dir")
    if config_dir is not None and not isinstance(config_dir, str):
        raise ConfigError(f"config_dir={config_dir!r} is invalid; expected the path of a folder")
    return config_set(config_dir)


def identity(flat: dict[str, Any]) -> tuple[str, str]:
    """The task and algo a flat override dict asks for (their fields' defaults when not given)."""
    defaults = run_defaults()
    return str(flat.get("task", defaults["task"])), str(flat.get("algo", defaults["algo"]))


def _with_env_prefix(flat: dict[str, Any], task: TaskSpec, defaults: dict) -> dict[str, Any]:
    """Env options given without the ``env.`` prefix (``motion_file=clips/``) under their prefixed key."""
    fields = task.cfg_class.defaults()
    out = dict(flat)
    for key in [k for k in flat if "." not in k and k not in defaults and k in fields]:
        if f"env.{key}" in flat:
            raise ConfigError(f"'{key}' and 'env.{key}' are the same option, given twice; give it once")
        out[f"env.{key}"] = out.pop(key)
    return out


def _device_type(flat: dict[str, Any], defaults: dict, files: tuple[ConfigFile, ...]) -> str:
    """``cpu`` or ``cuda``: the type of the device the run asks for (the command line's, else the last of the task's
    files that sets one, else the default)."""
    from refpo_warp.utils.device import resolve_device

    device = defaults["device"]
    for file in files:
        device = file.data.get("device", device)
    return resolve_device(str(flat.get("device", device))).split(":")[0]


def resolve(overrides: list[str] | dict[str, Any] | None = None, device_type: str | None = None) -> Resolution:
    """Merge the layers and the overrides, validate, and keep where every key came from.

    Args:
        overrides: ``["task=dmc_cheetah_run", "algorithm.reflow_coef=0.1", ...]`` or an equivalent dotted dict.
        device_type: ``"cpu"`` or ``"cuda"`` profile to apply; default: from the resolved ``device``.
    """
    flat = parse_overrides(overrides) if isinstance(overrides, list) else dict(overrides or {})
    configs = run_config_set(flat)
    if flat.get("config_dir"):  # saved with the run as an absolute path: its evaluation finds it from anywhere
        flat["config_dir"] = str(Path(flat["config_dir"]).expanduser().resolve())
    task, algo = identity(flat)
    flat = {k: v for k, v in flat.items() if k not in ("task", "algo")}
    for key in flat:
        if key.split(".")[0] in PROFILE_KEYS:
            raise ConfigError(f"'{key}' is a config-file key, not a run option")
    spec, task_files, algo_files = configs.run_files(task, algo)
    defaults = run_defaults()
    flat = _with_env_prefix(flat, spec, defaults)
    if device_type is None:
        device_type = _device_type(flat, defaults, task_files)
    layers = run_layers(configs.defaults, task_files, algo_files, device_type)
    cfg: dict = {}
    sources: dict[str, list[tuple[str, Any]]] = {}
    notes: dict[str, str] = {}
    for layer in layers:
        cfg = merge(cfg, layer.values)
        for key, value in flatten(layer.values).items():
            sources.setdefault(key, []).append((layer.source, value))
            if key in layer.notes:
                notes[key] = layer.notes[key]
            else:
                notes.pop(key, None)
    for key, value in flat.items():
        set_dotted(cfg, key, value)
        sources.setdefault(key, []).append((COMMAND_LINE, value))
        notes.pop(key, None)
    cfg["task"], cfg["algo"] = task, algo
    cfg = validate(cfg, defaults, spec)
    check_combinations(cfg)
    return Resolution(cfg, spec, sources, [*layers, Layer(COMMAND_LINE, {})], notes)


def resolve_config(overrides: list[str] | dict[str, Any] | None = None, device_type: str | None = None) -> dict:
    """The validated config of a run (see ``resolve``)."""
    return resolve(overrides, device_type).cfg
