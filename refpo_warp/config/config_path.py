"""Where config files are found: the user's folders first, then the configs shipped in the package.

A user's folder has the layout of the shipped ``configs/``: ``task/<task>.yaml``, ``algo/<algo>.yaml`` and
``sweep/<name>.yaml`` (any of them). It is named by the run option ``config_dir=DIR`` (saved in the run's config, so
its evaluation finds the files again) and by the environment variable ``REFPO_CONFIG_PATH`` (folders separated by
``:``); its files are validated, explained and listed like the shipped ones (a task file that names no registered
task adds one: ``refpo_warp.config.config_set``). Each name is found in one folder only: a file that repeats a
name of another folder (a shipped one included) is an error; derive from it with ``base:`` instead. The run
options' defaults are their fields' (``refpo_warp/config/run_options.py``), the networks' shared settings the shipped
``default.yaml``'s: a ``default.yaml`` in a user's folder is refused.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.paths import PACKAGED_CONFIG_DIR, shown

ENV_VAR = "REFPO_CONFIG_PATH"
KINDS = ("task", "algo", "sweep", "tune")
DEFAULT_FILE = PACKAGED_CONFIG_DIR / "default.yaml"


@dataclass(frozen=True)
class ConfigPath:
    """The config folders searched, the user's (in the order given) before the shipped one."""

    user_dirs: tuple[Path, ...] = ()

    @property
    def dirs(self) -> tuple[Path, ...]:
        return (*self.user_dirs, PACKAGED_CONFIG_DIR)

    def files(self, kind: str, dirs: tuple[Path, ...] | None = None) -> dict[str, Path]:
        """Every ``<kind>/<name>.yaml`` of the folders by name; a name in two folders is an error naming both."""
        found: dict[str, Path] = {}
        for folder in self.dirs if dirs is None else dirs:
            for path in sorted((folder / kind).glob("*.yaml")):
                if path.stem in found:
                    raise ConfigError(
                        f"{shown(found[path.stem])} has the name of {shown(path)} ({kind} "
                        f"'{path.stem}'); give it another name (it may derive from the other with "
                        f"base: {path.stem})"
                    )
                found[path.stem] = path
        return found

    def find(self, kind: str, name: str) -> Path | None:
        """The file ``<kind>/<name>.yaml`` of the first folder that has it, or None."""
        return self.files(kind).get(name)

    def named_or_path(self, kind: str, source: str) -> Path:
        """A file named by ``source``: a path to a YAML file, or the name of a ``<kind>/<name>.yaml`` of the
        folders (a sweep, a tuning); a missing one names the valid names."""
        path = Path(source)
        if path.suffix in (".yaml", ".yml") or path.exists():
            if not path.is_file():
                raise ConfigError(f"{kind.capitalize()} file '{source}' not found")
            return path
        named = self.find(kind, source)
        if named is None:
            raise unknown(kind, source, self.names(kind))
        return named

    def names(self, kind: str) -> list[str]:
        """The choices of ``kind`` (``algo=`` values, sweep names, task files): names not starting with ``_``."""
        return sorted(name for name in self.files(kind) if not name.startswith("_"))

    def described(self, kind: str) -> list[tuple[str, str]]:
        """Each choice of ``kind`` (``names``) with its file's ``description:`` ('' where it has none)."""
        files = self.files(kind)
        return [(name, str(load_yaml(files[name]).get("description") or "")) for name in self.names(kind)]

    def user_files(self, kind: str) -> dict[str, Path]:
        """The ``kind`` files of the user's folders only (checked against the shipped names too)."""
        everything = self.files(kind)
        return {name: path for name, path in everything.items() if not path.is_relative_to(PACKAGED_CONFIG_DIR)}


def config_path(config_dir: str | Path | None = None, environ: Mapping[str, str] = os.environ) -> ConfigPath:
    """The folders of the ``config_dir`` option, then of ``REFPO_CONFIG_PATH``, then the shipped configs."""
    named = [(str(config_dir), "config_dir")] if config_dir else []
    named += [(part, ENV_VAR) for part in environ.get(ENV_VAR, "").split(os.pathsep) if part]
    dirs: list[Path] = []
    for value, where in named:
        folder = _user_folder(value, where)
        if folder not in dirs and folder != PACKAGED_CONFIG_DIR:
            dirs.append(folder)
    return ConfigPath(tuple(dirs))


def _user_folder(value: str, where: str) -> Path:
    folder = Path(value).expanduser().resolve()
    layout = "a folder holding task/, algo/ or sweep/ with YAML files in them, as the shipped configs/"
    if not folder.is_dir():
        raise ConfigError(f"{where}={value}: no such directory; expected {layout}")
    if not any((folder / kind).is_dir() for kind in KINDS):
        raise ConfigError(
            f"{where}={value}: has none of the folders {', '.join(k + '/' for k in KINDS)}; expected {layout}"
        )
    if (folder / DEFAULT_FILE.name).exists():
        raise ConfigError(
            f"{where}={value}: holds a {DEFAULT_FILE.name}, which is never read (the run options' "
            f"defaults are their fields', in refpo_warp/config/run_options.py); put your settings in a task or algo "
            f"file"
        )
    return folder
