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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from refpo_warp.config.config_path import config_path
from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.sweeps.spec import Method, Run, _flat_overrides, cli_value, device_type
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import Int, ListOf, Text
from refpo_warp.utils.options import option

SPEC_KEYS = (
    "description",
    "device",
    "tasks",
    "seed",
    "trials",
    "overrides",
    "objective",
    "sampler",
    "pruner",
    "methods",
    "evaluate",
    "out",
)
METHOD_KEYS = ("label", "algo", "name", "overrides", "enqueue", "space")
OBJECTIVE_KEYS = ("metric", "reference", "description")
SAMPLER_KEYS = ("startup_trials",)
PRUNER_KEYS = ("percentile", "startup_trials", "warmup_evaluations")
EVALUATE_KEYS = ("tasks", "seeds", "variants")
VARIANT_KEYS = ("label", "of", "algo", "name")
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


def _method(entry: Any, where: str) -> TunedMethod:
    if not isinstance(entry, dict) or "algo" not in entry or "space" not in entry:
        raise ConfigError(
            f"{where}: each method needs 'algo' and 'space' (and optionally label, name, overrides, "
            f"enqueue), got {entry!r}"
        )
    for key in entry:
        if key not in METHOD_KEYS:
            raise unknown(f"method key in {where}", key, METHOD_KEYS)
    label = str(entry.get("label", entry["algo"]))
    space = entry["space"]
    if not isinstance(space, dict) or not space:
        raise ConfigError(f"{where}: method '{label}': 'space' must be a non-empty mapping of run options")
    dims = [_dimension(str(k), v, f"{where}, method '{label}'") for k, v in space.items()]
    overrides = _flat_overrides(entry.get("overrides"), where)
    for key in overrides:
        if key in space:
            raise ConfigError(f"{where}: method '{label}' both fixes and searches '{key}'")
    enqueue = entry.get("enqueue", [CONFIG_VALUES])
    if not isinstance(enqueue, list):
        raise ConfigError(f"{where}: method '{label}': 'enqueue' must be a list of '{CONFIG_VALUES}' or mappings")
    for item in enqueue:
        if item != CONFIG_VALUES and not isinstance(item, dict):
            raise ConfigError(
                f"{where}: method '{label}': an 'enqueue' entry is '{CONFIG_VALUES}' or a mapping of "
                f"searched values, got {item!r}"
            )
    return TunedMethod(label, str(entry.get("name", label)), str(entry["algo"]), overrides, dims, enqueue)


def _evaluation(spec: Any, labels: list[str], where: str) -> Evaluation | None:
    if spec is None:
        return None
    if not isinstance(spec, dict):
        raise ConfigError(f"{where}: 'evaluate' must be a mapping with tasks, seeds and optionally variants")
    for key in spec:
        if key not in EVALUATE_KEYS:
            raise unknown(f"evaluate key in {where}", key, EVALUATE_KEYS)
    tasks, seeds = spec.get("tasks"), spec.get("seeds")
    if not isinstance(tasks, list) or not tasks or not isinstance(seeds, list) or not seeds:
        raise ConfigError(f"{where}: evaluate needs non-empty lists 'tasks' and 'seeds'")
    variants = []
    for entry in spec.get("variants") or []:
        if not isinstance(entry, dict) or not {"label", "of", "algo"} <= set(entry):
            raise ConfigError(f"{where}: an evaluate variant needs label, of (a tuned method) and algo, got {entry!r}")
        for key in entry:
            if key not in VARIANT_KEYS:
                raise unknown(f"evaluate variant key in {where}", key, VARIANT_KEYS)
        if entry["of"] not in labels:
            raise unknown(f"tuned method (evaluate variant '{entry['label']}' of) in {where}", entry["of"], labels)
        variants.append({k: str(entry.get(k, entry["label"])) for k in VARIANT_KEYS})
    return Evaluation([str(t) for t in tasks], [_int(s, "evaluate.seeds", where, 0) for s in seeds], variants)


def _int(value: Any, key: str, where: str, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise ConfigError(f"{where}: '{key}' must be an integer >= {low}, got {value!r}")
    return value


def load_tuning(source: str, args: list[str] | None = None) -> Tuning:
    """Read a tuning file; command-line ``key=value``: ``TuneOptions``."""
    from refpo_warp.config.command_options import parse_options

    given, _ = parse_options("tune", TuneOptions, args or [])
    folders = {"config_dir": given.config_dir} if given.config_dir is not None else {}
    path = config_path(folders.get("config_dir")).named_or_path("tune", source)
    spec = load_yaml(path)
    where = str(path)
    for key in spec:
        if key not in SPEC_KEYS:
            raise unknown(f"key in tuning file {where}", key, SPEC_KEYS)
    tasks = spec.get("tasks")
    if not isinstance(tasks, list) or not tasks:
        raise ConfigError(f"{where}: 'tasks' must be a non-empty list of task ids")
    objective = spec.get("objective")
    if not isinstance(objective, dict) or "metric" not in objective or "reference" not in objective:
        raise ConfigError(f"{where}: 'objective' needs 'metric' and 'reference' (a positive number per task)")
    for key in objective:
        if key not in OBJECTIVE_KEYS:
            raise unknown(f"objective key in {where}", key, OBJECTIVE_KEYS)
    reference = objective["reference"]
    if (
        not isinstance(reference, dict)
        or sorted(reference) != sorted(tasks)
        or not all(isinstance(v, (int, float)) and v > 0 for v in reference.values())
    ):
        raise ConfigError(
            f"{where}: objective.reference needs one positive number for each of {tasks}, got {reference!r}"
        )
    sampler = spec.get("sampler") or {}
    for key in sampler:
        if key not in SAMPLER_KEYS:
            raise unknown(f"sampler key in {where}", key, SAMPLER_KEYS)
    pruner = spec.get("pruner")
    if pruner is not None:
        for key in pruner:
            if key not in PRUNER_KEYS:
                raise unknown(f"pruner key in {where}", key, PRUNER_KEYS)
        if not 0 < float(pruner.get("percentile", 25)) < 100:
            raise ConfigError(f"{where}: pruner.percentile must lie in (0, 100)")
    overrides = _flat_overrides(spec.get("overrides"), where)
    methods = [_method(m, where) for m in spec.get("methods") or []]
    if not methods:
        raise ConfigError(f"{where}: 'methods' must be a non-empty list")
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
    evaluation = _evaluation(spec.get("evaluate"), labels, where)
    trials = given.trials or _int(spec.get("trials", 8), "trials", where, 1)
    device = str(spec.get("device", "auto"))
    device_type(device)
    return Tuning(
        name=path.stem,
        source=str(path),
        description=str(spec.get("description", "")).strip(),
        device=device,
        tasks=[str(t) for t in tasks],
        seed=_int(spec.get("seed", 101), "seed", where, 0),
        trials=trials,
        overrides=overrides,
        objective=Objective(
            str(objective["metric"]),
            {str(k): float(v) for k, v in reference.items()},
            str(objective.get("description", "")).strip(),
        ),
        startup_trials=_int(sampler.get("startup_trials", 4), "sampler.startup_trials", where, 0),
        pruner=None
        if pruner is None
        else {
            "percentile": float(pruner.get("percentile", 25)),
            "startup_trials": _int(pruner.get("startup_trials", 3), "pruner.startup_trials", where, 0),
            "warmup_evaluations": _int(pruner.get("warmup_evaluations", 5), "pruner.warmup_evaluations", where, 0),
        },
        methods=methods,
        out_dir=Path(str(given.out or spec.get("out") or Path("runs") / "tune" / path.stem)),
        evaluation=evaluation,
        folders=folders,
    )
