"""The config files a run can be made of, found once along a config path (``refpo_warp/config/config_path.py``) into
one immutable ``ConfigSet``: ``default.yaml``, every ``task/<name>.yaml`` and ``algo/<name>.yaml`` by name, and the
tasks the user's folders add.

A task file of the user's folders whose name is no registered task id adds that id: a variant of the registered task
its ``base`` chain names (its env, env cfg and the env options that id fixes), trained with the file's settings over
that task's::

    # my_configs/task/gridworld_small.yaml: `refpo train task=gridworld_small config_dir=my_configs`
    base: gridworld
    num_envs: 8
    env: {max_episode_length: 100}

A file whose name is a registered id is that task's config (a task registered by code without a config file). The
variants live in the set that found them: nothing is registered, so ``ConfigSet.task`` is where their spec is looked
up, once, when a run's config is resolved (``Resolution.task``, handed down with the config). A run's files are read
when the run takes them (``run_files``: each file with its ``base`` chain, bases first, each read once).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

from refpo_warp.config.config_path import DEFAULT_FILE, ConfigPath, config_path
from refpo_warp.config.yaml_files import key_comments, load_yaml
from refpo_warp.envs.registry import get_task, list_tasks
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.paths import PACKAGED_CONFIG_DIR, shown

PROFILE_KEYS = ("base", "by_device", "by_algo")
DEVICE_TYPES = ("cpu", "cuda")


@dataclass(frozen=True)
class ConfigFile:
    """One config file as read: its values and, by dotted key, the comment it gives a value on its line."""

    path: Path
    data: dict
    comments: Mapping[str, str]

    @classmethod
    def read(cls, path: Path) -> ConfigFile:
        return cls(path, load_yaml(path), MappingProxyType(key_comments(path)))

    @property
    def name(self) -> str:
        return self.path.stem

    def bases(self) -> list[str]:
        """The names its ``base`` key gives (a name or a list of names)."""
        base = self.data.get("base")
        if base is None:
            return []
        if isinstance(base, str):
            return [base]
        if isinstance(base, list) and all(isinstance(b, str) for b in base):
            return base
        raise ConfigError(
            f"{shown(self.path)}: 'base' must name a file of the same kind or a list of them, got {base!r}"
        )


Chain = tuple[ConfigFile, ...]


@dataclass(frozen=True)
class ConfigSet:
    """The config files of a config path, found once: ``default.yaml`` (read), the task and algo files by name, and
    the tasks the user's task files add (``variants``: their spec and their file's ``base`` chain, as read)."""

    path: ConfigPath
    defaults: ConfigFile
    tasks: Mapping[str, Path]
    algos: Mapping[str, Path]
    variants: Mapping[str, tuple[TaskSpec, Chain]]

    @classmethod
    def read(cls, path: ConfigPath) -> ConfigSet:
        tasks, algos, registered = path.files("task"), path.files("algo"), list_tasks()
        variants = {
            name: _variant(name, file, tasks, registered)
            for name, file in tasks.items()
            if not name.startswith("_") and name not in registered and not file.is_relative_to(PACKAGED_CONFIG_DIR)
        }
        return cls(
            path,
            ConfigFile.read(DEFAULT_FILE),
            MappingProxyType(tasks),
            MappingProxyType(algos),
            MappingProxyType(variants),
        )

    def task_ids(self) -> list[str]:
        """Every ``task=`` choice: the registered tasks and the variants, sorted."""
        return sorted([*list_tasks(), *self.variants])

    def task(self, task_id: str) -> TaskSpec:
        """The spec of a task id (a variant's, else the registry's); an unknown one names the closest."""
        if task_id in self.variants:
            return self.variants[task_id][0]
        if task_id not in list_tasks():
            raise unknown("task", task_id, self.task_ids())
        return get_task(task_id)

    def identity(self, task_id: str, algo: str) -> TaskSpec:
        """The spec of a run's task, its task id and algo checked by name (an unknown one names the closest)."""
        spec = self.task(task_id)
        if algo not in self.algo_names():
            raise unknown("algo", algo, self.algo_names())
        return spec

    def run_files(self, task_id: str, algo: str) -> tuple[TaskSpec, Chain, Chain]:
        """What a run of ``task_id`` with ``algo`` is made of: the task's spec (``identity``), its file's ``base``
        chain and the algorithm's (``task_chain``, ``algo_chain``)."""
        return self.identity(task_id, algo), self.task_chain(task_id), self.algo_chain(algo)

    def algo_names(self) -> list[str]:
        """Every ``algo=`` choice: the files ``algo/<algo>.yaml`` (names not starting with ``_``)."""
        return sorted(name for name in self.algos if not name.startswith("_"))

    def task_file(self, task_id: str) -> Path:
        """The training config file of a task: its spec's ``config_file``, else ``task/<task>.yaml`` of the config
        path (where it is missing: the shipped folder's name for it, for the message)."""
        config_file = self.task(task_id).config_file
        if config_file is not None:
            return Path(config_file)
        return self.tasks.get(task_id) or PACKAGED_CONFIG_DIR / "task" / f"{task_id}.yaml"

    def task_chain(self, task_id: str) -> Chain:
        """The task's config file after its ``base`` chain, its ``by_algo`` and ``by_device`` sections checked."""
        if task_id in self.variants:
            chain = self.variants[task_id][1]
        else:
            path = self.task_file(task_id)
            if not path.exists():
                raise ConfigError(
                    f"task '{task_id}' is registered, but its config file {shown(path)} does not exist (every "
                    f"task needs one; it may hold just a 'base' line)"
                )
            chain = _chain(ConfigFile.read(path), "task", self.tasks, (task_id,))
        algos = self.algo_names()
        for file in chain:
            where = shown(file.path)
            for key in file.data.get("by_algo") or {}:
                if key not in algos:
                    raise unknown(f"algorithm under by_algo in {where}", key, algos)
            for device, profile in (file.data.get("by_device") or {}).items():
                if device not in DEVICE_TYPES:
                    raise unknown(f"device type under by_device in {where}", device, DEVICE_TYPES)
                for key in (profile or {}).get("by_algo") or {}:
                    if key not in algos:
                        raise unknown(f"algorithm under by_device.{device}.by_algo in {where}", key, algos)
        return chain

    def algo_chain(self, algo: str) -> Chain:
        """The algorithm's file after the algorithms it derives from (base first); each holds run options only."""
        if algo not in self.algos:
            raise unknown("algo", algo, self.algo_names())
        chain = _chain(ConfigFile.read(self.algos[algo]), "algo", self.algos, (algo,))
        for file in chain:
            extra = [k for k in file.data if k in PROFILE_KEYS[1:]]
            if extra:
                raise ConfigError(
                    f"{shown(file.path)}: an algo file holds run options (and 'base'), not {extra}; a task's "
                    f"settings for an algorithm go under by_algo in the task's file"
                )
        return chain


def _chain(file: ConfigFile, kind: str, named: Mapping[str, Path], seen: tuple[str, ...]) -> Chain:
    """``file`` after the files its ``base`` names (``<kind>/<base>.yaml`` of ``named``, recursively, bases first)."""
    out: list[ConfigFile] = []
    for base in file.bases():
        if base in seen:
            raise ConfigError(f"{shown(file.path)}: circular 'base' chain {' -> '.join(seen + (base,))}")
        if base not in named:
            raise unknown(f"base of {shown(file.path)} (a file {kind}/<name>.yaml of the config folders)", base, named)
        out += _chain(ConfigFile.read(named[base]), kind, named, seen + (base,))
    return (*out, file)


def _variant(name: str, file: Path, tasks: Mapping[str, Path], registered: list[str]) -> tuple[TaskSpec, Chain]:
    """A user's task file that adds a task id: the spec of the one registered task its ``base`` chain names."""
    chain = _chain(ConfigFile.read(file), "task", tasks, (name,))
    named = {f.name for f in chain[:-1]} & set(registered)
    if len(named) != 1:
        what = "names none" if not named else f"names several ({', '.join(sorted(named))})"
        raise ConfigError(
            f"{shown(file)}: a task file of your own either configures a registered task (its name is "
            f"the task id) or derives from exactly one with base: <task id>; its base chain {what}. "
            f"Registered tasks: {', '.join(registered)}"
        )
    base = get_task(named.pop())
    spec = TaskSpec(
        name,
        base.entry_point,
        base.cfg_class,
        dict(base.cfg_overrides),
        description=f"{base.description} (from {shown(file)})",
        config_file=file,
    )
    return spec, chain


def config_set(config_dir: str | Path | None = None) -> ConfigSet:
    """The config files of the ``config_dir`` option's folder, those of ``REFPO_CONFIG_PATH`` and the shipped ones."""
    return ConfigSet.read(config_path(config_dir))
