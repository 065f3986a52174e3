"""Options declared once: each option of a class is one field of the class's ``Options`` dataclass, holding its
default, its rule (``refpo_warp.utils.option_rules``) and a one-line doc::

    @dataclass(frozen=True)
    class ReFPOOptions:
        reflow_coef: float = option(0.04, Real(0, 1e6), "lambda, the weight of the Reflow (CFM) term; 0 is FPO")

    class ReFPO(OnPolicyAlgorithm):
        Options = ReFPOOptions

The config resolver checks a value against the field's rule, ``--explain`` shows the field's default and doc,
``docs/`` prints its table (``refpo_warp/config/option_docs.py``) and the constructor receives it
(``OnPolicyAlgorithm``: every option becomes an attribute of the same name; a model such as ``FlowActor`` takes
``**options`` after rsl_rl's positional arguments and reads them through ``constructor_options``). A class's options
are the fields of the ``Options`` of every class in its MRO, a subclass's field replacing its base's; a field without a
rule of its own (``option(0.05, doc=...)``: another default for a base's option, e.g. rsl_rl's ``clip_param``) keeps
the base's rule.
A fixed set of choices is an ``enum.Enum`` of strings: ``OneOf(TauSampling)`` accepts its values, which stay plain
strings in a config.
"""

from __future__ import annotations

import dataclasses
import inspect
from dataclasses import dataclass
from enum import Enum
from types import SimpleNamespace
from typing import Any

from refpo_warp.utils.option_rules import OPTIONS, Rule, rules_for


@dataclass(frozen=True)
class DeclaredOption:
    """One option as its class declares it."""

    default: Any
    rule: Rule | None
    doc: str
    owner: type  # the class whose ``Options`` declares this default


def option(default: Any, rule: Rule | None = None, doc: str = "") -> Any:
    """A field of an ``Options`` dataclass: ``default`` (a list or tuple is copied for every instance), ``rule`` and
    a one-line ``doc``."""
    metadata = {"rule": rule, "doc": doc}
    if isinstance(default, (list, dict, set)):
        return dataclasses.field(default_factory=lambda: type(default)(default), metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


def declared_options(cls: type) -> dict[str, DeclaredOption]:
    """Every option the ``Options`` of ``cls`` and its bases declare, by name: a subclass's default wins, a doc
    missing there is its base's, and the rule is the class's (``rules_for``: a base's when the field has none)."""
    out: dict[str, DeclaredOption] = {}
    rules = rules_for(cls)
    for klass in reversed(inspect.getmro(cls) if inspect.isclass(cls) else ()):
        options = getattr(klass, "__dict__", {}).get(OPTIONS)
        for f in dataclasses.fields(options) if dataclasses.is_dataclass(options) else ():
            default = f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default
            doc = f.metadata.get("doc") or (out[f.name].doc if f.name in out else "")
            out[f.name] = DeclaredOption(default, rules.get(f.name), doc, klass)
    return out


def option_values(cls: type, given: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(every declared option of ``cls`` with its default or the given value, the given arguments it does not
    declare)."""
    declared = declared_options(cls)
    values = {name: given.get(name, found.default) for name, found in declared.items()}
    return values, {k: v for k, v in given.items() if k not in declared}


def constructor_options(cls: type, given: dict[str, Any]) -> SimpleNamespace:
    """The options a constructor taking ``**options`` receives (a model's: rsl_rl passes them by keyword): every
    declared option of ``cls``, given or its default, as attributes; an argument ``cls`` does not declare is a
    ``TypeError``, as for a constructor with these parameters."""
    values, unknown = option_values(cls, given)
    if unknown:
        raise TypeError(f"{cls.__name__}.__init__() got an unexpected keyword argument '{next(iter(unknown))}'")
    return SimpleNamespace(**values)


def choices(enum: type[Enum]) -> tuple[str, ...]:
    """The values of a choice enum, as a config writes them."""
    return tuple(member.value for member in enum)
