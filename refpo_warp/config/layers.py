"""The layers a run's config is merged from, generic to specific, each named by the file (and section) it comes from.

Their order and what each holds is described once, in ``docs/cli.md`` ("The layers, generic to specific");
``generic_layers`` and ``specific_layers`` below build them in that order. Task, algo and base files are looked up along the config path
(``refpo_warp/config/config_path.py``): the user's folders, then the shipped ``configs/``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from refpo_warp.config.config_path import DEFAULT_FILE, ConfigPath
from refpo_warp.config.yaml_files import key_comments, load_yaml
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.paths import PACKAGED_CONFIG_DIR, shown

PROFILE_KEYS = ("base", "by_device", "by_algo")
DEVICE_TYPES = ("cpu", "cuda")


@dataclass(frozen=True)
class Layer:
    """One delta of the config, where it comes from (``configs/task/_dmc.yaml by_algo.refpo``) and, by dotted key,
    the comment the file gives a value on its line (why it is set: ``--explain`` prints it)."""

    source: str
    values: dict
    notes: dict = field(default_factory=dict)


def _notes(comments: dict[str, str], section: str = "") -> dict[str, str]:
    """A file's line comments (``key_comments``) of the keys under ``section`` (dotted), relative to it."""
    prefix = f"{section}." if section else ""
    return {k[len(prefix) :]: v for k, v in comments.items() if k.startswith(prefix)}


def algo_names(path: ConfigPath) -> list[str]:
    """Every ``algo=`` choice: the files ``algo/<algo>.yaml`` of the config path."""
    return path.names("algo")


def task_config_path(task: str, path: ConfigPath) -> Path:
    """The training config file of a registered task: its spec's ``config_file``, else ``task/<task>.yaml`` of the
    config path (where it is missing: the shipped folder's name for it, for the message)."""
    from refpo_warp.envs.registry import get_task

    config_file = get_task(task).config_file
    if config_file is not None:
        return Path(config_file)
    return path.find("task", task) or PACKAGED_CONFIG_DIR / "task" / f"{task}.yaml"


def _bases(data: dict, file: Path) -> list[str]:
    base = data.get("base")
    if base is None:
        return []
    if isinstance(base, str):
        return [base]
    if isinstance(base, list) and all(isinstance(b, str) for b in base):
        return base
    raise ConfigError(f"{shown(file)}: 'base' must name a file of the same kind or a list of them, got {base!r}")


def file_chain(file: Path, kind: str, path: ConfigPath, seen: tuple[str, ...] = ()) -> list[tuple[Path, dict]]:
    """``file`` and the files it names in ``base`` (``<kind>/<base>.yaml`` of the config path, recursively, bases
    first), each read once."""
    data = load_yaml(file)
    out: list[tuple[Path, dict]] = []
    for base in _bases(data, file):
        if base in seen:
            raise ConfigError(f"{shown(file)}: circular 'base' chain {' -> '.join(seen + (base,))}")
        found = path.find(kind, base)
        if found is None:
            raise unknown(
                f"base of {shown(file)} (a file {kind}/<name>.yaml of the config folders)", base, path.files(kind)
            )
        out += file_chain(found, kind, path, seen + (base,))
    return out + [(file, data)]


def task_files(task: str, path: ConfigPath) -> list[tuple[Path, dict]]:
    """The task's config file after its ``base`` chain (bases are task files of the config path)."""
    file = task_config_path(task, path)
    if not file.exists():
        raise ConfigError(
            f"task '{task}' is registered, but its config file {shown(file)} does not exist (every "
            f"task needs one; it may hold just a 'base' line)"
        )
    files = file_chain(file, "task", path, (task,))
    algos = algo_names(path)
    for file, data in files:
        for key in data.get("by_algo") or {}:
            if key not in algos:
                raise unknown(f"algorithm under by_algo in {shown(file)}", key, algos)
        for device, profile in (data.get("by_device") or {}).items():
            if device not in DEVICE_TYPES:
                raise unknown(f"device type under by_device in {shown(file)}", device, DEVICE_TYPES)
            for key in (profile or {}).get("by_algo") or {}:
                if key not in algos:
                    raise unknown(f"algorithm under by_device.{device}.by_algo in {shown(file)}", key, algos)
    return files


def algo_files(algo: str, path: ConfigPath) -> list[tuple[str, Path, dict]]:
    """(name, file, data) of the algorithm and the algorithms its file derives from, base first."""
    file = path.find("algo", algo)
    if file is None:
        raise unknown("algo", algo, algo_names(path))
    files = file_chain(file, "algo", path, (algo,))
    for found, data in files:
        extra = [k for k in data if k in PROFILE_KEYS[1:]]
        if extra:
            raise ConfigError(
                f"{shown(found)}: an algo file holds run options (and 'base'), not {extra}; a task's "
                f"settings for an algorithm go under by_algo in the task's file"
            )
    return [(found.stem, found, data) for found, data in files]


def _without_profiles(data: dict) -> dict:
    return {k: v for k, v in data.items() if k not in PROFILE_KEYS and not k.startswith("_")}


def generic_layers(task: str, path: ConfigPath) -> list[Layer]:
    """Layers 1 and 2: the defaults and what the task sets for every algorithm and device."""
    layers = [Layer(shown(DEFAULT_FILE), load_yaml(DEFAULT_FILE), key_comments(DEFAULT_FILE))]
    return layers + [
        Layer(shown(file), _without_profiles(data), key_comments(file)) for file, data in task_files(task, path)
    ]


def specific_layers(task: str, algo: str, device_type: str, path: ConfigPath) -> list[Layer]:
    """Layers 3 and 4: the task's device profile, then each algorithm of the chain with the task's settings for it."""
    files = task_files(task, path)
    comments = {file: key_comments(file) for file, _ in files}  # each task file read once for all its sections
    profiles = [(file, dict((data.get("by_device") or {}).get(device_type) or {})) for file, data in files]
    layers = [
        Layer(
            f"{shown(file)} by_device.{device_type}",
            {k: v for k, v in p.items() if k != "by_algo"},
            _notes(comments[file], f"by_device.{device_type}"),
        )
        for file, p in profiles
    ]
    for name, file, data in algo_files(algo, path):
        layers.append(Layer(shown(file), _without_profiles(data), key_comments(file)))
        layers += [
            Layer(
                f"{shown(file)} by_algo.{name}",
                (d.get("by_algo") or {}).get(name) or {},
                _notes(comments[file], f"by_algo.{name}"),
            )
            for file, d in files
        ]
        section = f"by_device.{device_type}.by_algo.{name}"
        layers += [
            Layer(f"{shown(file)} {section}", (p.get("by_algo") or {}).get(name) or {}, _notes(comments[file], section))
            for file, p in profiles
        ]
    return [layer for layer in layers if layer.values]
