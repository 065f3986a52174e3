"""The words the results pages put around their numbers."""

from refpo_warp.studies.reports.phrases import and_list


def test_and_list_joins_like_english_without_a_comma_before_the_last():
    assert and_list([]) == ""
    assert and_list(["PPO"]) == "PPO"
    assert and_list(["PPO", "ReFPO"]) == "PPO and ReFPO"
    assert and_list(["cartpole", "point_mass", "reacher"]) == "cartpole, point_mass and reacher"
    assert and_list(x for x in ("a", "b", "c", "d")) == "a, b, c and d"  # any iterable, read once
