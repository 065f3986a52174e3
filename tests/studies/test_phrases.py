"""The words the results pages put around their numbers."""

from refpo_warp.studies.reports.phrases import and_list, value_range


def test_and_list_joins_like_english_without_a_comma_before_the_last():
    assert and_list([]) == ""
    assert and_list(["PPO"]) == "PPO"
    assert and_list(["PPO", "ReFPO"]) == "PPO and ReFPO"
    assert and_list(["cartpole", "point_mass", "reacher"]) == "cartpole, point_mass and reacher"
    assert and_list(x for x in ("a", "b", "c", "d")) == "a, b, c and d"  # any iterable, read once


def test_value_range_writes_the_extremes_once_where_they_read_the_same():
    assert value_range([0.031, 0.012, 0.02], ".2f") == "0.01-0.03"
    assert value_range([3.0, 2.6], ".0f") == "3"  # both read 3
    assert value_range([-0.2, 0.15], ".1f", sep=" to ") == "-0.2 to 0.1"
    assert value_range(iter([5.0]), ".3g") == "5"
