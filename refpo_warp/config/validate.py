"""Every key of a merged config checked where it is consumed, each value against the rule its option field declares
(``refpo_warp/utils/options.py``):

- ``actor``, ``critic``, ``algorithm``: against the constructor of the class their ``class_name`` selects and that
  class's rules;
- ``env`` and ``eval.env``: against the task's env cfg dataclass and its rules; ``video`` against ``VideoOptions``;
- every other key: against the fields of ``refpo_warp/config/run_options.py``.

An unknown key is an error that names the closest valid one; a refused value names the key and the valid range or
choices.
"""

from __future__ import annotations

from refpo_warp.config.classes import CLASS_SECTIONS, check_class_kind, section_options
from refpo_warp.config.dotted import LEAF_KEYS
from refpo_warp.config.run_options import NOT_RULED, RUN_RULES
from refpo_warp.envs.registry import check_env_options
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import check_options
from refpo_warp.utils.options import rules_for


def class_section(section: str, values: dict) -> dict:
    """A class section: its class_name checked, then every option against the constructor and the class's rules."""
    if "class_name" not in values:
        raise ConfigError(f"Section '{section}' needs a class_name (e.g. refpo_warp.models:FlowActor)")
    cls = check_class_kind(section, values["class_name"])
    params = section_options(section, values["class_name"])
    options = {k: v for k, v in values.items() if k != "class_name"}
    for key in options:
        if key not in params:
            err = unknown(
                f"key '{section}.{key}' for {values['class_name']}",
                f"{section}.{key}",
                [f"{section}.{k}" for k in params],
            )
            raise ConfigError(
                f"{err} (A task file keeps keys that only some algorithms accept under by_algo.<algo>.{section}.)"
            )
    return {"class_name": values["class_name"], **check_options(rules_for(cls), options, f"{section}.")}


def env_section(task: TaskSpec, values: dict, prefix: str = "env.") -> dict:
    """Env options: fields of the task's env cfg (the family's options and the task's own), each checked by the cfg's
    rules."""
    check_env_options(task, values, prefix)
    return check_options(rules_for(task.cfg_class), values, prefix)


def video_section(values: dict) -> dict:
    """Video options: fields of ``VideoOptions``, each checked by its rules (the given keys only)."""
    from refpo_warp.render.options import VideoOptions

    VideoOptions.from_dict(values)
    return check_options(rules_for(VideoOptions), values, "video.")


def run_options(cfg: dict, schema: dict, prefix: str = "") -> None:
    """Check (and normalise in place) every key of ``cfg`` against ``schema`` (the run options' defaults) and its run
    rule."""
    for key, value in cfg.items():
        dotted = f"{prefix}{key}"
        if key not in schema:
            raise unknown("config key", dotted, _schema_keys(schema, prefix))
        if isinstance(schema[key], dict) and schema[key] and isinstance(value, dict) and key not in LEAF_KEYS:
            run_options(value, schema[key], dotted + ".")
        elif isinstance(schema[key], dict) and not isinstance(value, dict) and key not in LEAF_KEYS:
            raise section_error(dotted, value)
        elif dotted in RUN_RULES:
            cfg[key] = RUN_RULES[dotted].check(dotted, value)


def _schema_keys(schema: dict, prefix: str = "") -> list[str]:
    keys = []
    for key, value in schema.items():
        keys.append(prefix + key)
        if isinstance(value, dict) and value:
            keys += _schema_keys(value, f"{prefix}{key}.")
    return keys


def section_error(key: str, value: object) -> ConfigError:
    return ConfigError(f"'{key}' is a section; set its keys ({key}.<key>=...), not {key}={value!r}")


def validate(cfg: dict, defaults: dict, task: TaskSpec) -> dict:
    """The merged config with every section validated (see the module docstring); ``defaults`` is the run options'
    (``run_defaults``), ``task`` the spec of ``cfg["task"]``."""
    for key in NOT_RULED:  # the sections other classes check: each a mapping
        section, _, name = key.rpartition(".")
        node = cfg.get(section) if section else cfg
        if isinstance(node, dict) and node.get(name) is not None and not isinstance(node[name], dict):
            raise section_error(key, node[name])
    for section in CLASS_SECTIONS:
        cfg[section] = class_section(section, cfg.get(section) or {})
    cfg["env"] = env_section(task, cfg.get("env") or {})
    cfg["video"] = video_section(cfg.get("video") or {})
    if isinstance(cfg.get("eval"), dict):
        cfg["eval"]["env"] = env_section(task, cfg["eval"].get("env") or {}, "eval.env.")
    plain = {k: v for k, v in cfg.items() if k not in CLASS_SECTIONS + ("env", "video")}
    run_options(plain, {k: v for k, v in defaults.items() if k not in CLASS_SECTIONS + ("env", "video")})
    cfg.update(plain)
    return cfg
