"""Confidence intervals over runs (rliable): the point estimates by hand, intervals that contain them and shrink
with more runs, and the probability of improvement of separated and of identical methods."""

import numpy as np
import pytest

from refpo_warp.studies.reports.intervals import aggregate, improvement, improvement_of, mean_estimate


def test_point_estimates_by_hand_and_intervals_around_them():
    # 2 tasks x 4 runs: IQM drops the lowest and the highest quarter of the 8 scores (1, 2 and 7, 8).
    scores = np.array([[1.0, 5.0], [2.0, 6.0], [3.0, 7.0], [4.0, 8.0]])
    est = aggregate({"m": scores})["m"]
    assert est["mean"].point == pytest.approx(4.5) and est["iqm"].point == pytest.approx(4.5)
    skewed = np.array([[0.0, 1.0], [1.0, 1.0], [1.0, 1.0], [1.0, 100.0]])
    est = aggregate({"s": skewed})["s"]
    assert est["mean"].point == pytest.approx(106 / 8) and est["iqm"].point == pytest.approx(1.0)
    for stat in est.values():
        assert stat.low <= stat.point <= stat.high
    # Stratified: runs are resampled within a task, so a constant task adds no width; more runs, a narrower interval.
    rng = np.random.default_rng(0)
    few, many = rng.normal(1.0, 0.2, (3, 2)), rng.normal(1.0, 0.2, (30, 2))
    width = {n: (e["mean"].high - e["mean"].low) for n, e in aggregate({"few": few, "many": many}).items()}
    assert width["many"] < width["few"]


def test_probability_of_improvement():
    low, high = np.full((3, 2), 1.0), np.full((3, 2), 2.0)
    assert improvement(high, low).point == pytest.approx(1.0)
    assert improvement(low, high).point == pytest.approx(0.0)
    same = improvement(low, low)  # every pair ties: one half
    assert same.point == pytest.approx(0.5) and same.low == pytest.approx(0.5) and same.high == pytest.approx(0.5)
    # One task each way: x wins task 0 in all 9 pairs, loses task 1 in all: 0.5 on average.
    x, y = np.array([[2.0, 0.0]] * 3), np.array([[1.0, 1.0]] * 3)
    assert improvement(x, y).point == pytest.approx(0.5)


def test_one_run_on_a_side_compares_nothing():
    """One run on a side leaves the bootstrap nothing to resample: the interval is the point, so even a point of 1
    separates nothing and the text says there is no interval; two runs a side separate again."""
    one = improvement(np.array([[2.0, 3.0]]), np.array([[1.0, 1.0], [0.0, 0.0]]))
    assert (one.point, one.low, one.high) == (1.0, 1.0, 1.0)
    assert not one.compared and not one.separates and one.side == 0
    assert one.text(2) == "1.00 (one seed, no interval)"
    two = improvement(np.array([[2.0, 3.0], [4.0, 5.0]]), np.array([[1.0, 1.0], [0.0, 0.0]]))
    assert two.compared and two.side == 1 and two.text(2) == "1.00 [1.00, 1.00]"
    assert improvement(np.zeros((2, 1)), np.ones((3, 1))).side == -1


def test_a_mean_of_one_seed_has_no_interval_and_of_more_the_bootstraps():
    assert mean_estimate([631.0]).text() == "631 (one seed, no interval)"
    two = mean_estimate([600.0, 700.0])
    assert two.compared and (two.point, two.low, two.high) == (650.0, 600.0, 700.0)  # two runs: ends at the runs
    three, expected = mean_estimate((1.0, 2.0, 6.0)), aggregate({"m": np.array([[1.0], [2.0], [6.0]])})["m"]["mean"]
    assert (three.point, three.low, three.high, three.fewest_runs) == (expected.point, expected.low, expected.high, 3)


def test_one_tasks_improvement_from_score_lists_is_the_matrix_ones():
    x, y = [3.0, 0.0, 4.0], (1.0, 5.0)  # x wins 2 of the 6 pairs: 3 and 4 beat 1, nothing beats 5
    got, expected = improvement_of(x, y), improvement(np.array([[3.0], [0.0], [4.0]]), np.array([[1.0], [5.0]]))
    assert got == expected and got.point == pytest.approx(2 / 6) and got.fewest_runs == 2


def test_intervals_are_reproducible_and_leave_numpys_generator_alone():
    scores = np.array([[765.0], [765.0], [365.0], [332.0], [720.0], [526.0]])
    np.random.seed(7)
    expected_next = np.random.random()
    np.random.seed(7)
    first = aggregate({"m": scores}, seed=3)["m"]["mean"]
    assert np.random.random() == expected_next  # the caller's global stream is where it was
    assert aggregate({"m": scores}, seed=3)["m"]["mean"] == first  # same seed, same interval
    assert aggregate({"m": scores}, seed=4)["m"]["mean"] != first


def test_probability_of_improvement_is_rliables_exactly():
    """The NumPy statistic is rliable's (SciPy's Mann-Whitney U over n x m), float for float, ties included."""
    from rliable import metrics

    from refpo_warp.studies.reports.intervals import probability_of_improvement

    rng = np.random.default_rng(0)
    for _ in range(200):
        runs_x, runs_y, tasks = rng.integers(1, 7, size=3)
        x = rng.integers(0, 4, (runs_x, tasks % 3 + 1)).astype(float)
        y = rng.integers(0, 4, (runs_y, tasks % 3 + 1)).astype(float)
        assert probability_of_improvement(x, y) == metrics.probability_of_improvement(x, y)


def _rliables(scores: dict, func, seed: int) -> tuple[dict, dict]:
    """rliable's own ``get_interval_estimates`` (arch's bootstrap loop) under the same seeding as ours."""
    import warnings

    from rliable import library

    state = np.random.get_state()
    np.random.seed(seed)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=FutureWarning)
            return library.get_interval_estimates(scores, func, reps=300, random_state=np.random.RandomState(seed))
    finally:
        np.random.set_state(state)


def test_intervals_are_rliables_float_for_float():
    """The vectorised bootstrap draws what rliable's loop draws and computes the same floats: every estimate and
    interval end equal to rliable's on random matrices of 1-15 runs x 1-3 tasks, ties and methods of unequal runs."""
    from refpo_warp.studies.reports.intervals import interquartile_mean, probability_of_improvement

    def both(matrix):
        return np.array([np.mean(np.mean(matrix, axis=0)), interquartile_mean(matrix)])

    rng = np.random.default_rng(1)
    for case in range(40):
        tasks = int(rng.integers(1, 4))
        scores = {
            name: (rng.normal(500, 200, (int(rng.integers(1, 16)), tasks)) if case % 2 else
                   rng.integers(0, 5, (int(rng.integers(1, 16)), tasks)).astype(float))
            for name in ("a", "b", "c")
        }  # fmt: skip
        points, intervals = _rliables(scores, both, seed=case)
        ours = aggregate(scores, seed=case, reps=300)
        for name in scores:
            for i, stat in enumerate(("mean", "iqm")):
                expected = (points[name][i], intervals[name][0, i], intervals[name][1, i])
                assert (ours[name][stat].point, ours[name][stat].low, ours[name][stat].high) == expected, (case, name)
        x = scores["a"]
        y = scores["b"] if case % 3 else np.round(rng.normal(2, 1, x.shape))  # runs unequal, or equal (one draw)
        points, intervals = _rliables({"xy": (x, y)}, probability_of_improvement, seed=case)
        est = improvement(x, y, seed=case, reps=300)
        assert (est.point, est.low, est.high) == (points["xy"], *np.ravel(intervals["xy"])), case
