"""Confidence intervals over runs, as RL evaluation recommends (Agarwal et al. 2021, the ``rliable`` library): scores
as a (runs x tasks) matrix per method, point estimates with 95 % stratified-bootstrap intervals (runs resampled
within each task), the interquartile mean (IQM) beside the mean, and the probability that one method's run beats
another's on a task."""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from refpo_warp.utils.errors import ConfigError

REPS = 2000  # bootstrap resamples: the intervals' ends move by well under 1 % between seeds at this count


@dataclass(frozen=True)
class Estimate:
    point: float
    low: float
    high: float

    def text(self, digits: int = 0) -> str:
        """``point [low, high]`` with ``digits`` decimals: how every page writes an estimate and its interval."""
        return f"{self.point:.{digits}f} [{self.low:.{digits}f}, {self.high:.{digits}f}]"

    @property
    def separates(self) -> bool:
        """For a probability of improvement: its interval leaves out one half, so the runs tell the methods apart."""
        return self.low > 0.5 or self.high < 0.5

    def overlaps_or_above(self, other: Estimate) -> bool:
        """This interval reaches ``other``'s (they overlap), or lies above it."""
        return self.high >= other.low


def _rliable():
    try:
        from rliable import library, metrics
    except ImportError as err:
        raise ConfigError('Confidence intervals need rliable: pip install "refpo-warp[tune]"') from err
    return library, metrics


@contextlib.contextmanager
def _quiet(seed: int) -> Iterator[None]:
    """Reproducible intervals: rliable's stratified bootstrap draws its resamples from NumPy's global generator
    (``StratifiedBootstrap.update_indices``), not from the seeded ``RandomState`` it hands arch (which arch 7 warns
    is deprecated), so the global generator is seeded here and restored afterwards."""
    state = np.random.get_state()
    np.random.seed(seed)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=FutureWarning, module="arch")
            yield
    finally:
        np.random.set_state(state)


def _check(scores: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    out = {}
    for name, value in scores.items():
        matrix = np.asarray(value, dtype=float)
        if matrix.ndim != 2 or min(matrix.shape) < 1 or not np.isfinite(matrix).all():
            raise ValueError(f"scores of '{name}' must be a finite (runs x tasks) matrix, got shape {matrix.shape}")
        out[name] = matrix
    return out


def aggregate(scores: dict[str, np.ndarray], seed: int = 0, reps: int = REPS) -> dict[str, dict[str, Estimate]]:
    """Per method: ``{"mean": Estimate, "iqm": Estimate}`` over all (run, task) scores, stratified bootstrap 95 %."""
    library, _ = _rliable()
    scores = _check(scores)

    def both(matrix: np.ndarray) -> np.ndarray:
        return np.array([np.mean(np.mean(matrix, axis=0)), interquartile_mean(matrix)])

    with _quiet(seed):
        points, intervals = library.get_interval_estimates(
            scores, both, reps=reps, random_state=np.random.RandomState(seed)
        )
    return {
        name: {
            stat: Estimate(float(points[name][i]), float(intervals[name][0, i]), float(intervals[name][1, i]))
            for i, stat in enumerate(("mean", "iqm"))
        }
        for name in scores
    }


def interquartile_mean(scores: np.ndarray) -> float:
    """rliable's ``metrics.aggregate_iqm`` (SciPy's 25 % ``trim_mean`` over all scores), the same partition and so
    the same float, without SciPy's array-API dispatch, which took most of an interval's time."""
    flat = np.ravel(scores)
    low = int(0.25 * flat.size)
    high = flat.size - low
    return float(np.mean(np.partition(flat, (low, high - 1))[low:high]))


def probability_of_improvement(x: np.ndarray, y: np.ndarray) -> float:
    """rliable's ``metrics.probability_of_improvement`` without SciPy's Mann-Whitney test (its U statistic is the
    count of pairs with x > y plus half the ties, the same float): each bootstrap resample calls it once, and the
    test made an interval take seconds."""
    per_task = []
    for task in range(x.shape[1]):
        a, b = x[:, task], y[:, task]
        if np.array_equal(a, b):
            per_task.append(0.5)
            continue
        u = float(np.greater.outer(a, b).sum()) + 0.5 * float(np.equal.outer(a, b).sum())
        per_task.append(u / (a.size * b.size))
    return float(np.mean(per_task))


def improvement(x: np.ndarray, y: np.ndarray, seed: int = 0, reps: int = REPS) -> Estimate:
    """P(a run of x beats a run of y on the same task), averaged over tasks (ties count one half), with its
    stratified bootstrap 95 % interval."""
    library, _ = _rliable()
    pair = _check({"x": x, "y": y})
    if pair["x"].shape[1] != pair["y"].shape[1]:
        raise ValueError("x and y must have the same tasks (columns)")
    with _quiet(seed):
        points, intervals = library.get_interval_estimates(
            {"xy": (pair["x"], pair["y"])},
            probability_of_improvement,
            reps=reps,
            random_state=np.random.RandomState(seed),
        )
    low, high = np.asarray(intervals["xy"], dtype=float).ravel()
    return Estimate(float(np.asarray(points["xy"]).ravel()[0]), float(low), float(high))
