"""The one argument convention of every command: ``refpo <command> [SUBJECT ...] [key=value ...] [--flag [VALUE] ...]``.

- ``key=value``: an option of what the command makes (a run's config keys, a video's options, a sweep's grid); the
  value is YAML (``eval.flow_steps=[1,10]``), parsed by the command (``refpo_warp/config/dotted.py``).
- ``--flag``, ``--flag VALUE`` or ``--flag=VALUE``: how the command itself works (``--dry-run``, ``--jobs 2``).
- a subject: the one or two things a command acts on, where it has them (``refpo sweep cpu_dmc``,
  ``refpo report runs/sweeps/cpu_dmc``, ``refpo bench dmc``).

A command declares its subjects and flags (its options: ``refpo_warp/config/command_options.py``); anything else is an
error naming the argument and the valid flags. A spelling a command once took (the table of
``refpo_warp/utils/renamed_spellings.py``: ``refpo report --out`` -> ``out=DIR``) is refused with the name it has now.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.renamed_spellings import renamed_error

HELP = ("-h", "--help", "help")


@dataclass(frozen=True)
class Flag:
    """A ``--flag`` of a command: a switch (``kind=None``) or a flag with a value of ``kind``."""

    name: str
    kind: type | None = None
    doc: str = ""
    optional_value: bool = False  # --explain [KEYS]: the next argument is its value unless it is an option or flag
    default: Any = None  # what ``Arguments.get`` returns when the flag is not given

    def line(self) -> str:
        """The flag's line in a command's help."""
        value = "" if self.kind is None else f" {self.name.lstrip('-').replace('-', '_').upper()}"
        default = "" if self.default is None else f" (default {self.default})"
        return f"    {self.name + value:22s}  {self.doc}{default}"

    def convert(self, text: str) -> Any:
        kind = self.kind
        assert kind is not None  # only a flag that takes a value converts one
        try:
            return kind(text)
        except ValueError:
            raise ConfigError(f"{self.name} {text!r} is invalid; expected {kind.__name__} ({self.doc})") from None


@dataclass
class Arguments:
    """A command line split by the convention (see the module docstring)."""

    subjects: list[str] = field(default_factory=list)
    options: list[str] = field(default_factory=list)  # key=value, in the order given
    flags: dict[str, Any] = field(default_factory=dict)  # given flags only: name -> value (True for a switch)

    def flag(self, name: str, default: Any = None) -> Any:
        return self.flags.get(name, default)

    def get(self, flag: Flag) -> Any:
        """A declared flag's value, or its default."""
        return self.flags.get(flag.name, flag.default)

    def values(self, key: str) -> list[str]:
        """Every value given to ``key=`` (a key a command takes more than once, e.g. ``run_dir=``), as text."""
        return [option.partition("=")[2] for option in self.options if option.partition("=")[0] == key]

    def only(self, command: str, keys: tuple[str, ...]) -> None:
        """Refuse any ``key=`` but ``keys``, naming the closest valid one."""
        for option in self.options:
            key = option.partition("=")[0]
            if key not in keys:
                raise unknown(f"option of refpo {command}", key, keys)


def wants_help(argv: list[str]) -> bool:
    return any(a in HELP for a in argv)


def parse_arguments(
    command: str,
    argv: list[str],
    flags: tuple[Flag, ...] = (),
    subjects: int = 0,
) -> Arguments:
    """Split ``argv``; a flag not declared, a missing flag value, an extra subject or an old spelling (the command's
    entries in ``refpo_warp/utils/renamed_spellings.py``) raises ``ConfigError``."""
    declared = {flag.name: flag for flag in flags}
    out = Arguments()
    i = 0
    while i < len(argv):
        arg = argv[i]
        i += 1
        old = arg.partition("=")[0] if arg.startswith("--") else arg.partition("=")[0] + "=" if "=" in arg else None
        error = renamed_error(command, old) if old else None
        if error is not None:
            raise error
        if arg.startswith("--"):
            name, has_value, value = arg.partition("=")
            if name not in declared:
                raise (
                    unknown(f"flag of refpo {command}", name, declared)
                    if declared
                    else ConfigError(f"refpo {command} takes no flags, got {name}")
                )
            flag = declared[name]
            if flag.kind is None:
                if has_value:
                    raise ConfigError(f"{name} takes no value, got {arg!r}")
                out.flags[name] = True
                continue
            if not has_value and flag.optional_value:
                taken = i < len(argv) and "=" not in argv[i] and not argv[i].startswith("-")
                value, i = (argv[i], i + 1) if taken else ("", i)
            elif not has_value:
                if i >= len(argv):
                    raise ConfigError(f"{name} needs a value ({flag.doc})")
                value, i = argv[i], i + 1
            out.flags[name] = flag.convert(value) if value or not flag.optional_value else ""
        elif "=" in arg:
            out.options.append(arg)
        elif len(out.subjects) < subjects:
            out.subjects.append(arg)
        else:
            raise ConfigError(
                f"unexpected argument {arg!r}: refpo {command} takes key=value options"
                + (f" and the flags {', '.join(declared)}" if declared else "")
                + "; see refpo "
                + command
                + " --help"
            )
    return out


def usage(synopsis: str, summary: str, flags: tuple[Flag, ...]) -> str:
    """A command's help: its synopsis, what it does and one line per flag."""
    return "\n".join([synopsis, "", summary.strip(), "", "Flags:", *(f.line() for f in flags)])


def parse_flags(
    command: str,
    argv: list[str],
    flags: tuple[Flag, ...],
    options: tuple[str, ...] = (),
) -> tuple[SimpleNamespace, dict[str, str]]:
    """A benchmark that does not declare an ``Options`` dataclass (``refpo_warp/cli/bench.py`` calls its
    ``main(argv)``): its arguments through the convention, its flags as attributes (``--num-envs 8`` ->
    ``.num_envs``, the declared default when not given) and its ``key=value`` options whose key starts with one of
    ``options`` (e.g. ``env.``), as text."""
    args = parse_arguments(command, argv, flags, 0)
    given = {}
    for option in args.options:
        key, _, value = option.partition("=")
        if not key.startswith(options) or not options:
            raise ConfigError(
                f"refpo {command} takes "
                + (f"{', '.join(o + '<key>=' for o in options)} options and " if options else "")
                + f"flags, not {option!r}; see refpo {command} --help"
            )
        given[key] = value
    values = {f.name.lstrip("-").replace("-", "_"): args.get(f) for f in flags}
    return SimpleNamespace(**values), given
