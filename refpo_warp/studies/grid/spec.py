"""Sweep specifications: a grid of tasks x methods x seeds (x list-valued overrides), expanded into runs.

A sweep file (``sweep/<name>.yaml`` of the config folders: a user's ``config_dir=`` or ``REFPO_CONFIG_PATH`` folders,
then the shipped ``configs/``; or any YAML path) holds::

    device: cpu                      # cpu | cuda | auto: which by_device profile every run uses
    tasks: [dmc_point_mass, ...]
    seeds: [1, 2, 3]
    overrides: {}                    # run options for every run (dotted keys or nested mappings)
    methods:                         # one table row each (after expansion)
      - {label: ppo, algo: ppo, name: PPO}
      - {label: "refpo_l{algorithm.reflow_coef}", algo: refpo, name: "ReFPO, λ={algorithm.reflow_coef}",
         overrides: {algorithm.reflow_coef: [0.02, 0.08]}}
    report: {curve_methods: [...], ratio_tasks: [...], ratio_methods: [...]}   # optional figure choices

A list value expands the grid (one method variant per value) unless the option itself takes a list (e.g.
``eval.flow_steps``); such an option is swept by a list of lists. ``{key}`` in a label or name is replaced by that
variant's value; axes not named in the label are appended as ``_<leaf><value>``. Each run trains in
``<sweep dir>/<task>/<label>/seed<k>``.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import yaml

from refpo_warp.config.command_options import parse_options, read_section
from refpo_warp.config.config_path import config_path
from refpo_warp.config.dotted import LEAF_KEYS, parse_overrides
from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import DEVICE_RULE, Check, Int, ListOf, Rule, Text, mapping_or_none, optional
from refpo_warp.utils.options import option

_MAPPING = Check(mapping_or_none, "null or a mapping of run options (dotted keys or nested mappings)", optional=True)
_LABELS = ListOf(Text(), optional=True)


@dataclass(frozen=True)
class SweepFile:
    """The keys of a sweep file (the module docstring shows one)."""

    name: str | None = option(None, Text(optional=True), "the sweep's name (default: the file's name)")
    description: str = option("", Text(), "what the sweep is for")
    device: str = option("auto", DEVICE_RULE, "the device profile every run resolves for (cpu, cuda, cuda:N, auto)")
    tasks: list[str] = option(rule=ListOf(Text()), doc="the task ids")
    seeds: list[int] = option([1], ListOf(Int(0, 2**32 - 1)), "the seeds")
    overrides: dict | None = option(None, _MAPPING, "run options of every run")
    methods: list = option(rule=ListOf(Rule()), doc="the methods, one table row each (MethodEntry, or an algo name)")
    report: dict | None = option(None, _MAPPING, "figure choices: curve_methods, ratio_tasks, ratio_methods")
    out: str | None = option(None, Text(optional=True), "the sweep dir (default: runs/sweeps/<name>)")


@dataclass(frozen=True)
class MethodEntry:
    """One entry of a sweep file's ``methods``."""

    algo: str = option(rule=Text(), doc="the algorithm (refpo train's algo=)")
    label: str | None = option(None, Text(optional=True), "its label (default: algo); {key} takes a variant's value")
    name: str | None = option(None, Text(optional=True), "its name in tables (default: the label)")
    overrides: dict | None = option(None, _MAPPING, "its run options; a list expands the grid")


@dataclass(frozen=True)
class ReportChoices:
    """A sweep file's ``report``: the figures' defaults of ``refpo report`` (its command line's keys of the same
    names override them)."""

    curve_methods: list[str] | None = option(None, _LABELS, "method labels in Figure 3")
    ratio_tasks: list[str] | None = option(None, _LABELS, "tasks of Figure 4")
    ratio_methods: list[str] | None = option(None, _LABELS, "method labels of Figure 4")


SPEC_KEYS = tuple(f.name for f in fields(SweepFile))
# Run options the sweep sets itself (on the command line: the sweep-level key, utils/renamed_spellings.py's "sweep")
MANAGED = {"task": "tasks=", "algo": "methods=", "seed": "seeds=", "run_dir": "out=", "resume": None}


@dataclass(frozen=True)
class SweepOptions:
    """The sweep-level options of ``refpo sweep``'s command line (over the sweep file's keys of the same names);
    every other ``key=value`` is a run option of every run."""

    tasks: list[str] | None = option(None, ListOf(Text(), optional=True), "task ids (default: the file's tasks)")
    seeds: list[int] | None = option(
        None, ListOf(Int(0, 2**32 - 1), optional=True), "seeds (default: the file's seeds, else [1])"
    )
    methods: list[str] | None = option(
        None, ListOf(Text(), optional=True), "method labels to keep: an entry's label keeps all its variants"
    )
    device: str | None = option(
        None, optional(DEVICE_RULE), "the runs' device profile (default: the file's device, else auto)"
    )
    out: str | None = option(
        None, Text(optional=True), "the sweep dir (default: the file's out, else runs/sweeps/<name>)"
    )


# Config keys that do not change what a run computes: a finished run whose config differs only here is kept.
FINGERPRINT_IGNORED = (
    "device",
    "torch_threads",  # like the device: the same run, its sums in another order
    "resume",
    "run_dir",
    "verbose",
    "config_dir",
    "stop_after_iterations",  # a run in pieces computes what the run in one call does (training/pieces.py)
    "stop_after_minutes",
)
# Options that act only with init_from: without it a run computes the same whatever they say.
FINE_TUNING_ONLY = ("critic_warmup_iterations", "clone_normalizer")


@dataclass(frozen=True)
class Method:
    """One table row: an algorithm with its fixed overrides (list axes already expanded)."""

    label: str
    name: str
    algo: str
    overrides: dict[str, Any] = field(default_factory=dict, hash=False, compare=False)


@dataclass(frozen=True)
class Run:
    task: str
    method: Method
    seed: int
    run_dir: Path
    args: tuple[str, ...]  # refpo train arguments, device excluded (chosen at launch)
    resume: bool = False  # continue the run dir's newest checkpoint (a paused run) instead of starting it again

    @property
    def key(self) -> str:
        return f"{self.task}/{self.method.label}/seed{self.seed}"

    def continued(self) -> Run:
        """This run, continued from its run dir's newest checkpoint (``resume=true``)."""
        return replace(self, resume=True, args=(*self.args, "resume=true"))

    def from_scratch(self) -> Run:
        """This run, started again from nothing."""
        return replace(self, resume=False, args=tuple(a for a in self.args if a != "resume=true"))


@dataclass
class Sweep:
    name: str
    source: str
    description: str
    device: str
    tasks: list[str]
    seeds: list[int]
    methods: list[Method]
    out_dir: Path
    report: dict[str, list[str]]
    runs: list[Run] = field(default_factory=list)


def _flat_overrides(values: Any, where: str, prefix: str = "") -> dict[str, Any]:
    """Nested mappings to dotted keys (``LEAF_KEYS`` mappings stay whole)."""
    if values is None:
        return {}
    if not isinstance(values, dict):
        raise ConfigError(f"{where}: 'overrides' must be a mapping of run options, got {values!r}")
    out: dict[str, Any] = {}
    for key, value in values.items():
        leaf = str(key).rsplit(".", 1)[-1]
        if isinstance(value, dict) and value and leaf not in LEAF_KEYS:
            out.update(_flat_overrides(value, where, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def _as_list(value: Any, key: str, kind: type) -> list:
    if isinstance(value, str):
        value = [v.strip() for v in value.split(",") if v.strip()]
    elif not isinstance(value, list):
        value = [value]
    try:
        out = [kind(v) for v in value]
    except (TypeError, ValueError) as err:
        raise ConfigError(f"'{key}' expects a list of {kind.__name__}, got {value!r}") from err
    if not out or len(set(out)) != len(out):
        raise ConfigError(f"'{key}' must be a non-empty list without repeats, got {value!r}")
    return out


def format_value(value: Any) -> str:
    """A value as it appears in labels: 0.02 -> '0.02', [10, 1] -> '10-1', True -> 'true'."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (list, tuple)):
        return "-".join(format_value(v) for v in value)
    return str(value)


def cli_value(value: Any) -> str:
    """A value written as ``key=<value>`` so that ``parse_overrides`` (YAML) reads it back unchanged."""
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            return ".nan" if math.isnan(value) else (".inf" if value > 0 else "-.inf")
        text = repr(value)
        return text.replace("e", ".0e") if "e" in text and "." not in text else text  # YAML floats need a dot
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(cli_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))}: {cli_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, str):
        return json.dumps(value)
    return str(value)


def _substitute(template: str, values: dict[str, Any]) -> tuple[str, set[str]]:
    used: set[str] = set()

    def repl(match: re.Match) -> str:
        key = match.group(1)
        if key not in values:
            raise ConfigError(f"'{template}' names {{{key}}}, which is not a list-valued override of this method")
        used.add(key)
        return format_value(values[key])

    return re.sub(r"\{([^{}]+)\}", repl, template), used


def _list_valued(cfg: dict, key: str) -> bool:
    """Whether the option ``key`` of a resolved config takes a list (then a list value is not a grid axis)."""
    from refpo_warp.config.classes import class_parameters

    node: Any = cfg
    parts = key.split(".")
    for part in parts[:-1]:
        node = node.get(part) if isinstance(node, dict) else None
    if not isinstance(node, dict):
        return False
    if parts[-1] in node:
        return isinstance(node[parts[-1]], (list, tuple))
    if "class_name" in node:  # a constructor argument not set in any YAML layer: look at its default
        return isinstance(class_parameters(node["class_name"]).get(parts[-1]), (list, tuple))
    return False


def expand_method(entry: dict, overrides: dict[str, Any], probe: dict) -> list[Method]:
    """The variants of one method entry: one per combination of its list-valued (axis) overrides."""
    axes = {
        k: v
        for k, v in overrides.items()
        if isinstance(v, list) and (not _list_valued(probe, k) or (v and all(isinstance(x, list) for x in v)))
    }
    fixed = {k: v for k, v in overrides.items() if k not in axes}
    for key, values in axes.items():
        if not values:
            raise ConfigError(f"Method '{entry['label']}': override '{key}' is an empty list")
    variants = []
    for combo in itertools.product(*axes.values()) if axes else [()]:
        point = dict(zip(axes, combo))
        label, used = _substitute(entry["label"], point)
        label += "".join(f"_{k.rsplit('.', 1)[-1]}{format_value(v)}" for k, v in point.items() if k not in used)
        name, used_in_name = _substitute(entry["name"], point)
        rest = [f"{k.rsplit('.', 1)[-1]}={format_value(v)}" for k, v in point.items() if k not in used_in_name]
        name += f" ({', '.join(rest)})" if rest else ""
        label = re.sub(r"[^A-Za-z0-9._=+-]", "-", label)
        variants.append(Method(label, name, entry["algo"], {**fixed, **point}))
    return variants


def _method_entries(entries: list, where: str) -> list[dict]:
    out = []
    for given in entries:
        entry = read_section(f"{where} method", MethodEntry, {"algo": given} if isinstance(given, str) else given)
        label = str(entry.label or entry.algo)
        out.append(
            {
                "label": label,
                "algo": entry.algo,
                "name": str(entry.name or label),
                "overrides": _flat_overrides(entry.overrides, where),
            }
        )
    return out


def device_type(device: str) -> str:
    if device == "auto":
        from refpo_warp.utils.device import resolve_device

        device = resolve_device("auto")
    if device != "cpu" and not device.startswith("cuda"):
        raise ConfigError(f"Sweep 'device' must be cpu, cuda, cuda:N or auto, got '{device}'")
    return "cuda" if device.startswith("cuda") else "cpu"


def load_sweep(source: str, args: list[str] | None = None) -> Sweep:
    """Read a sweep file, apply command-line ``key=value`` arguments and expand the grid into runs.

    Sweep-level arguments: ``tasks=``, ``seeds=``, ``methods=`` (labels to keep: a method entry's label keeps all
    its variants), ``device=``, ``out=`` (the sweep dir). Every other ``key=value`` is a run option for every run
    (list values expand the grid as in the file).
    """
    from refpo_warp.config.resolve import resolve_config  # here: a Ray worker imports this module without torch

    given, cli = parse_options("sweep", SweepOptions, args or [], lambda key: True)  # the rest: run options
    path = config_path(cli.get("config_dir")).named_or_path("sweep", source)  # the runs' config folders
    where = str(path)
    spec = read_section(f"sweep file {where}", SweepFile, load_yaml(path))
    for key, hint in MANAGED.items():
        if key in cli:
            raise ConfigError(f"'{key}=' is set by the sweep for each run" + (f"; use '{hint}...'" if hint else ""))
    name = str(spec.name or path.stem)
    device = str(given.device or spec.device)
    tasks = _as_list(given.tasks or spec.tasks, "tasks", str)
    seeds = _as_list(given.seeds or spec.seeds, "seeds", int)
    keep = given.methods
    out_dir = Path(str(given.out or spec.out or Path("runs") / "sweeps" / name))
    figures = read_section(f"report of {where}", ReportChoices, spec.report or {})
    report = {k: v for k, v in vars(figures).items() if v is not None}
    entries = _method_entries(spec.methods, where)
    base = _flat_overrides(spec.overrides, where)
    dtype = device_type(device)
    methods: list[tuple[str, Method]] = []  # (entry label, variant), the file's grid
    probes: dict[str, dict] = {}
    folders = {"config_dir": cli["config_dir"]} if "config_dir" in cli else {}
    for entry in entries:
        probe = resolve_config({"task": tasks[0], "algo": entry["algo"], **folders}, device_type=dtype)
        probes[entry["algo"]] = probe
        methods += [(entry["label"], m) for m in expand_method(entry, {**base, **entry["overrides"]}, probe)]
    if keep is not None:  # a method entry's label keeps all its variants; a variant label keeps that one
        keep = _as_list(keep, "methods", str)
        choices = sorted({e for e, _ in methods} | {m.label for _, m in methods})
        for label in keep:
            if label not in choices:
                raise unknown(f"method of sweep '{name}'", label, choices)
        methods = [(e, m) for e, m in methods if e in keep or m.label in keep]
    if cli:  # command-line run options apply to every kept method; their lists expand the grid further
        methods = [
            (e, v)
            for e, m in methods
            for v in expand_method(
                {"label": m.label, "name": m.name, "algo": m.algo}, {**m.overrides, **cli}, probes[m.algo]
            )
        ]
    labels = [m.label for _, m in methods]
    if len(set(labels)) != len(labels):
        raise ConfigError(f"{where}: method labels must be unique after expansion, got {labels}")
    sweep = Sweep(
        name,
        str(path),
        spec.description.strip(),
        device,
        tasks,
        seeds,
        [m for _, m in methods],
        out_dir,
        {k: _as_list(v, f"report.{k}", str) for k, v in report.items()},
    )
    sweep.runs = [_make_run(sweep, task, method, seed) for seed in seeds for task in tasks for method in sweep.methods]
    return sweep


def _make_run(sweep: Sweep, task: str, method: Method, seed: int) -> Run:
    run_dir = sweep.out_dir / task / method.label / f"seed{seed}"
    args = [f"task={task}", f"algo={method.algo}", f"seed={seed}", f"run_dir={run_dir}"]
    args += [f"{k}={cli_value(v)}" for k, v in method.overrides.items()]
    return Run(task, method, seed, run_dir, tuple(args))


def computed_part(cfg: dict) -> dict:
    """A resolved run config less what does not change what the run computes: how it runs (``FINGERPRINT_IGNORED``);
    without a checkpoint to start from, ``init_from`` itself and the options that act only with one; outside a
    ``refpo pretrain`` run (one with ``pretrain.dataset``), the ``pretrain`` section, which only that command reads.
    So a run saved before one of these options existed stays finished."""
    ignored: set[str] = set(FINGERPRINT_IGNORED)
    if not cfg.get("init_from"):
        ignored.update(FINE_TUNING_ONLY, ["init_from"])
    if not (cfg.get("pretrain") or {}).get("dataset"):
        ignored.add("pretrain")
    return {k: v for k, v in cfg.items() if k not in ignored}


def fingerprint(cfg: dict) -> str:
    """A hash of a resolved run config's ``computed_part``."""
    data = yaml.safe_load(yaml.safe_dump(computed_part(cfg)))
    return hashlib.sha1(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


def validate(sweep: Sweep) -> dict[str, str]:
    """Resolve every run's config (as ``refpo train`` will); returns run key -> config fingerprint.

    All failures are collected and raised together, naming the runs, so a typo fails before anything starts.
    Seeds differ only in the plain ``seed`` key, so each (task, method) is resolved once and its seeds share it.
    """
    from refpo_warp.config.resolve import resolve_config

    dtype = device_type(sweep.device)
    prints: dict[str, str] = {}
    errors: dict[str, list[str]] = {}
    resolved: dict[tuple[str, str], dict | None] = {}
    for run in sweep.runs:
        cell = (run.task, run.method.label)
        if cell not in resolved:
            try:
                cfg = resolve_config(parse_overrides([*run.args, f"device={sweep.device}"]), device_type=dtype)
                if not cfg["eval"]["at_end"]:
                    raise ConfigError("eval.at_end is false: a sweep run must write eval.json")
                resolved[cell] = cfg
            except ConfigError as err:
                resolved[cell] = None
                errors.setdefault(str(err), [])
                errors[str(err)].append(run.key)
        cell_config = resolved[cell]
        if cell_config is not None:
            prints[run.key] = fingerprint({**cell_config, "seed": run.seed})
    if errors:
        lines = [f"- {len(keys)} (task, method) cell(s), e.g. {keys[0]}: {msg}" for msg, keys in errors.items()]
        raise ConfigError(
            f"Sweep '{sweep.name}': {sum(map(len, errors.values()))} of "
            f"{len(sweep.tasks) * len(sweep.methods)} (task, method) configs do not resolve:\n" + "\n".join(lines)
        )
    return prints
