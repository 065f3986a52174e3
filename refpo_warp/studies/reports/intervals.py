"""Confidence intervals over runs, as RL evaluation recommends (Agarwal et al. 2021, the ``rliable`` library): scores
as a (runs x tasks) matrix per method, point estimates with 95 % stratified-bootstrap intervals (runs resampled
within each task), the interquartile mean (IQM) beside the mean, and the probability that one method's run beats
another's on a task."""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np

REPS = 2000  # bootstrap resamples: the intervals' ends move by well under 1 % between seeds at this count


@dataclass(frozen=True)
class Estimate:
    point: float
    low: float
    high: float
    fewest_runs: int | None = None  # the runs (seeds) it rests on; a probability of improvement: its smaller side

    @property
    def compared(self) -> bool:
        """False where it rests on one run (a mean of one seed, or one run on a side of a probability of
        improvement): the bootstrap has nothing to resample there, so its interval is the point itself."""
        return self.fewest_runs is None or self.fewest_runs > 1

    def text(self, digits: int = 0) -> str:
        """``point [low, high]`` with ``digits`` decimals: how every page writes an estimate and its interval (the
        point alone, so marked, where one run on a side leaves no interval)."""
        if not self.compared:
            return f"{self.point:.{digits}f} (one seed, no interval)"
        return f"{self.point:.{digits}f} [{self.low:.{digits}f}, {self.high:.{digits}f}]"

    @property
    def side(self) -> int:
        """For a probability of improvement: 1 where its interval lies above one half (x's runs beat y's), -1 below,
        0 where it holds one half or rests on one run a side (the runs do not tell the methods apart)."""
        if not self.compared:
            return 0
        return 1 if self.low > 0.5 else -1 if self.high < 0.5 else 0

    @property
    def separates(self) -> bool:
        return self.side != 0

    def overlaps_or_above(self, other: Estimate) -> bool:
        """This interval reaches ``other``'s (they overlap), or lies above it."""
        return self.high >= other.low


@contextlib.contextmanager
def _seeded(seed: int) -> Iterator[None]:
    """rliable's stratified bootstrap draws its resamples from NumPy's global generator
    (``StratifiedBootstrap.update_indices``), so the same draws come from seeding it here; the caller's stream is
    restored afterwards."""
    state = np.random.get_state()
    np.random.seed(seed)
    try:
        yield
    finally:
        np.random.set_state(state)


def _percentile_interval(estimates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """arch's ``conf_int(method="percentile", size=0.95)`` over (reps x statistics) bootstrap estimates (its
    percentiles as it computes them: 100 alpha is not exactly 2.5)."""
    alpha = (1.0 - 0.95) / 2
    bounds = [np.percentile(estimates[:, i], [100 * alpha, 100 * (1.0 - alpha)]) for i in range(estimates.shape[1])]
    return np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])


def _check(scores: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    out = {}
    for name, value in scores.items():
        matrix = np.asarray(value, dtype=float)
        if matrix.ndim != 2 or min(matrix.shape) < 1 or not np.isfinite(matrix).all():
            raise ValueError(f"scores of '{name}' must be a finite (runs x tasks) matrix, got shape {matrix.shape}")
        out[name] = matrix
    return out


def aggregate(scores: dict[str, np.ndarray], seed: int = 0, reps: int = REPS) -> dict[str, dict[str, Estimate]]:
    """Per method: ``{"mean": Estimate, "iqm": Estimate}`` over all (run, task) scores, stratified bootstrap 95 %.

    rliable's ``get_interval_estimates`` (percentile method) resample by resample, computed on every resample at once:
    the same draws in the same order (one ``np.random.choice`` of the runs per task for each resample, methods in
    ``scores``' order) and the same floats (tests/studies/test_intervals.py checks both against rliable)."""
    scores = _check(scores)
    out = {}
    with _seeded(seed):
        for name, matrix in scores.items():
            runs, tasks = matrix.shape
            rows = np.random.choice(runs, (reps, runs, tasks), replace=True)
            resampled = matrix[rows, np.arange(tasks)]  # (reps, runs, tasks): runs resampled within each task
            means = resampled.mean(axis=1).mean(axis=1)
            flat = resampled.reshape(reps, -1)
            low, high = _iqm_slice(flat.shape[1])
            iqms = np.partition(flat, (low, high - 1), axis=1)[:, low:high].mean(axis=1)
            lows, highs = _percentile_interval(np.stack([means, iqms], axis=1))
            points = (float(np.mean(np.mean(matrix, axis=0))), interquartile_mean(matrix))
            out[name] = {
                stat: Estimate(points[i], float(lows[i]), float(highs[i])) for i, stat in enumerate(("mean", "iqm"))
            }
    return out


def mean_estimate(values) -> Estimate:
    """The mean of one task's runs with its 95 % bootstrap interval: ``aggregate`` of a (runs x 1) matrix (each score
    set bootstrapped once: pages ask for the same cell many times)."""
    return _mean_estimate(tuple(float(v) for v in values))


@functools.cache
def _mean_estimate(values: tuple[float, ...]) -> Estimate:
    return replace(aggregate({"m": np.asarray(values)[:, None]})["m"]["mean"], fewest_runs=len(values))


def _iqm_slice(size: int) -> tuple[int, int]:
    """The sorted positions the IQM averages: SciPy's 25 % ``trim_mean`` cut."""
    low = int(0.25 * size)
    return low, size - low


def interquartile_mean(scores: np.ndarray) -> float:
    """rliable's ``metrics.aggregate_iqm`` (SciPy's 25 % ``trim_mean`` over all scores), the same partition and so
    the same float, without SciPy's array-API dispatch."""
    flat = np.ravel(scores)
    low, high = _iqm_slice(flat.size)
    return float(np.mean(np.partition(flat, (low, high - 1))[low:high]))


def probability_of_improvement(x: np.ndarray, y: np.ndarray) -> float:
    """rliable's ``metrics.probability_of_improvement`` without SciPy's Mann-Whitney test (its U statistic is the
    count of pairs with x > y plus half the ties, the same float)."""
    return float(_improvements(x[None], y[None])[0])


def _improvements(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``probability_of_improvement`` of each resample: x (reps x runs x tasks), y (reps x runs' x tasks). Identical
    columns give one half, as rliable's shortcut does (the count gives it exactly too)."""
    greater = (x[:, :, None, :] > y[:, None, :, :]).sum(axis=(1, 2)).astype(float)
    ties = (x[:, :, None, :] == y[:, None, :, :]).sum(axis=(1, 2)).astype(float)
    per_task = (greater + 0.5 * ties) / (x.shape[1] * y.shape[1])
    return per_task.mean(axis=1)


def improvement(x: np.ndarray, y: np.ndarray, seed: int = 0, reps: int = REPS) -> Estimate:
    """P(a run of x beats a run of y on the same task), averaged over tasks (ties count one half), with its
    stratified bootstrap 95 % interval: rliable's (``StratifiedIndependentBootstrap``: x's and y's runs resampled
    independently, x's draw first in each resample), computed on every resample at once."""
    pair = _check({"x": x, "y": y})
    x, y = pair["x"], pair["y"]
    if x.shape[1] != y.shape[1]:
        raise ValueError("x and y must have the same tasks (columns)")
    with _seeded(seed):
        if len(x) == len(y):  # one call draws what the resamples' x-then-y calls draw, in that order
            both = np.random.choice(len(x), (reps, 2 * len(x), x.shape[1]))
            x_rows, y_rows = both[:, : len(x)], both[:, len(x) :]
        else:
            draws = [(np.random.choice(len(x), x.shape), np.random.choice(len(y), y.shape)) for _ in range(reps)]
            x_rows, y_rows = np.stack([d[0] for d in draws]), np.stack([d[1] for d in draws])
    columns = np.arange(x.shape[1])
    xs, ys = x[x_rows, columns], y[y_rows, columns]
    low, high = _percentile_interval(_improvements(xs, ys)[:, None])
    return Estimate(probability_of_improvement(x, y), float(low[0]), float(high[0]), min(len(x), len(y)))


def improvement_of(x_values, y_values) -> Estimate:
    """``improvement`` on one task: P(a run of x beats a run of y) from each side's list of run scores (each pair of
    score sets bootstrapped once: pages ask for the same comparison many times)."""
    return _improvement_of(tuple(float(v) for v in x_values), tuple(float(v) for v in y_values))


@functools.cache
def _improvement_of(x: tuple[float, ...], y: tuple[float, ...]) -> Estimate:
    return improvement(np.asarray(x)[:, None], np.asarray(y)[:, None])
