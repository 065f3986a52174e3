"""Error types and the 'did you mean' helper shared by configs, the task registry and data loaders."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class ConfigError(ValueError):
    """A configuration key, value or task id is invalid."""


class NonFiniteLossError(FloatingPointError):
    """A training loss or statistic became NaN or infinite; training stops before the bad step is applied."""


class MotionDataError(ValueError):
    """A motion file is malformed; the message names the file and the problem."""


def closest(name: str, choices: Iterable[str]) -> str | None:
    """Return the valid choice closest to ``name`` (or None when nothing is close)."""
    choices = list(choices)
    match = difflib.get_close_matches(name, choices, n=1, cutoff=0.4)
    if match:
        return match[0]
    # Fall back to a prefix/suffix match so short typos of long dotted keys still get a suggestion.
    leaf = name.rsplit(".", 1)[-1]
    for choice in choices:
        if choice.rsplit(".", 1)[-1] == leaf:
            return choice
    return None


def unknown(kind: str, name: str, choices: Iterable[str]) -> ConfigError:
    """Build the error for an unknown ``kind`` (task, key, ...) that names the closest valid choice."""
    choices = sorted(choices)
    suggestion = closest(name, choices)
    hint = f" Did you mean '{suggestion}'?" if suggestion else ""
    return ConfigError(f"Unknown {kind} '{name}'.{hint} Valid choices: {', '.join(choices)}")
