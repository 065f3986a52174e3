"""The Reflow coefficient lambda over training: fixed (the paper's), or adapted to the one-step consistency.

``adaptive`` (ours; the paper's open direction "adaptive coefficient schedules may further improve robustness"): after
each rollout, before the update, the one-step ratio r = E|T(a_1) - T(a_N)|^2 / Var_eps[T(a_N)] is measured on states
of the rollout (``refpo_warp.models.flow_diagnostics.one_step_consistency``); lambda is multiplied by 1.5 when
r > 2 * target and divided by 1.5 when r < target / 2, kept within [lambda_min, lambda_max]. It starts at
``reflow_coef``. The band and the factor are those of rsl_rl's adaptive learning-rate schedule (there driven by the
KL divergence): lambda moves only when the one-step error is far from the target, by a bounded step per update.
"""

from __future__ import annotations

from enum import Enum

from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.option_rules import ListOf, Real
from refpo_warp.utils.options import choices


class ScheduleMode(str, Enum):
    FIXED = "fixed"  # the paper's
    ADAPTIVE = "adaptive"  # to the one-step ratio (ours)


STEP = 1.5  # factor per update
BAND = 2.0  # no change while target / BAND <= r <= target * BAND


def coefficient_range(key: str, value) -> list[float]:
    """The rule of ``reflow_coef_range``: [min, max] with 0 <= min <= max."""
    low, high = ListOf(Real(0, 1e6), min_len=2, max_len=2).check(key, value)
    if low > high:
        raise ConfigError(f"{key}={value} is invalid: the minimum must not exceed the maximum")
    return [low, high]


class ReflowSchedule:
    """How lambda moves from one update to the next, given the one-step ratio of the coming update's rollout."""

    def __init__(
        self, mode: str = "fixed", target: float = 0.25, coef_range: tuple[float, float] = (0.01, 0.2)
    ) -> None:
        if mode not in choices(ScheduleMode):
            raise ValueError(f"reflow_schedule must be one of {choices(ScheduleMode)}, got '{mode}'")
        self.mode, self.target = mode, float(target)
        self.low, self.high = float(coef_range[0]), float(coef_range[1])

    def start(self, coef: float) -> float:
        """The first update's lambda: ``reflow_coef``, within the range when adaptive."""
        return min(max(coef, self.low), self.high) if self.mode == "adaptive" else coef

    def step(self, coef: float, one_step_ratio: float) -> float:
        """The lambda of the coming update (unchanged when fixed)."""
        if self.mode == "adaptive":
            if one_step_ratio > self.target * BAND:
                return min(coef * STEP, self.high)
            if one_step_ratio < self.target / BAND:
                return max(coef / STEP, self.low)
        return coef
