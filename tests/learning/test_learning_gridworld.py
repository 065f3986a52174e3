"""Learning check: ReFPO on GridWorld with the paper's budget (260k env steps) and hyperparameters, on the CPU."""

import pytest

from refpo_warp.training import train


@pytest.mark.slow(minutes=3)
def test_refpo_solves_gridworld_with_one_and_ten_flow_steps(tmp_run_dir):
    results = train(["task=gridworld", "algo=refpo", "seed=1", "device=cpu", f"run_dir={tmp_run_dir}",
                     "eval.flow_steps=[1, 10]"])  # fmt: skip
    assert results["results"].keys() == {"N=1", "N=10"}
    for setting, summary in results["results"].items():
        assert summary["success_rate"] >= 0.95, (setting, summary)
        # the policy stays multimodal: both goal bands receive a real share of the successes
        assert summary["top_share"] >= 0.2 and summary["bottom_share"] >= 0.2, (setting, summary)
    assert results["diagnostics"]["explosion_rate"] < 0.01
