"""The layers a run's config is merged from, generic to specific, each named by the file (and section) it comes from.

Their order and what each holds is described once, in ``docs/cli.md`` ("The layers, generic to specific");
``run_layers`` below builds them in that order: the run options' fields (``refpo_warp/config/run_options.py``), then
from files already read: ``default.yaml`` (the networks' shared settings), the task's and the algorithm's ``base``
chains (``refpo_warp/config/config_set.py``, which finds them along the config path: the user's folders, then the
shipped ``configs/``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from refpo_warp.config.config_set import DEVICE_TYPES, PROFILE_KEYS, Chain, ConfigFile
from refpo_warp.config.run_options import run_defaults
from refpo_warp.utils.paths import shown

__all__ = ["DEVICE_TYPES", "PROFILE_KEYS", "RUN_DEFAULTS", "Layer", "run_layers"]

RUN_DEFAULTS = "the run options' defaults (refpo_warp/config/run_options.py)"  # the first layer's name


@dataclass(frozen=True)
class Layer:
    """One delta of the config, where it comes from (``configs/task/_dmc.yaml by_algo.refpo``) and, by dotted key,
    the comment the file gives a value on its line (why it is set: ``--explain`` prints it)."""

    source: str
    values: dict
    notes: Mapping[str, str] = field(default_factory=dict)


def _notes(comments: Mapping[str, str], section: str = "") -> dict[str, str]:
    """A file's line comments (``key_comments``) of the keys under ``section`` (dotted), relative to it."""
    prefix = f"{section}." if section else ""
    return {k[len(prefix) :]: v for k, v in comments.items() if k.startswith(prefix)}


def _without_profiles(data: dict) -> dict:
    return {k: v for k, v in data.items() if k not in PROFILE_KEYS and not k.startswith("_")}


def _whole(file: ConfigFile) -> Layer:
    return Layer(shown(file.path), _without_profiles(file.data), file.comments)


def run_layers(defaults: ConfigFile, task: Chain, algo: Chain, device_type: str) -> list[Layer]:
    """The layers of a run, generic to specific: 1 and 2, the defaults (the run options' fields, then ``default.yaml``)
    and what the task's files set for every algorithm and device; 3 and 4, the task's device profile, then each
    algorithm of the chain with the task's settings for it (empty layers left out)."""
    generic = [Layer(RUN_DEFAULTS, run_defaults()), Layer(shown(defaults.path), defaults.data, defaults.comments)]
    generic += [_whole(file) for file in task]
    profiles = [(file, dict((file.data.get("by_device") or {}).get(device_type) or {})) for file in task]
    device = f"by_device.{device_type}"
    layers = [
        Layer(
            f"{shown(file.path)} {device}",
            {k: v for k, v in p.items() if k != "by_algo"},
            _notes(file.comments, device),
        )
        for file, p in profiles
    ]
    for algo_file in algo:
        name = algo_file.name
        layers.append(_whole(algo_file))
        layers += [
            Layer(
                f"{shown(file.path)} by_algo.{name}",
                (file.data.get("by_algo") or {}).get(name) or {},
                _notes(file.comments, f"by_algo.{name}"),
            )
            for file in task
        ]
        section = f"{device}.by_algo.{name}"
        layers += [
            Layer(
                f"{shown(file.path)} {section}",
                (p.get("by_algo") or {}).get(name) or {},
                _notes(file.comments, section),
            )
            for file, p in profiles
        ]
    return generic + [layer for layer in layers if layer.values]
