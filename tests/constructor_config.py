"""What the constructors of a run receive: a resolved config with every option a class or env cfg sets by default
filled in (the saved ``config.yaml`` holds only what the layers set). For tests that compare a profile with a paper's
table."""

from refpo_warp.config.classes import CLASS_SECTIONS, POSITIONAL, class_defaults


def effective_config(cfg: dict) -> dict:
    """``cfg`` with the constructors' and the env cfg's defaults filled in."""
    from refpo_warp.envs.registry import get_task

    out = dict(cfg)
    for section in CLASS_SECTIONS:
        found = class_defaults(cfg[section]["class_name"])
        defaults = {n: d for n, (d, _) in found.items() if n not in POSITIONAL[section]}
        out[section] = {**defaults, **cfg[section]}
    spec = get_task(cfg["task"])
    out["env"] = {**spec.cfg_class.defaults(), **spec.cfg_overrides, **cfg["env"]}
    return out
