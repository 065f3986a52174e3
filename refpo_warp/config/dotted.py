"""Nested configs and their dotted keys: deep merge, the flat ``section.key`` view, and the command line's
``key=value`` form."""

from __future__ import annotations

import copy
from typing import Any

import yaml

from refpo_warp.config.yaml_files import ConfigLoader
from refpo_warp.utils.errors import ConfigError

# Mappings that are values, not config sections: merged, validated and flattened as a whole (obs_groups has
# free-form group names; distribution_cfg is one class's constructor kwargs, replaced rather than merged key-wise).
LEAF_KEYS = ("obs_groups", "distribution_cfg")


def merge(base: dict, delta: dict) -> dict:
    """Deep-merge ``delta`` into a copy of ``base`` (mappings merge, everything else replaces)."""
    out = copy.deepcopy(base)
    for key, value in delta.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict) and key not in LEAF_KEYS:
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def flatten(cfg: dict, prefix: str = "") -> dict[str, Any]:
    """Dotted-key view of a nested config (``LEAF_KEYS`` mappings and empty sections stay whole)."""
    out: dict[str, Any] = {}
    for key, value in cfg.items():
        if isinstance(value, dict) and value and key not in LEAF_KEYS:
            out.update(flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def set_dotted(cfg: dict, key: str, value: Any) -> None:
    """Set ``section.sub.key`` in a nested config, creating sections on the way."""
    node = cfg
    parts = key.split(".")
    for part in parts[:-1]:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise ConfigError(f"Cannot set '{key}': '{part}' is not a section")
    node[parts[-1]] = value


def parse_overrides(args: list[str]) -> dict[str, Any]:
    """Parse ``key=value`` strings (values are YAML: numbers, bools, lists) into a flat dotted-key dict.

    ``--key=value`` and ``--key-name=value`` are accepted too; a key given twice is an error.
    """
    out: dict[str, Any] = {}
    given: dict[str, str] = {}
    for arg in args:
        if "=" not in arg:
            raise ConfigError(f"Expected key=value, got '{arg}' (example: task=gridworld seed=3 num_envs=256)")
        key, raw = arg.split("=", 1)
        key = key.strip().lstrip("-").replace("-", "_") if key.startswith("--") else key.strip()
        if not key:
            raise ConfigError(f"Expected key=value, got '{arg}': the key is empty")
        if key in given:
            raise ConfigError(f"'{key}' is given twice on the command line ('{given[key]}' and '{arg}'); give it once")
        given[key] = arg
        try:
            out[key] = yaml.load(raw, Loader=ConfigLoader) if raw != "" else ""
        except yaml.YAMLError:
            out[key] = raw
    return out
