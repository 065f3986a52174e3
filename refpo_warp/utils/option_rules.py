"""The rule types of options: the valid values of one option (``Int``, ``Real``, ``OneOf``, ``Flag``, ``Text``,
``ListOf``, ``Check``), each with ``check(key, value)``, which returns the value (normalised: a whole float becomes an
int, an ``Enum`` member its plain value) or raises a ``ConfigError`` that names the key and the valid values.

An option is declared as a field with its default, its rule and its doc (``refpo_warp.utils.options.option``); this
module only holds the rule types. ``fixed=True`` marks an option that may not change when a run is resumed (it changes
the model or the spaces); without ``fixed``, actor and critic options are fixed and all others may change
(``fixed=False`` frees an actor option such as the number of flow steps).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from enum import Enum
from typing import Any

from refpo_warp.utils.errors import ConfigError


class Rule:
    """Valid values of one option; ``check`` returns the value (normalised) or raises ``ConfigError``."""

    def __init__(self, optional: bool = False, fixed: bool | None = None) -> None:
        self.optional = optional  # null (None) is valid
        self.fixed = fixed  # may not change on resume (None: the section's default)

    def check(self, key: str, value: Any) -> Any:
        if value is None and self.optional:
            return None
        if value is None:
            raise self.error(key, value)
        return self._check(key, value)

    def _check(self, key: str, value: Any) -> Any:
        return value

    def describe(self) -> str:
        return "any value"

    def with_fixed(self, fixed: bool | None) -> Rule:
        """The same rule with another resume behaviour."""
        rule = copy.copy(self)
        rule.fixed = fixed
        return rule

    def error(self, key: str, value: Any, why: str = "") -> ConfigError:
        expected = ("null or " if self.optional else "") + self.describe()
        return ConfigError(f"{key}={_show(value)} is invalid{': ' + why if why else ''}; expected {expected}")


class Num(Rule):
    """A finite number in [lo, hi] (``lo_open``/``hi_open`` exclude the bound); ``integer`` requires a whole number."""

    def __init__(
        self,
        lo: float | None = None,
        hi: float | None = None,
        *,
        integer: bool = False,
        lo_open: bool = False,
        hi_open: bool = False,
        multiple_of: int | None = None,
        optional: bool = False,
        fixed: bool | None = None,
    ) -> None:
        super().__init__(optional, fixed)
        self.lo, self.hi, self.integer = lo, hi, integer
        self.lo_open, self.hi_open, self.multiple_of = lo_open, hi_open, multiple_of

    def _check(self, key: str, raw: Any) -> Any:
        value = raw
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(key, raw)
        if not math.isfinite(value):
            raise self.error(key, raw, "not a finite number")
        if self.integer:
            if value != int(value):
                raise self.error(key, raw, "not a whole number")
            value = int(value)
        else:
            value = float(value)
        below = self.lo is not None and (value <= self.lo if self.lo_open else value < self.lo)
        above = self.hi is not None and (value >= self.hi if self.hi_open else value > self.hi)
        if below or above:
            raise self.error(key, raw, "out of range")
        if self.multiple_of and value % self.multiple_of:
            raise self.error(key, raw, f"not a multiple of {self.multiple_of}")
        return value

    def describe(self) -> str:
        kind = "an integer" if self.integer else "a number"
        if self.multiple_of:
            kind = f"{kind} multiple of {self.multiple_of}"
        if self.lo is not None and self.hi is not None:
            left, right = "(" if self.lo_open else "[", ")" if self.hi_open else "]"
            return f"{kind} in {left}{_fmt(self.lo)}, {_fmt(self.hi)}{right}"
        if self.lo is not None:
            return f"{kind} {'>' if self.lo_open else '>='} {_fmt(self.lo)}"
        if self.hi is not None:
            return f"{kind} {'<' if self.hi_open else '<='} {_fmt(self.hi)}"
        return f"a finite {kind.removeprefix('a ')}"


def Int(lo: int | None = None, hi: int | None = None, **kwargs) -> Num:
    """An integer in [lo, hi]."""
    return Num(lo, hi, integer=True, **kwargs)


def Real(lo: float | None = None, hi: float | None = None, **kwargs) -> Num:
    """A finite real number in [lo, hi] (``lo_open``/``hi_open`` exclude a bound)."""
    return Num(lo, hi, **kwargs)


class OneOf(Rule):
    """One of the listed values, or of an ``Enum``'s values (kept plain: a config holds the string); ``None`` among the
    choices makes it optional."""

    def __init__(self, *choices: Any, fixed: bool | None = None) -> None:
        def values(group: Any) -> list:
            if isinstance(group, type) and issubclass(group, Enum):
                return [member.value for member in group]
            return list(group) if isinstance(group, (tuple, list)) else [group]

        flat = [c for group in choices for c in values(group)]
        super().__init__(optional=None in flat, fixed=fixed)
        self.choices = tuple(c for c in flat if c is not None)

    def _check(self, key: str, value: Any) -> Any:
        if isinstance(value, bool) or value not in self.choices:
            raise self.error(key, value)
        return value.value if isinstance(value, Enum) else value

    def describe(self) -> str:
        return "one of " + ", ".join(_show(c) for c in self.choices)


class Flag(Rule):
    """``true`` or ``false``."""

    def _check(self, key: str, value: Any) -> Any:
        if not isinstance(value, bool):
            raise self.error(key, value)
        return value

    def describe(self) -> str:
        return "true or false"


class Text(Rule):
    """A string (a path, a name)."""

    def _check(self, key: str, value: Any) -> Any:
        if not isinstance(value, str):
            raise self.error(key, value)
        return value

    def describe(self) -> str:
        return "a string"


class ListOf(Rule):
    """A list of ``min_len`` to ``max_len`` items, each valid for ``item``; one item may be given alone (``x`` is
    ``[x]``); a string with a comma is refused naming the list spelling (``a,b``: ``[a,b]``), in every command."""

    def __init__(
        self,
        item: Rule,
        min_len: int = 1,
        max_len: int | None = None,
        optional: bool = False,
        fixed: bool | None = None,
    ) -> None:
        super().__init__(optional, fixed)
        self.item, self.min_len, self.max_len = item, min_len, max_len

    def _check(self, key: str, value: Any) -> Any:
        if isinstance(value, str) and "," in value:  # the one list syntax is YAML's: a bare a,b is one string
            items = ",".join(v.strip() for v in value.split(","))
            raise self.error(key, value, f"a list is written {key}=[{items}]")
        if not isinstance(value, (list, tuple, dict)):
            value = [value]  # one item may be given without brackets: tasks=dmc_point_mass
        if not isinstance(value, (list, tuple)):
            raise self.error(key, value, "not a list")
        if len(value) < self.min_len or (self.max_len is not None and len(value) > self.max_len):
            raise self.error(key, value, f"{len(value)} items")
        return [self.item.check(f"{key}[{i}]", v) for i, v in enumerate(value)]

    def describe(self) -> str:
        size = f"at least {self.min_len}" if self.max_len is None else f"{self.min_len} to {self.max_len}"
        return f"a list of {size} items, each {self.item.describe()}"


class Check(Rule):
    """A rule given by a function ``fn(key, value) -> value`` that raises ``ConfigError`` (for the odd option)."""

    def __init__(
        self, fn: Callable[[str, Any], Any], description: str, optional: bool = False, fixed: bool | None = None
    ) -> None:
        super().__init__(optional, fixed)
        self.fn, self.description = fn, description

    def _check(self, key: str, value: Any) -> Any:
        return self.fn(key, value)

    def describe(self) -> str:
        return self.description


def _device_name(key: str, value: Any) -> str:
    if not (
        isinstance(value, str)
        and (value in ("auto", "cpu", "cuda") or (value.startswith("cuda:") and value[5:].isdigit()))
    ):
        raise ConfigError(f"{key}={value!r} is invalid; expected auto, cpu, cuda or cuda:N")
    return value


# Every command's device= (a run's is refpo_warp/config/run_options.py's, the same names); whether this machine has the
# device is checked where it is used (refpo_warp/utils/device.py's resolve_device). auto, the default of every
# command, is the GPU where one is usable, else the CPU.
DEVICE_RULE = Check(_device_name, "auto, cpu, cuda or cuda:N")
DEVICE_DOC = "where it runs (auto: cuda:0 where CUDA is usable, else cpu)"


def optional(rule: Rule) -> Rule:
    """The same rule with null valid too (an option whose default is found elsewhere, e.g. in a sweep file)."""
    out = copy.copy(rule)
    out.optional = True
    return out


def mapping_or_none(key: str, value: Any) -> Any:
    """For ``Check``: null or a mapping of options (e.g. rsl_rl's ``rnd_cfg``), checked by whoever consumes it."""
    if value is not None and not isinstance(value, dict):
        raise ConfigError(f"{key}={value!r} is invalid; expected null or a mapping of options")
    return value


def check_options(rules: dict[str, Rule], values: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """``values`` with every option that has a rule checked (and normalised); raises ``ConfigError``."""
    return {k: rules[k].check(f"{prefix}{k}", v) if k in rules else v for k, v in values.items()}


def _fmt(x: float) -> str:
    return f"{x:g}" if isinstance(x, float) else f"{x:,}" if abs(x) >= 10_000 else str(x)


def _show(value: Any) -> str:
    text = (
        repr(value)
        if isinstance(value, str)
        else "null"
        if value is None
        else str(value).lower()
        if isinstance(value, bool)
        else str(value)
    )
    return text if len(text) <= 80 else text[:77] + "..."
