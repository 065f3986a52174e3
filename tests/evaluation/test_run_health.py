"""Run health: FPO++'s cliff rule on the training reward, and peak, final and drop of each periodic evaluation
curve, against hand-worked series."""

import pytest

from refpo_warp.evaluation.evaluate_policy import curve_key, setting_name
from refpo_warp.evaluation.run_health import reward_cliff, run_health, setting_of
from refpo_warp.utils.console import health_line


def rows(**curves):
    n = max(len(v) for v in curves.values())
    out = [{"iteration": it} for it in range(n)]
    for key, values in curves.items():
        for it, value in enumerate(values):
            if value is not None:
                out[it][key] = value
    return out


def test_curves_peak_final_and_drop_hand_worked():
    curves = run_health(
        rows(
            **{"eval/return_N10": [None, 400.0, None, 950.0, 900.0], "eval/return_N1": [None, 700.0, None, 300.0, 75.0]}
        )
    )["curves"]
    assert curves["N=10"] == {
        "peak": 950.0,
        "peak_iteration": 3,
        "final": 900.0,
        "final_iteration": 4,
        "drop": pytest.approx(50 / 950),
    }
    assert curves["N=1"]["peak_iteration"] == 1 and curves["N=1"]["drop"] == pytest.approx(625 / 700)
    negative = run_health(rows(**{"eval/return": [-10.0, -20.0]}))["curves"]["mean_action"]  # peak -10: twice as bad
    assert negative["drop"] == pytest.approx(1.0)


def test_a_run_under_150_iterations_or_a_low_peak_is_insufficient_data():
    short = reward_cliff([100.0] * 149)
    assert short["status"] == "insufficient_data" and short["message"] == "needs 150 iterations, has 149"
    low = reward_cliff([9.0] * 200)
    assert low["status"] == "insufficient_data" and low["peak"] == 9.0  # FPO++'s minimum peak: 10


def test_the_cliff_is_a_50_iteration_mean_30_percent_under_the_peak_100_iterations_after_it():
    # peak 100 at iteration 10; from iteration 110 on the reward is 70: the window [110, 160) has mean 70, a 30 % drop
    rewards = [50.0] * 10 + [100.0] + [90.0] * 99 + [70.0] * 50
    cliff = reward_cliff(rewards)
    assert (cliff["status"], cliff["peak_iteration"], cliff["cliff_iteration"]) == ("cliff_detected", 10, 110)
    assert cliff["drop"] == pytest.approx(0.3)
    # 70.1: a 29.9 % drop; and an earlier fall (within 100 iterations of the peak) is not looked at
    assert reward_cliff([50.0] * 10 + [100.0] + [90.0] * 99 + [70.1] * 50)["status"] == "healthy"
    assert reward_cliff([100.0] + [0.0] * 99 + [90.0] * 50)["status"] == "healthy"
    # the first window that drops far enough is reported: [s, s + 50) over 90 until 150, 60 after it has the mean
    # (90 (150 - s) + 60 (s - 100)) / 50 = 150 - 0.6 s, which first reaches 70 or less at s = 134 (69.6)
    late = reward_cliff([100.0] + [90.0] * 149 + [60.0] * 50)
    assert late["cliff_iteration"] == 134 and late["drop"] == pytest.approx(0.304)


def test_missing_iterations_count_as_zero_as_fpo_plus_plus_reads_them():
    data = [{"iteration": it, "reward_mean": 100.0} for it in range(150) if it < 100] + [{"iteration": 149}]
    cliff = run_health(data)["cliff"]  # iterations 100..149 have no reward: zeros, a 100 % drop from iteration 100
    assert (cliff["status"], cliff["iterations"], cliff["cliff_iteration"]) == ("cliff_detected", 150, 100)


def test_settings_and_curve_keys_round_trip():
    for n, noise in [(10, "random"), (1, "zero")]:
        name = setting_name(n, noise)
        assert setting_of(curve_key(name)) == name
    assert (setting_name(1, "zero"), curve_key("N=1/zero"), curve_key("mean_action")) == (
        "N=1/zero",
        "eval/return_N1_zero",
        "eval/return",
    )
    assert run_health([{"iteration": 0, "reward_mean": 3.0}])["curves"] == {}


def test_health_line():
    line = health_line(run_health(rows(**{"eval/return_N1_zero": [700.0, 70.0], "reward_mean": [1.0, 2.0]})))
    assert line == (
        "cliff: insufficient data (needs 150 iterations, has 2);  N=1/zero peak 700 (it 0), final 70 (-90 %)"
    )
