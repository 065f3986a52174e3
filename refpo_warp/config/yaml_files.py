"""Config files: a YAML mapping read with every problem named by its file (a key given twice included), and a
resolved config written atomically.

YAML 1.1 (PyYAML) reads ``3e-4`` as a string (its floats need a dot); ``ConfigLoader`` reads it as the number it is,
here and on the command line, so no option ever needs a string turned into a number.
"""

from __future__ import annotations

import re
from collections.abc import Hashable
from pathlib import Path
from typing import Any

import yaml

from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.errors import ConfigError


class ConfigLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """SafeLoader (libyaml's parser where PyYAML has it: configs, sweeps and results pages read hundreds of files)
    that reads ``1e-3`` as a float and refuses a key given twice in one mapping (YAML itself keeps the last one
    silently)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Hashable, Any]:
        seen: dict = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":  # '<<: *anchor' may be repeated and overridden
                continue
            key = self.construct_object(key_node, deep=True)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key '{key}' is given twice (also {seen[key]})", key_node.start_mark
                )
            seen[key] = f"line {key_node.start_mark.line + 1}"
        return super().construct_mapping(node, deep=deep)


ConfigLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),  # 1e-3, 3E+5, 2.5e-4: exponent floats
    list("-+0123456789"),
)


def key_comments(path: Path) -> dict[str, str]:
    """The comment at the end of the line of each key of a block mapping that holds a value, by dotted key
    (``algorithm.num_mc_samples: 16  # FPO++: rl_cfg.py:234`` gives ``{"algorithm.num_mc_samples": "FPO++: ..."}``):
    why a file sets a value, for ``--explain``. Keys inside a one-line ``{...}`` mapping share a line and get none."""
    try:
        text = Path(path).read_text(encoding="utf-8")
        root = yaml.compose(text, Loader=ConfigLoader)
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return {}
    lines = text.splitlines()
    out: dict[str, str] = {}

    def walk(node, prefix: str) -> None:
        if not isinstance(node, yaml.MappingNode):
            return
        for key_node, value in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = prefix + str(key_node.value)
            if isinstance(value, yaml.MappingNode):
                if not value.flow_style:
                    walk(value, key + ".")
            elif not node.flow_style and value.end_mark.line == key_node.start_mark.line:
                # after the value's end only blanks and a comment can follow on its line
                rest = lines[value.end_mark.line][value.end_mark.column :]
                if "#" in rest:
                    out[key] = rest.split("#", 1)[1].strip()

    walk(root, "")
    return out


def load_yaml(path: Path, error: type[Exception] = ConfigError) -> dict:
    """Read a YAML mapping; any problem (unreadable, not YAML, duplicate key, not a mapping) raises ``error``
    naming the file."""
    try:
        with open(path, encoding="utf-8") as f:
            data = yaml.load(f, Loader=ConfigLoader) or {}
    except FileNotFoundError as err:
        raise error(f"{path}: no such file") from err
    except (OSError, UnicodeDecodeError) as err:
        raise error(f"{path}: cannot be read ({err})") from err
    except yaml.YAMLError as err:
        raise error(f"{path}: not valid YAML ({' '.join(str(err).split())})") from err
    if not isinstance(data, dict):
        raise error(f"{path}: expected a mapping at the top level")
    return data


def dump_config(cfg: dict, path: Path) -> None:
    """Write a config as YAML (atomically), so a run can be reproduced and resumed from it."""
    write_text(path, yaml.safe_dump(cfg, sort_keys=False))
