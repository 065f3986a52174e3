"""ReFPO inside mjlab: ReFPO variants of mjlab's tasks (``<task id>-ReFPO``), trained and played by mjlab's own
``train`` / ``play`` scripts.

mjlab imports this package through the ``mjlab.tasks`` entry point (``pyproject.toml``), which registers the variants
(``tasks.py``). A variant is the task's env and runner config with the actor switched to a flow actor of the task's
sizes and the algorithm to ReFPO with its own settings (``cfg.py``), run by the task's runner class with ReFPO's
statistics logged as statistics (``runner.py``). ``docs/mjlab.md`` has the install line and results.
"""

from refpo_warp.integrations.mjlab.cfg import FlowActorCfg, ReFPOAlgorithmCfg, refpo_runner_cfg
from refpo_warp.integrations.mjlab.runner import refpo_runner_cls
from refpo_warp.integrations.mjlab.tasks import REFPO_SUFFIX, VARIANT_BASES, register_refpo_variant, register_variants

__all__ = [
    "REFPO_SUFFIX",
    "VARIANT_BASES",
    "FlowActorCfg",
    "ReFPOAlgorithmCfg",
    "refpo_runner_cfg",
    "refpo_runner_cls",
    "register_refpo_variant",
    "register_variants",
]

register_variants()
