"""Where a run's option got its value:
``refpo train task=gridworld algo=fpo --explain algorithm.reflow_coef``.

For each key: the resolved value, the layer that set it (a file and section, the command line, a constructor's or an
env cfg's default, or the task id) with the comment that file gives the value on its line, what the earlier layers had
set, and what the option means: the doc of its field (``refpo_warp/utils/options.py``; a class's, the env cfg's,
the video options' or the run options'). A section (``--explain algorithm``) lists every option of it, the ones only a
constructor sets included.
"""

from __future__ import annotations

import inspect
from typing import Any

from refpo_warp.config.classes import CLASS_SECTIONS, POSITIONAL, class_defaults, resolve_class
from refpo_warp.config.dotted import LEAF_KEYS, flatten
from refpo_warp.config.resolve import Resolution
from refpo_warp.envs.task_spec import TaskSpec
from refpo_warp.utils.errors import unknown
from refpo_warp.utils.options import docs_for
from refpo_warp.utils.paths import shown


def _class_default(cfg: dict, section: str, name: str) -> tuple[Any, str] | None:
    found = class_defaults(cfg[section]["class_name"]).get(name)
    if found is None or name in POSITIONAL[section]:
        return None
    default, owner = found
    where = inspect.getsourcefile(owner)
    return default, f"the default of {owner.__module__}.{owner.__qualname__}" + (f" ({shown(where)})" if where else "")


def _env_default(spec: TaskSpec, name: str) -> tuple[Any, str] | None:
    if name in spec.cfg_overrides:
        return spec.cfg_overrides[name], f"the task id {spec.task_id} (its TaskSpec)"
    defaults = spec.cfg_class.defaults()
    if name not in defaults:
        return None
    return defaults[name], f"the default of {spec.cfg_class.__module__}.{spec.cfg_class.__qualname__}"


def _video_default(name: str) -> tuple[Any, str] | None:
    from refpo_warp.render.options import VideoOptions

    defaults = {k: f.default for k, f in VideoOptions.__dataclass_fields__.items()}
    return (defaults[name], "the default of refpo_warp.render.options.VideoOptions") if name in defaults else None


def _fallback(res: Resolution, key: str) -> tuple[Any, str] | None:
    """The value a key has when no layer sets it (a constructor's, an env cfg's or the video options' default)."""
    cfg = res.cfg
    section, _, name = key.partition(".")
    if section == "video" and name and "." not in name:
        return _video_default(name)
    if section in CLASS_SECTIONS and name and "." not in name:
        return _class_default(cfg, section, name)
    if section == "env" and name and "." not in name:
        return _env_default(res.task, name)
    if key.startswith("eval.env.") and key.count(".") == 2:
        return _env_default(res.task, key.rsplit(".", 1)[1])
    return None


def all_keys(res: Resolution) -> list[str]:
    """Every option of a resolved config, the ones set only by a constructor or env cfg default included."""
    cfg = res.cfg
    keys = list(flatten(cfg))
    for section in CLASS_SECTIONS:
        keys += [f"{section}.{n}" for n in class_defaults(cfg[section]["class_name"]) if n not in POSITIONAL[section]]
    keys += [f"env.{n}" for n in res.task.cfg_class.defaults()]
    from refpo_warp.render.options import VideoOptions

    keys += [f"video.{n}" for n in VideoOptions.__dataclass_fields__]
    return list(dict.fromkeys(k for k in keys if not k.endswith(".") and k not in ("env", "eval.env", "video")))


def _meaning(res: Resolution, key: str) -> str:
    """The one-line doc of an option's field, or ``""``."""
    cfg = res.cfg
    from refpo_warp.config.run_options import RUN_DOCS

    section, _, name = key.partition(".")
    if key.startswith("eval.env."):
        section, name = "env", key[len("eval.env.") :]
    if section in CLASS_SECTIONS and name and "." not in name:
        return docs_for(resolve_class(cfg[section]["class_name"])).get(name, "")
    if section == "env" and name:
        return docs_for(res.task.cfg_class).get(name, "")
    if section == "video" and name:
        from refpo_warp.render.options import VideoOptions

        return docs_for(VideoOptions).get(name, "")
    return RUN_DOCS.get(key, "")


def _value(cfg: dict, key: str) -> tuple[bool, Any]:
    node: Any = cfg
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return False, None
        node = node[part]
    return True, node


def explain_key(res: Resolution, key: str) -> list[str]:
    """The lines for one option (see the module docstring)."""
    cfg = res.cfg
    found, value = _value(cfg, key)
    history = list(res.sources.get(key, []))
    fallback = _fallback(res, key)
    if fallback is not None:
        history.insert(0, (fallback[1], fallback[0]))
    if not found and fallback is not None:
        value = fallback[0]
    lines = [f"{key} = {value!r}"]
    if history:
        source, _ = history[-1]
        lines.append(f"  set by  {source}")
        if key in res.notes:
            lines.append(f"  why     {res.notes[key]}")
        for earlier, old in reversed(history[:-1]):
            lines.append(f"  over    {old!r} from {earlier}")
    meaning = _meaning(res, key)
    if meaning:
        lines.append(f"  means   {meaning}")
    return lines


def explain(res: Resolution, keys: list[str] | None = None) -> str:
    """The lines for each of ``keys`` (a section stands for all of its options; None: every option)."""
    everything = all_keys(res)
    chosen = []
    for key in keys or everything:
        below = [k for k in everything if k.startswith(f"{key}.")]
        if key in LEAF_KEYS or key in everything:
            chosen.append(key)
        elif below:
            chosen += below
        else:
            raise unknown("config key to explain", key, everything)
    title = f"Config of task={res.cfg['task']} algo={res.cfg['algo']}, later layers win:"
    layer_list = "\n".join(f"  {i + 1}. {layer.source}" for i, layer in enumerate(res.layers))
    return "\n".join([title, layer_list, ""] + [line for key in chosen for line in explain_key(res, key)])
