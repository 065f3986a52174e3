"""The options of a command other than a run's (``refpo bench <family>``, ``report``, ``plot``, ``play``,
``collect``, ``tune``, ``sweep``, mjlab's evaluate): a dataclass of fields ``option(default, rule, doc)``, read by one
parser, ``parse_options``, and shown by ``options_help`` (``--help``) and ``explain_options`` (``--explain``).

The grammar is ``refpo train``'s: ``key=value`` with a YAML value, a list written ``key=[a,b]`` (one item may be
written without brackets: ``tasks=dmc_point_mass``; ``tasks=a,b`` is refused with the list spelling named, in every
command: ``refpo_warp/utils/option_rules.py``'s ``ListOf``). A key given twice is refused; a key the command does not
declare is refused naming the closest valid one; a spelling it once took is refused with the name it has now (the one
table of them: ``refpo_warp/utils/renamed_spellings.py``). All exit 2 through ``refpo_warp/cli/guard.py``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

from refpo_warp.config.config_path import config_path
from refpo_warp.config.dotted import parse_overrides
from refpo_warp.utils.command_line import Arguments, Flag
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_tables import shown_value
from refpo_warp.utils.options import declared_options, docs_for, rules_for
from refpo_warp.utils.renamed_spellings import renamed_error

T = TypeVar("T")


def option_names(cls: type) -> list[str]:
    """The keys of an options dataclass, in declaration order."""
    return [f.name for f in dataclasses.fields(cls)]


def parse_options(
    command: str,
    cls: type[T],
    given: Iterable[str] | dict[str, Any],
    rest: Callable[[str], bool] | None = None,
    rest_names: Iterable[str] = (),
) -> tuple[T, dict[str, Any]]:
    """(``cls`` with the given ``key=value`` options, each checked by its field's rule, the others their defaults;
    the given options ``rest`` accepts, unchecked: a run's options, ``env.<option>``). ``rest_names`` describes what
    ``rest`` accepts, for the unknown-key error."""
    flat = dict(given) if isinstance(given, dict) else parse_overrides(list(given))
    names = option_names(cls)
    rules, declared = rules_for(cls), declared_options(cls)
    values: dict[str, Any] = {}
    passed: dict[str, Any] = {}
    for key, value in flat.items():
        old = renamed_error(command, f"{key}=")
        if old is not None:
            raise old
        if key in names:
            values[key] = rules[key].check(key, value) if key in rules else value
        elif rest is not None and rest(key):
            passed[key] = value
        else:
            raise unknown(f"option of refpo {command}", key, [*names, *rest_names])
    missing = [n for n in names if n not in values and n not in declared]
    if missing:
        raise ConfigError(f"refpo {command} needs {' '.join(f'{n}=...' for n in missing)}; see refpo {command} --help")
    return cls(**values), passed


def read_section(where: str, cls: type[T], mapping: Any) -> T:
    """A section of a file (a sweep file, one of its method entries) as ``cls``: each key one of its fields (an unknown
    one refused naming the valid ones), each value checked by the field's rule (the error names the file), the others
    their defaults; a field without a default is required."""
    names = option_names(cls)
    if not isinstance(mapping, dict):
        raise ConfigError(f"{where}: expected a mapping of {', '.join(names)}, got {mapping!r}")
    rules, declared, docs = rules_for(cls), declared_options(cls), docs_for(cls)
    for key in mapping:
        if key not in names:
            raise unknown(f"key in {where}", str(key), names)
    values = {k: rules[k].check(f"{where}: {k}", v) if k in rules else v for k, v in mapping.items()}
    for name in names:
        if name not in values and name not in declared:
            raise ConfigError(f"{where}: '{name}' is missing ({docs.get(name, '')})")
    return cls(**values)


def options_help(cls: type, skip: Iterable[str] = ()) -> str:
    """One line per option: ``key=<default>`` (or ``key=...`` for a required one), its doc and valid values."""
    declared, docs, rules = declared_options(cls), docs_for(cls), rules_for(cls)
    shown = {
        n: f"{n}={_shown(declared[n].default)}" if n in declared else f"{n}=... (required)"
        for n in option_names(cls)
        if n not in skip
    }
    width = max(len(s) for s in shown.values()) + 2
    lines = []
    for name, text in shown.items():
        rule = rules.get(name)
        valid = f" [{rule.describe()}]" if rule is not None else ""
        lines.append(f"    {text:<{width}}{docs.get(name, '')}{valid}")
    return "\n".join(lines)


def explain_options(command: str, cls: type, given: Iterable[str], keys: str = "", rest=None) -> str:
    """``--explain [KEYS]``: each option's value, whether the command line or the field's default set it, its valid
    values and doc (nothing is run)."""
    given = list(given)
    options: Any
    options, passed = parse_options(command, cls, given, rest)
    flat = parse_overrides(given)
    docs, rules = docs_for(cls), rules_for(cls)
    chosen = [k.strip() for k in keys.split(",") if k.strip()] or option_names(cls)
    lines = [f"Options of refpo {command} (the command line over each field's default):"]
    for key in chosen:
        if key not in option_names(cls):
            raise unknown(f"option of refpo {command}", key, option_names(cls))
        source = "the command line" if key in flat else "the default (its field in " + cls.__module__ + ")"
        rule = rules.get(key)
        lines += ["", f"{key} = {_shown(getattr(options, key))}", f"  set by  {source}"]
        lines.append(f"  means   {docs.get(key, '')}")
        if rule is not None:
            lines.append(f"  valid   {rule.describe()}")
    if passed:
        lines += ["", "passed on: " + " ".join(f"{k}={v}" for k, v in passed.items())]
    return "\n".join(lines)


def command_help(synopsis: str, summary: str, cls: type, flags: str = "", skip: Iterable[str] = ()) -> str:
    """A command's ``--help``: synopsis, what it does, its options from the fields, then its flags."""
    parts = [synopsis, "", summary.strip(), "", "Options (key=value; lists as key=[a,b]):", options_help(cls, skip)]
    parts += ["", "Flags: --help, --explain [KEY,KEY,...] (each option's value and where it comes from)" + flags]
    return "\n".join(parts)


EXPLAIN = Flag("--explain", str, "the keys to explain, comma-separated; none: every option", optional_value=True)


def options_or_explain(
    command: str, cls: type[T], args: Arguments, rest: Callable[[str], bool] | None = None, rest_names=()
) -> tuple[T, dict[str, Any]] | None:
    """The command's options (``parse_options``); with ``--explain``, print ``explain_options`` and return None."""
    if "--explain" in args.flags:
        print(explain_options(command, cls, args.options, args.flag("--explain") or "", rest), flush=True)
        return None
    return parse_options(command, cls, args.options, rest, rest_names)


def named_files(kind: str, given: Iterable[str]) -> str:
    """``refpo sweep --list`` / ``refpo tune --list``: every ``<kind>/<name>.yaml`` of the config folders (the shipped
    ones, then ``config_dir=DIR``'s and ``REFPO_CONFIG_PATH``'s) with its ``description:``."""
    flat = parse_overrides(list(given))
    for key in flat:
        if key != "config_dir":
            raise unknown(f"option of refpo {kind} --list", key, ["config_dir"])
    named = config_path(flat.get("config_dir")).described(kind)
    width = max((len(name) for name, _ in named), default=0)
    return "\n".join(f"{name:{width}s}  {description}".rstrip() for name, description in named)


def _shown(value: Any) -> str:
    return shown_value(value).replace("`", "")
