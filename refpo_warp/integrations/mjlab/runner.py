"""The runner of a ReFPO variant: the task's own runner class (mjlab's ``MjlabOnPolicyRunner``, or a subclass such
as ``VelocityOnPolicyRunner`` with its ONNX export on save) with ReFPO's statistics logged as statistics
(``refpo_warp.integrations.statistics_logger``).

Subclassing the task's class keeps everything it adds (checkpointed env state, ONNX export and metadata, W&B
uploads); the flow actor's ONNX export takes the observation only (``refpo_warp.models.flow_export``).
"""

from __future__ import annotations

import functools

from mjlab.rl import MjlabOnPolicyRunner

from refpo_warp.integrations.statistics_logger import StatisticsRunnerMixin


@functools.cache
def refpo_runner_cls(base: type | None = None) -> type:
    """The ReFPO runner class for a task whose runner class is ``base`` (None: mjlab's default,
    ``MjlabOnPolicyRunner``); one class per base, named ``ReFPO<base>``."""
    base = base or MjlabOnPolicyRunner
    if not (isinstance(base, type) and issubclass(base, MjlabOnPolicyRunner)):
        raise TypeError(f"runner_cls {base!r} is not mjlab's MjlabOnPolicyRunner (valid: it or a subclass of it)")
    return type(f"ReFPO{base.__name__}", (StatisticsRunnerMixin, base), {"__module__": __name__})
