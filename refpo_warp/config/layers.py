"""The layers a run's config is merged from, generic to specific, each named by the file (and section) it comes from.

For task T, algorithm A (whose algo file may name a ``base`` algorithm: A's chain is base first, then A) and the
device type D (cpu | cuda), later layers win:

1. ``configs/default.yaml``: every run option and its default;
2. T's task file, after the task files it names in ``base``: settings for every algorithm;
3. their ``by_device.D``: the device profile for every algorithm;
4. for each algorithm a of A's chain, base first: ``configs/algo/<a>.yaml``, then the task files' ``by_algo.<a>``,
   then their ``by_device.D.by_algo.<a>``;
5. the command line (``refpo_warp.config.resolve``).

So an algorithm's file beats what a task sets for every algorithm, and what a task sets for that algorithm beats
its file. A derived algorithm is its base with its own file's changes, on every task: ``fpo.yaml`` is ``base: refpo``
with ``reflow_coef: 0``, so FPO takes whatever a task sets for ReFPO (``by_algo.refpo``) except the coefficient.
An option no layer sets takes its constructor's default (for ``actor``, ``critic`` and ``algorithm``) or its env
cfg's default. Top-level keys of a task file that start with ``_`` are YAML anchors for reuse inside that file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.paths import CONFIG_DIR, REPO_ROOT

PROFILE_KEYS = ("base", "by_device", "by_algo")
DEVICE_TYPES = ("cpu", "cuda")


@dataclass(frozen=True)
class Layer:
    """One delta of the config and where it comes from (``configs/task/_dmc.yaml by_algo.refpo``)."""

    source: str
    values: dict


def _choices(kind: str) -> list[str]:
    return sorted(p.stem for p in (CONFIG_DIR / kind).glob("*.yaml") if not p.stem.startswith("_"))


def algo_names() -> list[str]:
    """Every ``algo=`` choice: the files ``configs/algo/<algo>.yaml``."""
    return _choices("algo")


def task_config_path(task: str) -> Path:
    """The training config file of a registered task: its spec's ``config_file``, else ``configs/task/<task>.yaml``."""
    from refpo_warp.envs.registry import get_task

    config_file = get_task(task).config_file
    return Path(config_file) if config_file is not None else CONFIG_DIR / "task" / f"{task}.yaml"


def shown(path: Path) -> str:
    """A config file's name as layers and messages show it (relative to the repository where it lies inside)."""
    try:
        return str(Path(path).resolve().relative_to(REPO_ROOT))
    except ValueError:
        return str(path)


def _bases(data: dict, path: Path) -> list[str]:
    base = data.get("base")
    if base is None:
        return []
    if isinstance(base, str):
        return [base]
    if isinstance(base, list) and all(isinstance(b, str) for b in base):
        return base
    raise ConfigError(f"{path}: 'base' must name a file of the same folder or a list of them, got {base!r}")


def _chain(path: Path, folder: Path, what: str, seen: tuple[str, ...] = ()) -> list[tuple[Path, dict]]:
    """``path`` and the files it names in ``base`` (recursively, bases first), each read once."""
    if not path.exists():
        raise ConfigError(f"{what} {path} does not exist")
    data = load_yaml(path)
    out: list[tuple[Path, dict]] = []
    for base in _bases(data, path):
        if base in seen:
            raise ConfigError(f"{path}: circular 'base' chain {' -> '.join(seen + (base,))}")
        out += _chain(folder / f"{base}.yaml", folder, f"base '{base}' of {path}:", seen + (base,))
    return out + [(path, data)]


def task_files(task: str) -> list[tuple[Path, dict]]:
    """The task's config file after its ``base`` chain (bases are ``configs/task/<base>.yaml``)."""
    path = task_config_path(task)
    what = f"task '{task}' is registered, but its config file"
    if not path.exists():
        raise ConfigError(f"{what} {path} does not exist (every task needs one; it may hold just a 'base' line)")
    files = _chain(path, CONFIG_DIR / "task", what, (task,))
    algos = algo_names()
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


def algo_files(algo: str) -> list[tuple[str, Path, dict]]:
    """(name, file, data) of the algorithm and the algorithms its file derives from, base first."""
    folder = CONFIG_DIR / "algo"
    files = _chain(folder / f"{algo}.yaml", folder, f"algorithm '{algo}':", (algo,))
    for path, data in files:
        extra = [k for k in data if k in PROFILE_KEYS[1:]]
        if extra:
            raise ConfigError(f"{path}: an algo file holds run options (and 'base'), not {extra}; a task's settings "
                              f"for an algorithm go under by_algo in the task's file")  # fmt: skip
    return [(path.stem, path, data) for path, data in files]


def _without_profiles(data: dict) -> dict:
    return {k: v for k, v in data.items() if k not in PROFILE_KEYS and not k.startswith("_")}


def generic_layers(task: str) -> list[Layer]:
    """Layers 1 and 2: the defaults and what the task sets for every algorithm and device."""
    layers = [Layer(shown(CONFIG_DIR / "default.yaml"), load_yaml(CONFIG_DIR / "default.yaml"))]
    return layers + [Layer(shown(path), _without_profiles(data)) for path, data in task_files(task)]


def specific_layers(task: str, algo: str, device_type: str) -> list[Layer]:
    """Layers 3 and 4: the task's device profile, then each algorithm of the chain with the task's settings for it."""
    files = task_files(task)
    profiles = [(path, dict((data.get("by_device") or {}).get(device_type) or {})) for path, data in files]
    layers = [Layer(f"{shown(path)} by_device.{device_type}", {k: v for k, v in p.items() if k != "by_algo"})
              for path, p in profiles]  # fmt: skip
    for name, path, data in algo_files(algo):
        layers.append(Layer(shown(path), _without_profiles(data)))
        layers += [Layer(f"{shown(file)} by_algo.{name}", (d.get("by_algo") or {}).get(name) or {})
                   for file, d in files]  # fmt: skip
        layers += [Layer(f"{shown(file)} by_device.{device_type}.by_algo.{name}",
                         (p.get("by_algo") or {}).get(name) or {}) for file, p in profiles]  # fmt: skip
    return [layer for layer in layers if layer.values]
