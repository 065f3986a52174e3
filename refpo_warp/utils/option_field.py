"""``option(default, rule, doc)``: the field that declares an option (see ``refpo_warp/utils/options.py``, which reads
the fields; it re-exports ``option``), and ``section(doc, options)``, a field that holds a section of options. Apart
so that rsl_rl's table (``refpo_warp/utils/rsl_rl_options.py``) can declare fields without importing the reader."""

from __future__ import annotations

import dataclasses
from enum import Enum
from typing import Any, TypeVar, overload

from refpo_warp.utils.option_rules import Rule


class _Unset:
    def __repr__(self) -> str:
        return "UNSET"


UNSET: Any = _Unset()  # a field's default is elsewhere: the constructor's (rsl_rl's classes)
MARK = "refpo_option"  # in a field's metadata: the field is an option
T = TypeVar("T")


# Typed as ``dataclasses.field`` is: the field is of its default's type (``reflow_coef: float = option(0.04, ...)``);
# one without a default of its own (``option(rule=...)``) is of any type.
@overload
def option(default: T, rule: Rule | None = None, doc: str = "") -> T: ...


@overload
def option(*, rule: Rule | None = None, doc: str = "") -> Any: ...


def option(default: Any = UNSET, rule: Rule | None = None, doc: str = "") -> Any:
    """An option field: ``default`` (a list, dict or set is copied for every instance), ``rule`` and a one-line
    ``doc``; the same in a dataclass and in an algorithm's class body."""
    metadata = {MARK: True, "rule": rule, "doc": doc}
    if isinstance(default, (list, dict, set)):
        return dataclasses.field(default_factory=lambda: type(default)(default), metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


SECTION = "refpo_section"  # in a field's metadata: the field is a section; its value, the dataclass of its options


def section(doc: str, options: type | None = None) -> Any:
    """A section of a config (a mapping of options) at its place among an options dataclass's fields: the options of
    the dataclass ``options``, or (None) those of another class, which declares and checks them (the run options'
    ``env``: the task's env cfg)."""
    return dataclasses.field(default_factory=dict, metadata={SECTION: options, "doc": doc})


def choices(enum: type[Enum]) -> tuple[str, ...]:
    """The values of a choice enum, as a config writes them."""
    return tuple(member.value for member in enum)
