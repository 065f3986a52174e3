"""Learning check: ReFPO and Gaussian PPO learn dmc_cartpole_balance on the CPU within a few minutes.

Uses the task's CPU profile as shipped (configs/task/dmc_cartpole_balance.yaml: 256 envs, 450k env steps) and the
final evaluation of tools/train.py (N = 10 and N = 1 Euler steps for ReFPO, the mean action for PPO).
"""

import os

import pytest
import torch

from refpo_warp.training import train


@pytest.fixture
def two_threads():
    # The update dominates the run time; CI has 2 cores (conftest pins 1 thread for the small unit tests). Under
    # xdist (-n 2) the other core runs the other worker's tests: one thread each.
    previous = torch.get_num_threads()
    torch.set_num_threads(1 if os.environ.get("PYTEST_XDIST_WORKER") else 2)
    yield
    torch.set_num_threads(previous)


@pytest.mark.slow
def test_refpo_balances_the_cartpole_with_ten_and_one_flow_steps(tmp_run_dir, two_threads):
    results = train(["task=dmc_cartpole_balance", "algo=refpo", "seed=1", "device=cpu", f"run_dir={tmp_run_dir}"])
    assert results["results"].keys() == {"N=10", "N=1"}
    for setting, summary in results["results"].items():
        assert summary["return_mean"] >= 800, (setting, summary)
        assert summary["length_mean"] == 1000 and summary["nonfinite_resets_mean"] == 0
    assert (tmp_run_dir / "eval.json").exists() and (tmp_run_dir / "curves.png").exists()


@pytest.mark.slow
def test_ppo_balances_the_cartpole(tmp_run_dir, two_threads):
    results = train(["task=dmc_cartpole_balance", "algo=ppo", "seed=1", "device=cpu", f"run_dir={tmp_run_dir}",
                     "eval.interval=0"])  # fmt: skip
    summary = results["results"]["mean_action"]
    assert summary["return_mean"] >= 800, summary
