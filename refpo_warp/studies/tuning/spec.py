"""Tuning specifications: the methods to tune, each with a declared search space, one budget of trials for all,
the tasks and the one tuning seed every trial trains on, and the objective, stated before the search.

A tuning file (``tune/<name>.yaml`` of the config folders, or any YAML path) holds::

    device: cpu
    tasks: [dmc_point_mass, dmc_reacher_easy]
    seed: 101                         # the tuning seed: never one of the reported seeds
    trials: 8                         # per method: the equal budget
    overrides: {}                     # run options of every trial run
    objective:                        # score = mean over tasks of metric / reference[task]
      metric: return_multi            # a column of the sweep report's runs.csv (N = 10, or a Gaussian's mean action)
      reference: {dmc_point_mass: 869.1, dmc_reacher_easy: 781.8}
    sampler: {startup_trials: 4}      # Optuna's TPE; the enqueued trials count among the startup trials
    pruner: {percentile: 25, startup_trials: 3, warmup_evaluations: 5}   # or null: no pruning
    methods:
      - label: ppo
        algo: ppo
        overrides: {}                 # fixed run options of this method's trials
        enqueue: [config]             # first trials: `config` (the values its config gives) or a mapping of values
        space:
          algorithm.learning_rate: {low: 3.0e-5, high: 3.0e-3, log: true}
          algorithm.clip_param: {choices: [0.02, 0.05, 0.1, 0.2]}
    evaluate:                         # optional: the sweep of the chosen values on fresh seeds, written when done
      tasks: [dmc_cartpole_balance, dmc_point_mass, dmc_reacher_easy]
      seeds: [11, 12, 13]
      variants:                       # more rows: another algo with a tuned method's chosen values
        - {label: refpo_onestep, of: refpo, algo: refpo_onestep}
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from refpo_warp.config.command_options import parse_options, read_section
from refpo_warp.config.config_path import config_path
from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.grid.spec import Method, Run, _flat_overrides, cli_value, device_type
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import DEVICE_RULE, Check, Int, ListOf, Real, Rule, Text, mapping_or_none
from refpo_warp.utils.options import option

_MAPPING = Check(mapping_or_none, "null or a mapping", optional=True)


@dataclass(frozen=True)
class TuningFile:
    """The keys of a tuning file (the module docstring shows one)."""

    description: str = option("", Text(), "what the tuning is for")
    device: str = option("auto", DEVICE_RULE, "the device profile every trial run resolves for")
    tasks: list[str] = option(rule=ListOf(Text()), doc="the task ids every trial trains on")
    seed: int = option(101, Int(0, 2**32 - 1), "the tuning seed: never one of the reported seeds")
    trials: int = option(8, Int(1), "trials per method: the equal budget")
    overrides: dict | None = option(None, _MAPPING, "run options of every trial run")
    objective: dict = option(rule=_MAPPING, doc="the score: metric, reference (ObjectiveSection)")
    sampler: dict | None = option(None, _MAPPING, "Optuna's TPE sampler (SamplerSection)")
    pruner: dict | None = option(None, _MAPPING, "the pruner (PrunerSection); null: no pruning")
    methods: list = option(rule=ListOf(Rule()), doc="the methods tuned (MethodSection)")
    evaluate: dict | None = option(None, _MAPPING, "the sweep of the chosen values on fresh seeds (EvaluateSection)")
    out: str | None = option(None, Text(optional=True), "the tuning folder (default: runs/tune/<name>)")


@dataclass(frozen=True)
class ObjectiveSection:
    metric: str = option(rule=Text(), doc="a column of the sweep report's runs.csv (N = 10, or a Gaussian's mean)")
    reference: dict = option(rule=_MAPPING, doc="a positive number per task: score = mean of metric / reference")
    description: str = option("", Text(), "what the score means")


@dataclass(frozen=True)
class SamplerSection:
    startup_trials: int = option(4, Int(0), "TPE's random trials first (the enqueued ones count among them)")


@dataclass(frozen=True)
class PrunerSection:
    percentile: float = option(25.0, Real(0, 100, lo_open=True, hi_open=True), "prune below this percentile")
    startup_trials: int = option(3, Int(0), "trials never pruned, first")
    warmup_evaluations: int = option(5, Int(0), "periodic evaluations of a trial before it may be pruned")


@dataclass(frozen=True)
class MethodSection:
    algo: str = option(rule=Text(), doc="the algorithm (refpo train's algo=)")
    space: dict = option(rule=_MAPPING, doc="the searched run options: {low, high, log} or {choices: [...]} each")
    label: str | None = option(None, Text(optional=True), "its label (default: algo)")
    name: str | None = option(None, Text(optional=True), "its name in tables (default: the label)")
    overrides: dict | None = option(None, _MAPPING, "fixed run options of its trials")
    enqueue: list = option(["config"], ListOf(Rule(), min_len=0), "first trials: config (its own values) or mappings")


@dataclass(frozen=True)
class EvaluateSection:
    tasks: list[str] = option(rule=ListOf(Text()), doc="the tasks of the evaluation sweep")
    seeds: list[int] = option(rule=ListOf(Int(0, 2**32 - 1)), doc="its fresh seeds")
    variants: list | None = option(None, ListOf(Rule(), optional=True), "more rows (VariantSection)")


@dataclass(frozen=True)
class VariantSection:
    label: str = option(rule=Text(), doc="the row's label")
    of: str = option(rule=Text(), doc="the tuned method whose chosen values it takes")
    algo: str = option(rule=Text(), doc="its algorithm")
    name: str | None = option(None, Text(optional=True), "its name in tables (default: the label)")


SPEC_KEYS = tuple(f.name for f in fields(TuningFile))
DIMENSION_KEYS = {"float": ("low", "high", "log"), "categorical": ("choices",)}
CONFIG_VALUES = "config"  # an `enqueue` entry: the values the method's own config resolves to
# The run options a trial sets itself.
MANAGED = ("task", "algo", "seed", "run_dir", "resume")


@dataclass(frozen=True)
class TuneOptions:
    """The options of ``refpo tune``'s command line (over the tuning file's keys of the same names)."""

    trials: int | None = option(None, Int(1, optional=True), "trials per method (default: the file's trials, else 8)")
    methods: list[str] | None = option(
        None, ListOf(Text(), optional=True), "labels of the methods to tune (default: every one)"
    )
    out: str | None = option(
        None, Text(optional=True), "the tuning folder (default: the file's out, else runs/tune/<name>)"
    )
    config_dir: str | None = option(
        None, Text(optional=True), "a folder of your own config files, searched before the shipped ones"
    )


@dataclass(frozen=True)
class Dimension:
    """One searched option: a float range (``log`` for a log-uniform one) or a list of choices."""

    key: str
    low: float | None = None
    high: float | None = None
    log: bool = False
    choices: tuple = ()

    def contains(self, value: Any) -> bool:
        if self.choices:
            return value in self.choices
        return isinstance(value, (int, float)) and self.low <= value <= self.high  # type: ignore[operator]

    def describe(self) -> str:
        if self.choices:
            return "{" + ", ".join(str(c) for c in self.choices) + "}"
        return f"[{self.low:g}, {self.high:g}]" + (" log-uniform" if self.log else " uniform")


@dataclass
class TunedMethod:
    label: str
    name: str
    algo: str
    overrides: dict[str, Any]
    space: list[Dimension]
    enqueue: list[Any]  # CONFIG_VALUES or {key: value}


@dataclass
class Objective:
    metric: str
    reference: dict[str, float]
    description: str = ""

    def score(self, values: dict[str, float]) -> float:
        """Mean over the tasks of value / reference (each task's value from its run)."""
        return sum(values[t] / self.reference[t] for t in self.reference) / len(self.reference)


@dataclass
class Evaluation:
    """The fresh-seed sweep of the chosen values: every tuned method, plus variants (another algo with a tuned
    method's chosen values, e.g. ReFPO's one-step configuration)."""

    tasks: list[str]
    seeds: list[int]
    variants: list[dict[str, str]]  # {label, of, algo, name}


@dataclass
class Tuning:
    name: str
    source: str
    description: str
    device: str
    tasks: list[str]
    seed: int
    trials: int
    overrides: dict[str, Any]
    objective: Objective
    startup_trials: int
    pruner: dict[str, float] | None
    methods: list[TunedMethod]
    out_dir: Path
    evaluation: Evaluation | None = None
    folders: dict[str, Any] = field(default_factory=dict)  # config_dir=, passed to every run

    def trial_runs(self, method: TunedMethod, slot: int, values: dict[str, Any]) -> list[Run]:
        """The runs of one trial: one per task, in ``<out>/<label>/trial<slot>/<task>``."""
        overrides = {**self.overrides, **method.overrides, **values, **self.folders}
        row = Method(method.label, method.name, method.algo, overrides)
        runs = []
        for task in self.tasks:
            run_dir = self.out_dir / method.label / f"trial{slot:02d}" / task
            args = [f"task={task}", f"algo={method.algo}", f"seed={self.seed}", f"run_dir={run_dir}"]
            args += [f"{k}={cli_value(v)}" for k, v in overrides.items()]
            runs.append(Run(task, row, self.seed, run_dir, tuple(args)))
        return runs


def _dimension(key: str, spec: Any, where: str) -> Dimension:
    if not isinstance(spec, dict):
        raise ConfigError(f"{where}: space.{key} must be {{low, high, log}} or {{choices: [...]}}, got {spec!r}")
    if "choices" in spec:
        extra = sorted(set(spec) - set(DIMENSION_KEYS["categorical"]))
        choices = spec["choices"]
        if extra or not isinstance(choices, list) or len(choices) < 2:
            raise ConfigError(f"{where}: space.{key} takes only 'choices', a list of at least two values; got {spec!r}")
        return Dimension(key, choices=tuple(choices))
    for k in spec:
        if k not in DIMENSION_KEYS["float"]:
            raise unknown(f"key of space.{key} in {where}", k, DIMENSION_KEYS["float"] + DIMENSION_KEYS["categorical"])
    try:
        low, high, log = float(spec["low"]), float(spec["high"]), bool(spec.get("log", False))
    except (KeyError, TypeError, ValueError) as err:
        raise ConfigError(f"{where}: space.{key} needs numbers 'low' and 'high', got {spec!r}") from err
    if not (math.isfinite(low) and math.isfinite(high) and low < high) or (log and low <= 0):
        raise ConfigError(f"{where}: space.{key} needs finite low < high (and low > 0 when log), got {spec!r}")
    return Dimension(key, low, high, log)


def _method(given: Any, where: str) -> TunedMethod:
    entry = read_section(f"method of {where}", MethodSection, given)
    label = str(entry.label or entry.algo)
    space = entry.space
    if not space:
        raise ConfigError(f"{where}: method '{label}': 'space' must be a non-empty mapping of run options")
    dims = [_dimension(str(k), v, f"{where}, method '{label}'") for k, v in space.items()]
    overrides = _flat_overrides(entry.overrides, where)
    for key in overrides:
        if key in space:
            raise ConfigError(f"{where}: method '{label}' both fixes and searches '{key}'")
    enqueue = entry.enqueue
    for item in enqueue:
        if item != CONFIG_VALUES and not isinstance(item, dict):
            raise ConfigError(
                f"{where}: method '{label}': an 'enqueue' entry is '{CONFIG_VALUES}' or a mapping of "
                f"searched values, got {item!r}"
            )
    return TunedMethod(label, str(entry.name or label), entry.algo, overrides, dims, enqueue)


def _evaluation(given: Any, labels: list[str], where: str) -> Evaluation | None:
    if given is None:
        return None
    spec = read_section(f"evaluate of {where}", EvaluateSection, given)
    variants = []
    for entry in spec.variants or []:
        variant = read_section(f"evaluate variant of {where}", VariantSection, entry)
        if variant.of not in labels:
            raise unknown(f"tuned method (evaluate variant '{variant.label}' of) in {where}", variant.of, labels)
        variants.append({**vars(variant), "name": variant.name or variant.label})
    return Evaluation(list(spec.tasks), list(spec.seeds), variants)


def load_tuning(source: str, args: list[str] | None = None) -> Tuning:
    """Read a tuning file; command-line ``key=value``: ``TuneOptions``."""
    given, _ = parse_options("tune", TuneOptions, args or [])
    folders = {"config_dir": given.config_dir} if given.config_dir is not None else {}
    path = config_path(folders.get("config_dir")).named_or_path("tune", source)
    where = str(path)
    spec = read_section(f"tuning file {where}", TuningFile, load_yaml(path))
    tasks = spec.tasks
    objective = read_section(f"objective of {where}", ObjectiveSection, spec.objective)
    reference = objective.reference
    if sorted(reference) != sorted(tasks) or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in reference.values()
    ):
        raise ConfigError(
            f"{where}: objective.reference needs one positive number for each of {tasks}, got {reference!r}"
        )
    sampler = read_section(f"sampler of {where}", SamplerSection, spec.sampler or {})
    pruner = None if spec.pruner is None else read_section(f"pruner of {where}", PrunerSection, spec.pruner)
    overrides = _flat_overrides(spec.overrides, where)
    methods = [_method(m, where) for m in spec.methods]
    for m in methods:
        for key in [*overrides, *m.overrides, *(d.key for d in m.space)]:
            if key in MANAGED:
                raise ConfigError(f"{where}: '{key}' is set by the tuner for each trial run")
    labels = [m.label for m in methods]
    if len(set(labels)) != len(labels):
        raise ConfigError(f"{where}: method labels must be unique, got {labels}")
    if given.methods is not None:
        keep = given.methods
        for label in keep:
            if label not in labels:
                raise unknown(f"method of tuning '{path.stem}'", label, labels)
        methods = [m for m in methods if m.label in keep]
    evaluation = _evaluation(spec.evaluate, labels, where)
    trials = given.trials or spec.trials
    device = spec.device
    device_type(device)
    return Tuning(
        name=path.stem,
        source=str(path),
        description=spec.description.strip(),
        device=device,
        tasks=[str(t) for t in tasks],
        seed=spec.seed,
        trials=trials,
        overrides=overrides,
        objective=Objective(
            objective.metric, {str(k): float(v) for k, v in reference.items()}, objective.description.strip()
        ),
        startup_trials=sampler.startup_trials,
        pruner=None if pruner is None else vars(pruner),
        methods=methods,
        out_dir=Path(str(given.out or spec.out or Path("runs") / "tune" / path.stem)),
        evaluation=evaluation,
        folders=folders,
    )
