"""The learning checks' statistics and bound rule against hand-worked numbers (quick: nothing is trained)."""

import numpy as np
import pytest
from checks import CHECKS, Bound, linear_trend, one_step_holds, return_gains  # tests/learning/checks.py
from table import BoundStanding  # tests/learning/table.py


def test_linear_trend_against_hand_worked_series():
    y = np.array([1.1, 1.0, 1.3, 1.2])
    t, rise = linear_trend(y)
    # by hand: slope 0.06, intercept 1.06, residuals (0.04, -0.12, 0.12, -0.04), SSE 0.032, Sxx 5
    assert np.isclose(rise, 0.06 * 3 / 1.06)
    assert np.isclose(t, 0.06 / np.sqrt(0.032 / 2 / 5))


def test_gain_is_the_final_over_the_initial_return():
    record = {"initial": {"N=10": {"return_mean": 200.0}}, "final": {"N=10": {"return_mean": 500.0}}}
    assert return_gains("N=10")(record) == {"gain_N=10": 2.5}


def test_one_step_statistics_hand_worked():
    def record(n10, n1, initial_n10=20.0):
        return {
            "initial": {"N=10": {"return_mean": initial_n10}},
            "final": {"N=10": {"return_mean": n10}, "N=1": {"return_mean": n1}},
        }

    assert one_step_holds(record(700.0, 665.0)) == {"rise_N=10": 680.0, "ratio_N=1/N=10": 0.95}
    assert one_step_holds(record(0.0, 3.0, initial_n10=1.5)) == {"rise_N=10": -1.5, "ratio_N=1/N=10": 0.0}


def test_a_claim_bound_holds_in_every_learning_run_and_may_hold_in_the_null_control():
    learning, null = [(1, 1, 1.05), (1, 2, 0.93), (2, 1, 0.97)], [(1, 0.13), (2, 1.4)]
    assert not BoundStanding(Bound("ratio", ">=", 0.9, claim=True), learning, null).problems()
    assert (
        "claim fails in a learning run (0.93)"
        in BoundStanding(Bound("ratio", ">=", 0.95, claim=True), learning, null).problems()[0]
    )
    # the same value as a bound of the first kind breaks the rule: the null control's best (1.4) is beyond it
    assert BoundStanding(Bound("ratio", ">=", 0.9), learning, null).problems()


def test_bound_rule_hand_worked():
    # learning worst 1.6, null best 1.1: halfway 1.35; a bound must be above 1.1 and at most 1.35
    learning, null = [(1, 1, 2.0), (1, 2, 1.6), (2, 1, 1.8)], [(1, 1.0), (2, 1.1)]
    assert not BoundStanding(Bound("g", ">=", 1.3), learning, null).problems()
    assert "halfway (1.35)" in BoundStanding(Bound("g", ">=", 1.4), learning, null).problems()[0]
    assert "null control's best (1.1)" in BoundStanding(Bound("g", ">=", 1.1), learning, null).problems()[0]
    # lower is learning: null best 0.9, learning worst 0.3 -> halfway 0.6; bound in [0.6, 0.9)
    low = BoundStanding(Bound("r", "<=", 0.6), [(1, 1, 0.1), (1, 2, 0.3)], [(1, 0.95), (2, 0.9)])
    assert not low.problems() and low.halfway == pytest.approx(0.6)
    assert BoundStanding(Bound("r", "<=", 0.5), low.learning, low.null).problems()


def test_every_check_names_statistics_its_function_gives():
    record = {"initial": {}, "final": {}, "rows": [{"episode_length_mean": v} for v in (1.0, 2.0, 2.5, 4.0)]}
    for check in CHECKS.values():
        if check.name.startswith("humanoid"):
            assert {b.statistic for b in check.bounds} <= set(check.statistics(record))
