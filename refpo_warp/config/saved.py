"""A run's config resolved once, with the spec of its task (``Resolution``): a new run's (``resolve_run``), or the
saved config (``<run dir>/config.yaml``) with the overrides of a resume or an evaluation (``load_run``).

Resume rule: a resumed run keeps its task, algorithm and model. An option that would change them (``task``,
``algo``, every ``class_name``, actor/critic options, and options whose rule says ``fixed=True``, such as
``runner.obs_groups`` or ``algorithm.optimizer``) is refused, naming each differing key; everything else (learning
rate, budget, evaluation, device, ...) may change.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from refpo_warp.config.classes import CLASS_SECTIONS, class_parameters, resolve_class
from refpo_warp.config.dotted import flatten
from refpo_warp.config.resolve import Resolution, identity, resolve, run_config_set
from refpo_warp.config.run_options import RUN_RULES, run_defaults
from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.utils.errors import ConfigError, DataFileError
from refpo_warp.utils.options import rules_for

RUN_CONFIG = "config.yaml"
IDENTITY_KEYS = ("task", "algo")


def read_saved_config(run_dir: Path) -> dict:
    """The saved config of a run as written (not resolved); ``ConfigError`` if ``run_dir`` is not a run,
    ``DataFileError`` if the file is damaged."""
    saved = Path(run_dir) / RUN_CONFIG
    if not Path(run_dir).is_dir():
        raise ConfigError(f"run_dir={run_dir}: no such run directory")
    if not saved.exists():
        raise ConfigError(f"{saved} not found: '{run_dir}' is not a refpo_warp run directory")
    data = load_yaml(saved, error=DataFileError)
    for key in IDENTITY_KEYS:
        if not isinstance(data.get(key), str):
            raise DataFileError(f"{saved}: no '{key}' in it; the file was edited or damaged")
    return data


def default_run_dir(task: str, algo: str, seed: int) -> Path:
    return Path("runs") / task / f"{algo}_seed{seed}"


def resolve_run(flat: dict[str, Any]) -> Resolution:
    """The config of the run ``flat`` asks for and its task's spec, resolved once: a new one, or a resumed one (its
    saved config + the overrides, from ``run_dir`` or the default run dir of the task, algo and seed asked for).
    ``run_dir`` is always set (a new run's default: ``runs/<task>/<algo>_seed<seed>``)."""
    if RUN_RULES["resume"].check("resume", flat.get("resume", False)):
        run_dir = flat.get("run_dir") or str(_resumed_run_dir(flat))
        run = load_run(Path(run_dir), {**flat, "run_dir": run_dir})
    else:
        run = resolve(flat)
    cfg = run.cfg
    cfg["run_dir"] = str(cfg["run_dir"] or default_run_dir(cfg["task"], cfg["algo"], cfg["seed"]))
    return run


def _resumed_run_dir(flat: dict[str, Any]) -> Path:
    """The default run dir of the task, algo and seed that ``flat`` asks for (each checked)."""
    configs = run_config_set(flat)
    task, algo = identity(flat)
    configs.identity(task, algo)
    return default_run_dir(task, algo, RUN_RULES["seed"].check("seed", flat.get("seed", run_defaults()["seed"])))


def load_run(run_dir: Path, overrides: dict[str, Any]) -> Resolution:
    """The saved config of a run with ``overrides`` applied on top, resolved once (to resume, evaluate, record or
    collect); refuses overrides that would change the run's task, algorithm or model."""
    saved = read_saved_config(run_dir)
    for key in IDENTITY_KEYS:
        if key in overrides and str(overrides[key]) != saved[key]:
            raise ConfigError(
                f"{key}={overrides[key]} differs from the run's {key}={saved[key]} ({run_dir}); a run "
                f"keeps its {key}: choose another run_dir for a new run"
            )
    flat = flatten(saved)
    try:
        run = resolve({**flat, **overrides})
    except ConfigError as err:
        try:  # whose fault: the file's (it no longer resolves on its own) or the overrides'
            resolve(flat)
        except ConfigError:
            raise DataFileError(f"{Path(run_dir) / RUN_CONFIG}: {err}") from None
        raise
    changed = fixed_changes(saved, run.cfg, run.task)
    if changed:
        raise ConfigError(
            f"the run in {run_dir} keeps its task, algorithm and model, but these options differ from "
            f"its config.yaml: {'; '.join(changed)}. Choose another run_dir for a new run"
        )
    return run


def fixed_changes(saved: dict, cfg: dict, task: TaskSpec) -> list[str]:
    """``key: saved -> new`` for every option that may not change on resume and does. An option the saved config
    does not list (left at its default, or added to the code since) is compared with its default. ``task``: the spec
    of ``cfg["task"]``."""
    old, new = flatten(saved), flatten(cfg)
    changes = []
    for key, value in new.items():
        if not _is_fixed(cfg, task, key):
            continue
        before = old[key] if key in old else _default(cfg, task, key)
        if before is not _UNKNOWN and _plain(before) != _plain(value):
            changes.append(f"{key}: {before!r} -> {value!r}")
    return changes


_UNKNOWN = object()


def _plain(value: Any) -> Any:
    """Tuples as lists: a constructor's default ``(256, 256)`` is the config's ``[256, 256]``."""
    return [_plain(v) for v in value] if isinstance(value, (list, tuple)) else value


def _default(cfg: dict, task: TaskSpec, key: str) -> Any:
    """The value an option has when a config does not set it (constructor or env cfg default)."""
    section, _, name = key.partition(".")
    if section in CLASS_SECTIONS and "." not in name:
        return class_parameters(cfg[section]["class_name"]).get(name, _UNKNOWN)
    if section == "env" and "." not in name:
        return task.cfg_class.defaults().get(name, _UNKNOWN)
    return _UNKNOWN


def _is_fixed(cfg: dict, task: TaskSpec, key: str) -> bool:
    section, _, name = key.partition(".")
    if key in IDENTITY_KEYS:
        return True
    if section in CLASS_SECTIONS:
        if name == "class_name":
            return True
        rule = rules_for(resolve_class(cfg[section]["class_name"])).get(name.split(".")[0])
        default = section in ("actor", "critic")  # the networks
        return default if rule is None or rule.fixed is None else rule.fixed
    if section == "env":
        rule = rules_for(task.cfg_class).get(name)
        return bool(rule is not None and rule.fixed)
    rule = RUN_RULES.get(key)
    return bool(rule is not None and rule.fixed)
