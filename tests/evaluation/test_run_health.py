"""Run health: peak, final and drop of each periodic evaluation curve, the cliff flag, against hand-worked series."""

import pytest

from refpo_warp.evaluation.evaluate_policy import curve_key, setting_name
from refpo_warp.evaluation.run_health import run_health, setting_of
from refpo_warp.utils.console import health_line


def rows(**curves):
    n = max(len(v) for v in curves.values())
    out = [{"iteration": it} for it in range(n)]
    for key, values in curves.items():
        for it, value in enumerate(values):
            if value is not None:
                out[it][key] = value
    return out


def test_peak_final_and_drop_hand_worked():
    health = run_health(rows(**{"eval/return_N10": [None, 400.0, None, 950.0, 900.0],
                                "eval/return_N1": [None, 700.0, None, 300.0, 75.0]}))  # fmt: skip
    assert health["N=10"] == {"peak": 950.0, "peak_iteration": 3, "final": 900.0, "final_iteration": 4,
                              "drop": pytest.approx(50 / 950), "cliff": False}  # fmt: skip
    assert health["N=1"]["peak_iteration"] == 1 and health["N=1"]["drop"] == pytest.approx(625 / 700)
    assert health["N=1"]["cliff"] is True


def test_cliff_threshold_is_thirty_percent_of_the_peak():
    assert run_health(rows(**{"eval/return": [100.0, 70.0]}))["mean_action"]["cliff"] is True  # exactly 30 %
    assert run_health(rows(**{"eval/return": [100.0, 70.1]}))["mean_action"]["cliff"] is False
    negative = run_health(rows(**{"eval/return": [-10.0, -20.0]}))["mean_action"]  # peak -10: twice as bad
    assert negative["drop"] == pytest.approx(1.0) and negative["cliff"]


def test_settings_and_curve_keys_round_trip():
    for n, noise in [(10, "random"), (1, "zero")]:
        name = setting_name(n, noise)
        assert setting_of(curve_key(name)) == name
    assert (setting_name(1, "zero"), curve_key("N=1/zero"), curve_key("mean_action")) == (
        "N=1/zero", "eval/return_N1_zero", "eval/return")  # fmt: skip
    assert run_health([{"iteration": 0, "reward_mean": 3.0}]) == {}


def test_health_line():
    line = health_line(run_health(rows(**{"eval/return_N1_zero": [700.0, 70.0]})))
    assert line == "N=1/zero peak 700 (it 0), final 70 (-90 %) CLIFF"
