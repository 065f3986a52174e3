"""One way to declare an option: a field made by ``option(default, rule, doc)``, which holds the option's default, its
rule (the valid values; ``refpo_warp.utils.option_rules``) and a one-line doc::

    class MyAlgo(OnPolicyAlgorithm):                  # an algorithm: fields in the class body
        num_samples: int = option(3, Int(1, 1024), "samples per action")

    @dataclass
    class MyCfg(EnvCfg):                              # an env cfg, the video options, the run options: a dataclass
        speed: float = option(0.5, Real(0, 10, lo_open=True), "distance moved per step at action 1")

    class MyActor(nn.Module):                         # a model: a nested ``Options`` dataclass
        @dataclass(frozen=True)
        class Options:
            width: int = option(64, Int(1, 4096), "hidden width")

Where the fields stand (``option_fields``): in the body of an algorithm class (the constructor assigns each one, so
``self.num_samples`` is a typed attribute), in an env cfg / option dataclass itself, or in a model's ``Options``
dataclass (a model is a ``torch.nn.Module``, whose class attributes would shadow its buffers; its constructor holds a
typed ``Options`` instance). rsl_rl's classes, which cannot be edited, have theirs in one table of the same fields
(``refpo_warp/utils/rsl_rl_options.py``), read here. A field without a default of its own (``option(rule=...)``, only
in that table) takes the constructor's.

The same field is read by the config resolver (``refpo_warp/config/validate.py``, which names the dotted key in its
error), ``--explain`` (``refpo_warp/config/explain.py``), the docs' tables (``refpo_warp/config/option_docs.py``) and
the constructor (``option_values``, ``constructor_options``, ``check_fields``). A class's options are the fields of
every class in its MRO, a subclass's field replacing its base's; a field without a rule of its own
(``option(0.05, doc=...)``: another default for a base's option) keeps the base's rule, and a field without a doc keeps
the base's doc. A fixed set of choices is an ``enum.Enum`` of strings: ``OneOf(MyEnum)`` accepts its values, which stay
plain strings in a config and in the field (``mode: str = option("fast", OneOf(Mode), ...)``: ``option`` is typed as
``dataclasses.field`` is, the field has its default's type). ``tests/utils/test_option_rules.py`` fails for an option
without a rule.
"""

from __future__ import annotations

import dataclasses
import inspect
from dataclasses import dataclass
from typing import Any, TypeVar

from refpo_warp.utils.option_field import MARK, UNSET, choices, option  # noqa: F401  (option, choices: re-exported)
from refpo_warp.utils.option_rules import Rule, check_options

T = TypeVar("T")


@dataclass(frozen=True)
class DeclaredOption:
    """One option as its class declares it."""

    default: Any
    rule: Rule | None
    doc: str
    owner: type  # the class that declares this default


def _default(f: dataclasses.Field) -> Any:
    return f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default


def option_fields(klass: type) -> dict[str, dataclasses.Field]:
    """The option fields ``klass`` itself declares (not its bases'), by name (see the module docstring)."""
    if klass.__module__.split(".")[0] == "rsl_rl":
        from refpo_warp.utils.rsl_rl_options import RSL_RL_OPTIONS

        table = RSL_RL_OPTIONS.get(klass)
        return {f.name: f for f in dataclasses.fields(table)} if table is not None else {}
    own = vars(klass)
    if "__dataclass_fields__" in own:  # an option dataclass (env cfg, video, run options, a model's Options)
        names = own.get("__annotations__", {})
        return {f.name: f for f in dataclasses.fields(klass) if f.name in names}
    nested = own.get("Options")
    if dataclasses.is_dataclass(nested) and isinstance(nested, type):  # a model: every field of its Options
        return {f.name: f for f in dataclasses.fields(nested)}
    return {k: v for k, v in own.items() if isinstance(v, dataclasses.Field) and MARK in v.metadata}


def _mro(cls: type) -> list[type]:
    return list(reversed(inspect.getmro(cls))) if inspect.isclass(cls) else []


def rules_for(cls: type) -> dict[str, Rule]:
    """The rule of every option of ``cls`` and its bases (a subclass's rule replaces its base's)."""
    rules: dict[str, Rule] = {}
    for klass in _mro(cls):
        for name, f in option_fields(klass).items():
            if f.metadata.get("rule") is not None:
                rules[name] = f.metadata["rule"]
    return rules


def docs_for(cls: type) -> dict[str, str]:
    """The doc of every option of ``cls`` and its bases (a subclass's doc replaces its base's; none keeps it)."""
    docs: dict[str, str] = {}
    for klass in _mro(cls):
        for name, f in option_fields(klass).items():
            if f.metadata.get("doc"):
                docs[name] = f.metadata["doc"]
    return docs


def declared_options(cls: type) -> dict[str, DeclaredOption]:
    """Every option of ``cls`` and its bases with a default of its own, by name: a subclass's default wins, a doc
    missing there is its base's, and the rule is the class's (``rules_for``: a base's when the field has none)."""
    out: dict[str, DeclaredOption] = {}
    rules = rules_for(cls)
    for klass in _mro(cls):
        for name, f in option_fields(klass).items():
            default = _default(f)
            if default is UNSET:
                continue
            doc = f.metadata.get("doc") or (out[name].doc if name in out else "")
            out[name] = DeclaredOption(default, rules.get(name), doc, klass)
    return out


def option_values(cls: type, given: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """For a constructor taking ``**kwargs``: every given value checked against its rule (the error names
    ``<Class>.<option>``), then (every declared option of ``cls`` with the given value or its default, the given
    arguments it does not declare)."""
    checked = check_options(rules_for(cls), given, f"{cls.__name__}.")
    declared = declared_options(cls)
    values = {name: checked.get(name, found.default) for name, found in declared.items()}
    return values, {k: v for k, v in checked.items() if k not in declared}


def constructor_options(cls: type, options: type[T], given: dict[str, Any]) -> T:
    """A model's ``Options`` instance from the keyword arguments its constructor received (rsl_rl passes them by
    keyword), each checked against its rule; an argument ``options`` does not declare is a ``TypeError``, as for a
    constructor with these parameters."""
    values, unknown = option_values(cls, given)
    if unknown:
        raise TypeError(f"{cls.__name__}.__init__() got an unexpected keyword argument '{next(iter(unknown))}'")
    return options(**values)


def check_fields(obj: Any, prefix: str) -> None:
    """In an option dataclass's ``__post_init__``: every field checked against its rule and normalised in place."""
    values = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
    for name, value in check_options(rules_for(type(obj)), values, prefix).items():
        object.__setattr__(obj, name, value)
