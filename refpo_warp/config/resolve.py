"""Run configuration: YAML layers plus ``key=value`` overrides, validated key by key.

Layers, later winning: ``configs/default.yaml`` < ``configs/algo/<algo>.yaml`` < ``configs/task/<task>.yaml``
(after the task files it names in ``base``) < the task's ``by_device.<cpu|cuda>`` < its ``by_algo.<algo>`` <
``by_device.<cpu|cuda>.by_algo.<algo>`` < command-line overrides. Task and algo files hold deltas only. Keys of
``actor``, ``critic`` and ``algorithm`` that only some algorithms accept belong under ``by_algo`` in task files.

Keys are validated where they are consumed: ``env.*`` against the task's env cfg dataclass, ``actor.*``,
``critic.*`` and ``algorithm.*`` against the constructor of the class their ``class_name`` selects, and every other
key against ``default.yaml``. An unknown key is an error that names the closest valid one. Env options may also be
given without their ``env.`` prefix (``motion_file=...``). A key given twice (on the command line or in one YAML
mapping) is an error.

Values are checked against the option rules (``refpo_warp.utils.option_rules``): the rules a class, env cfg or
``refpo_warp.config.run_options`` declares next to its options, the same ones its constructor checks. So a refused value
is reported, with the key and the valid range or choices, before anything is built or written.
"""

from __future__ import annotations

import copy
import dataclasses
import inspect
from pathlib import Path
from typing import Any

import yaml

from refpo_warp.config.run_options import RUN_RULES, check_combinations
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.option_rules import check_options, rules_for
from refpo_warp.utils.paths import CONFIG_DIR

CLASS_SECTIONS = ("actor", "critic", "algorithm")
PROFILE_KEYS = ("base", "by_device", "by_algo")
# Mappings that are values, not config sections: merged, validated and flattened as a whole (obs_groups has
# free-form group names; distribution_cfg is one class's constructor kwargs, replaced rather than merged key-wise).
LEAF_KEYS = ("obs_groups", "distribution_cfg")
# Top-level keys of a task file starting with "_" are YAML anchors for reuse inside that file, not options.


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that refuses a key given twice in one mapping (YAML itself keeps the last one silently)."""

    def construct_mapping(self, node, deep=False):
        seen: dict = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":  # '<<: *anchor' may be repeated and overridden
                continue
            key = self.construct_object(key_node, deep=True)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key '{key}' is given twice (also {seen[key]})", key_node.start_mark
                )
            seen[key] = f"line {key_node.start_mark.line + 1}"
        return super().construct_mapping(node, deep=deep)


def load_yaml(path: Path, error: type[Exception] = ConfigError) -> dict:
    """Read a YAML mapping; any problem (unreadable, not YAML, duplicate key, not a mapping) raises ``error``
    naming the file."""
    try:
        with open(path, encoding="utf-8") as f:
            data = yaml.load(f, Loader=_UniqueKeyLoader) or {}
    except FileNotFoundError as err:
        raise error(f"{path}: no such file") from err
    except (OSError, UnicodeDecodeError) as err:
        raise error(f"{path}: cannot be read ({err})") from err
    except yaml.YAMLError as err:
        raise error(f"{path}: not valid YAML ({' '.join(str(err).split())})") from err
    if not isinstance(data, dict):
        raise error(f"{path}: expected a mapping at the top level")
    return data


def merge(base: dict, delta: dict) -> dict:
    """Deep-merge ``delta`` into a copy of ``base`` (mappings merge, everything else replaces)."""
    out = copy.deepcopy(base)
    for key, value in delta.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict) and key not in LEAF_KEYS:
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def parse_overrides(args: list[str]) -> dict[str, Any]:
    """Parse ``key=value`` strings (values are YAML: numbers, bools, lists) into a flat dotted-key dict.

    ``--key=value`` and ``--key-name=value`` are accepted too; a key given twice is an error.
    """
    out: dict[str, Any] = {}
    given: dict[str, str] = {}
    for arg in args:
        if "=" not in arg:
            raise ConfigError(f"Expected key=value, got '{arg}' (example: task=gridworld seed=3 num_envs=256)")
        key, raw = arg.split("=", 1)
        key = key.strip().lstrip("-").replace("-", "_") if key.startswith("--") else key.strip()
        if not key:
            raise ConfigError(f"Expected key=value, got '{arg}': the key is empty")
        if key in given:
            raise ConfigError(f"'{key}' is given twice on the command line ('{given[key]}' and '{arg}'); give it once")
        given[key] = arg
        try:
            out[key] = yaml.safe_load(raw) if raw != "" else ""
        except yaml.YAMLError:
            out[key] = raw
    return out


def _choices(kind: str) -> list[str]:
    return sorted(p.stem for p in (CONFIG_DIR / kind).glob("*.yaml") if not p.stem.startswith("_"))


def algo_names() -> list[str]:
    """Every ``algo=`` choice: the files ``configs/algo/<algo>.yaml``."""
    return _choices("algo")


def task_config_path(task: str) -> Path:
    """The training config file of a registered task: its spec's ``config_file``, else ``configs/task/<task>.yaml``."""
    from refpo_warp.envs.registry import get_task

    config_file = get_task(task).config_file
    return Path(config_file) if config_file is not None else CONFIG_DIR / "task" / f"{task}.yaml"


def _task_layers(task: str, seen: tuple[str, ...] = ()) -> dict:
    """The task's config file merged over its ``base`` chain (bases are ``configs/task/<base>.yaml``)."""
    path = task_config_path(task) if not seen else CONFIG_DIR / "task" / f"{task}.yaml"
    if not path.exists():
        what = f"task '{task}' is registered, but its config file" if not seen else f"base '{task}' of {seen[-1]}:"
        raise ConfigError(f"{what} {path} does not exist (every task needs one; it may hold just a 'base' line)")
    data = load_yaml(path)
    merged: dict = {}
    for base in [data.get("base")] if isinstance(data.get("base"), str) else data.get("base") or []:
        if base in seen:
            raise ConfigError(f"{path}: circular 'base' chain {' -> '.join(seen + (base,))}")
        merged = merge(merged, _task_layers(base, seen + (task,)))
    return merge(merged, data)


def _set_dotted(cfg: dict, key: str, value: Any) -> None:
    node = cfg
    parts = key.split(".")
    for part in parts[:-1]:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise ConfigError(f"Cannot set '{key}': '{part}' is not a section")
    node[parts[-1]] = value


def _coerce(value: Any, default: Any, key: str) -> Any:
    """Coerce a value to the type of its default (YAML reads '3e-4' as a string, '1' as an int)."""
    if default is None or value is None:
        return value
    if isinstance(default, bool):
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.lower() in ("true", "false", "yes", "no", "1", "0"):
            return value.lower() in ("true", "yes", "1")
    elif isinstance(default, int):
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        if isinstance(value, float) and value.is_integer():
            return int(value)
        if isinstance(value, str) and value.strip().lstrip("-").isdigit():
            return int(value)
    elif isinstance(default, float):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        if isinstance(value, str):
            try:
                return float(value)
            except ValueError:
                pass
    elif isinstance(default, (list, tuple)):
        if isinstance(value, (list, tuple)):
            return list(value)
    elif isinstance(default, str):
        if isinstance(value, (str, int, float)) and not isinstance(value, bool):
            return str(value)
    else:
        return value
    kind = {"int": "an integer", "float": "a number", "bool": "true or false", "str": "a string"}.get(
        type(default).__name__, f"a {type(default).__name__}")
    raise ConfigError(f"'{key}' expects {kind} (like {default!r}), got {value!r}")


def resolve_class(class_name: str) -> type:
    """The class a ``class_name`` string selects (``"pkg.mod:Class"``, or a bare rsl_rl name)."""
    from rsl_rl.utils import resolve_callable

    from refpo_warp.algorithms import rsl_rl_rules as _ppo_rules  # noqa: F401  (register the rules of rsl_rl's classes)
    from refpo_warp.models import rsl_rl_rules as _model_rules  # noqa: F401

    try:
        return resolve_callable(class_name)
    except (ImportError, AttributeError, ValueError, TypeError) as err:
        raise ConfigError(f"Cannot resolve class_name '{class_name}': {err}") from err


def class_parameters(class_name: str) -> dict[str, Any]:
    """Constructor keyword parameters (with defaults) of ``class_name`` and of the bases it forwards to."""
    cls = resolve_class(class_name)
    params: dict[str, Any] = {}
    for klass in inspect.getmro(cls) if inspect.isclass(cls) else [cls]:
        init = klass.__init__ if inspect.isclass(klass) else klass
        if init is object.__init__:
            continue
        sig = inspect.signature(init)
        has_var_kw = False
        for name, p in sig.parameters.items():
            if p.kind is p.VAR_KEYWORD:
                has_var_kw = True
            elif p.kind is not p.VAR_POSITIONAL and name != "self":
                params.setdefault(name, None if p.default is p.empty else p.default)
        if not has_var_kw:  # a class that does not forward **kwargs ends the chain
            break
    return params


def _check_class_kind(section: str, class_name: str) -> None:
    """A class_name must select a model (actor, critic: a torch Module) or an algorithm (a class with rsl_rl's
    ``construct_algorithm``), never an arbitrary callable such as ``os:system`` named in an edited config file."""
    import torch

    cls = resolve_class(class_name)
    if section in ("actor", "critic"):
        valid = inspect.isclass(cls) and issubclass(cls, torch.nn.Module)
        kind = "a model class (a torch.nn.Module, e.g. refpo_warp.models:FlowActor or rsl_rl.models:MLPModel)"
    else:
        valid = inspect.isclass(cls) and callable(getattr(cls, "construct_algorithm", None))
        kind = "an algorithm class with rsl_rl's construct_algorithm (e.g. refpo_warp.algorithms:ReFPO)"
    if not valid:
        raise ConfigError(f"{section}.class_name={class_name!r} is invalid; expected {kind}")


# Constructor arguments that rsl_rl itself passes positionally; a config must not set them.
_POSITIONAL = {"actor": ("obs", "obs_groups", "obs_set", "output_dim"),
               "critic": ("obs", "obs_groups", "obs_set", "output_dim"),
               "algorithm": ("actor", "critic", "storage", "device", "multi_gpu_cfg")}  # fmt: skip


def _validate_class_section(section: str, values: dict) -> dict:
    if "class_name" not in values:
        raise ConfigError(f"Section '{section}' needs a class_name (e.g. refpo_warp.models:FlowActor)")
    _check_class_kind(section, values["class_name"])
    params = class_parameters(values["class_name"])
    for pos in _POSITIONAL[section]:
        params.pop(pos, None)
    if section == "algorithm":
        params["share_cnn_encoders"] = None  # consumed by rsl_rl's construct_algorithm
    out = {"class_name": values["class_name"]}
    for key, value in values.items():
        if key == "class_name":
            continue
        if key not in params:
            err = unknown(f"key '{section}.{key}' for {values['class_name']}", f"{section}.{key}",
                          [f"{section}.{k}" for k in params])
            raise ConfigError(f"{err} (A task file keeps keys that only some algorithms accept under "
                              f"by_algo.<algo>.{section}.)")
        out[key] = _coerce(value, params[key], f"{section}.{key}")
    return {"class_name": out.pop("class_name"), **check_options(rules_for(resolve_class(values["class_name"])),
                                                                 out, f"{section}.")}  # fmt: skip


def _validate_env_section(task: str, values: dict, prefix: str = "env.") -> dict:
    from refpo_warp.envs.registry import get_task

    cfg_class = get_task(task).cfg_class
    fields = {f.name: f for f in dataclasses.fields(cfg_class)}
    out = {}
    for key, value in values.items():
        if key not in fields:
            raise unknown(f"env option for task '{task}'", f"{prefix}{key}", [f"{prefix}{k}" for k in fields])
        f = fields[key]
        default = f.default if f.default is not dataclasses.MISSING else None
        out[key] = _coerce(value, default, f"{prefix}{key}")
    return check_options(rules_for(cfg_class), out, prefix)


def _validate_plain(cfg: dict, schema: dict, prefix: str = "") -> None:
    """Check every key of ``cfg`` against ``schema`` (default.yaml) and coerce values to the default's type."""
    for key, value in cfg.items():
        dotted = f"{prefix}{key}"
        if key not in schema:
            raise unknown("config key", dotted, _flatten_keys(schema, prefix))
        if isinstance(schema[key], dict) and schema[key] and isinstance(value, dict) and key not in LEAF_KEYS:
            _validate_plain(value, schema[key], dotted + ".")
        elif isinstance(schema[key], dict) and not isinstance(value, dict) and key not in LEAF_KEYS:
            raise ConfigError(f"'{dotted}' is a section; set its keys ({dotted}.<key>=...), not {dotted}={value!r}")
        else:
            cfg[key] = _coerce(value, schema[key], dotted)
            if dotted in RUN_RULES:
                cfg[key] = RUN_RULES[dotted].check(dotted, cfg[key])


def _flatten_keys(schema: dict, prefix: str = "") -> list[str]:
    keys = []
    for key, value in schema.items():
        keys.append(prefix + key)
        if isinstance(value, dict) and value:
            keys += _flatten_keys(value, f"{prefix}{key}.")
    return keys


def resolve_config(overrides: list[str] | dict[str, Any] | None = None, device_type: str | None = None) -> dict:
    """Build and validate the full run config from the YAML layers and ``key=value`` overrides.

    Args:
        overrides: ``["task=dmc_cheetah_run", "algorithm.reflow_coef=0.1", ...]`` or an equivalent dotted dict.
        device_type: ``"cpu"`` or ``"cuda"`` profile to apply; default: from the resolved ``device``.
    """
    flat = parse_overrides(overrides) if isinstance(overrides, list) else dict(overrides or {})
    defaults = load_yaml(CONFIG_DIR / "default.yaml")
    task = str(flat.pop("task", defaults.get("task")))
    algo = str(flat.pop("algo", defaults.get("algo")))

    from refpo_warp.envs.registry import list_tasks

    if task not in list_tasks():
        raise unknown("task", task, list_tasks())
    if algo not in _choices("algo"):
        raise unknown("algo", algo, _choices("algo"))

    # Env options may be given without the "env." prefix (e.g. motion_file=clips/ or conditioning=root).
    from refpo_warp.envs.registry import get_task

    env_fields = {f.name for f in dataclasses.fields(get_task(task).cfg_class)}
    for key in [k for k in flat if "." not in k and k not in defaults and k in env_fields]:
        if f"env.{key}" in flat:
            raise ConfigError(f"'{key}' and 'env.{key}' are the same option, given twice; give it once")
        flat[f"env.{key}"] = flat.pop(key)

    task_cfg = _task_layers(task)
    cfg = merge(defaults, load_yaml(CONFIG_DIR / "algo" / f"{algo}.yaml"))
    cfg = merge(cfg, {k: v for k, v in task_cfg.items() if k not in PROFILE_KEYS and not k.startswith("_")})
    cfg["task"], cfg["algo"] = task, algo

    if device_type is None:
        from refpo_warp.utils.device import resolve_device

        device_type = resolve_device(str(flat.get("device", cfg.get("device", "auto")))).split(":")[0]
    device_profile = dict((task_cfg.get("by_device") or {}).get(device_type, {}))
    device_by_algo = device_profile.pop("by_algo", None) or {}
    cfg = merge(cfg, device_profile)
    cfg = merge(cfg, (task_cfg.get("by_algo") or {}).get(algo, {}))
    cfg = merge(cfg, device_by_algo.get(algo, {}))
    for key, value in flat.items():
        if key in PROFILE_KEYS:
            raise ConfigError(f"'{key}' is a config-file key, not a run option")
        _set_dotted(cfg, key, value)

    # Validate: class sections against constructors, env against the task, the rest against default.yaml.
    for section in CLASS_SECTIONS:
        cfg[section] = _validate_class_section(section, cfg.get(section) or {})
    cfg["env"] = _validate_env_section(task, cfg.get("env") or {})
    if isinstance(cfg.get("eval"), dict):
        cfg["eval"]["env"] = _validate_env_section(task, cfg["eval"].get("env") or {}, "eval.env.")
    plain = {k: v for k, v in cfg.items() if k not in CLASS_SECTIONS + ("env",)}
    _validate_plain(plain, {k: v for k, v in defaults.items() if k not in CLASS_SECTIONS + ("env",)})
    cfg.update(plain)
    check_combinations(cfg)
    return cfg


def dump_config(cfg: dict, path: Path) -> None:
    """Write the resolved config as YAML (atomically), so a run can be reproduced and resumed from it."""
    from refpo_warp.utils.atomic_files import write_text

    write_text(path, yaml.safe_dump(cfg, sort_keys=False))
