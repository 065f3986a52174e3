"""The options of ``refpo collect``, each a field with its default, rule and doc (``refpo_warp/utils/options.py``), and
their checks: ``collect_options`` validates a command line's ``key=value`` options against the fields, the usage of
``refpo collect --help`` lists them from the fields. Torch-free, so that ``refpo --help`` stays quick."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from refpo_warp.config.command_options import parse_options
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import DEVICE_RULE, Flag, Int, OneOf, Real, Text
from refpo_warp.utils.option_tables import shown_value
from refpo_warp.utils.options import declared_options, option

INITIAL_NOISE = ("random", "zero")  # eval.initial_noise's protocols
MAX_DEFAULT_ENVS = 64
SOURCES = ("run_dir", "task", "demonstrator")  # what is rolled out: in the usage's synopsis, not its option list


@dataclass(frozen=True)
class CollectOptions:
    run_dir: str | None = option(None, Text(optional=True), "a trained run whose policy is rolled out")
    checkpoint: str | None = option(
        None, Text(optional=True), "a checkpoint of the run (default: its newest usable one)"
    )
    task: str | None = option(None, Text(optional=True), "the task of a scripted demonstrator (demonstrator=scripted)")
    demonstrator: str | None = option(None, OneOf(None, "scripted"), "scripted: the task family's demonstrator")
    episodes: int = option(rule=Int(1, 10**8), doc="whole episodes written")
    out: str = option(rule=Text(), doc="the dataset folder written")
    noise: float = option(
        0.0, Real(0, 1e3), "std of Gaussian noise added to every action (the noisy action is stepped and stored)"
    )
    overwrite: bool = option(
        False, Flag(), "an existing out is refused unless overwrite=true (the old dataset is replaced whole)"
    )
    num_envs: int | None = option(
        None, Int(1, 1 << 22, optional=True), f"envs stepped together (default: min(episodes, {MAX_DEFAULT_ENVS}))"
    )
    seed: int | None = option(
        None,
        Int(0, 2**32 - 1, optional=True),
        "seed of the envs and the policy's noise (default: the run's seed + 20000; a demonstrator's: 1)",
    )
    flow_steps: int | None = option(
        None, Int(1, 1000, optional=True), "Euler steps of a flow policy (default: its num_flow_steps)"
    )
    initial_noise: str = option(
        "random",
        OneOf(*INITIAL_NOISE),
        "random: a flow from random initial noise, a Gaussian's sample; zero: zero initial noise, a Gaussian's mean "
        "(as eval.initial_noise)",
    )
    device: str = option("auto", DEVICE_RULE, "where the policy and the envs run (auto: cuda:0 if usable, else cpu)")


def options_usage() -> str:
    """The usage's option lines: every option outside the synopsis with its default and doc, from the fields."""
    declared = declared_options(CollectOptions)
    names = [n for n in declared if n not in SOURCES]
    given = {n: f"{n}={shown_value(declared[n].default).strip('`')}" for n in names}
    width = max(len(g) for g in given.values()) + 2
    return "\n".join(f"    {given[n]:<{width}}{declared[n].doc}" for n in names)


PASSED_ON = ("demonstrator.", "env.")  # checked where they apply: the demonstrator's fields, the task's env cfg


def PASSED(key: str) -> bool:
    """A scripted demonstrator's option (``demonstrator.<option>``) or an env option (``env.<option>``)."""
    return key.startswith(PASSED_ON)


def collect_options(flat: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """(checked options, demonstrator options, env options); every problem a ``ConfigError`` naming the key and valid
    values. The env options are checked against the task's env cfg by ``collect`` (a run's task is in its config)."""
    parsed, passed = parse_options("collect", CollectOptions, flat, PASSED, [f"{p}<option>" for p in PASSED_ON])
    demo = {k.split(".", 1)[1]: v for k, v in passed.items() if k.startswith("demonstrator.")}
    env = {k.split(".", 1)[1]: v for k, v in passed.items() if k.startswith("env.")}
    options = asdict(parsed)
    if (options["run_dir"] is None) == (options["demonstrator"] is None):
        raise ConfigError("refpo collect needs either run_dir=<trained run> or task=<task> demonstrator=scripted")
    if options["demonstrator"] and not options["task"]:
        raise ConfigError("demonstrator=scripted needs task=<task id>")
    if options["run_dir"] and options["task"]:
        raise ConfigError("task= comes from the run's config.yaml with run_dir=; give one of them")
    if demo and not options["demonstrator"]:
        raise ConfigError(
            f"demonstrator.{next(iter(demo))} is an option of a scripted demonstrator (demonstrator=scripted)"
        )
    out = Path(options["out"])
    if out.exists() and not options["overwrite"]:
        raise ConfigError(f"out={out} exists; pass overwrite=true to replace it, or choose another out")
    if out.exists() and not out.is_dir():
        raise ConfigError(f"out={out} is a file; a dataset is a folder: choose another out")
    return options, demo, env
