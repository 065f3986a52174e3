"""Learning check: ReFPO and Gaussian PPO balance the humanoid longer within a few minutes on a CPU.

Uses humanoid_all_residual's CPU profile as shipped (configs/task/humanoid_all_residual.yaml: standing clip,
residual PD targets, 64 envs x 32 steps) cut to 40 of its 100 iterations, without the final evaluation. The full
profile over 3 seeds is the demonstration in docs/humanoid.md ("Learning on a CPU"); this check asks for a clear
rising trend of the training episode length: its least-squares line over the 40 iterations has a slope at least 3
standard errors above 0 and rises by at least 5 % of its starting value. Over seeds 1-3 on one and two torch threads
(docs/results/learning_checks.md) the least was t = 5.2 and +11 % (ReFPO, seed 1, two threads); PPO 7.6 and +20 %.
ReFPO's return rises by only 0.2-0.3 of ~8 by then, too little to assert on another CPU.
"""

import numpy as np
import pytest

from refpo_warp.runner.progress import read_rows
from refpo_warp.training import train

ITERATIONS, MIN_T, MIN_RISE = 40, 3.0, 0.05


def linear_trend(y: np.ndarray) -> tuple[float, float]:
    """(t statistic of the least-squares slope, fitted rise over the series relative to the fitted start)."""
    x = np.arange(len(y), dtype=float)
    slope, start = np.polyfit(x, y, 1)
    residuals = y - (start + slope * x)
    standard_error = np.sqrt(residuals @ residuals / (len(y) - 2) / ((x - x.mean()) ** 2).sum())
    return slope / standard_error, slope * (len(y) - 1) / start


def test_linear_trend_against_hand_worked_series():
    y = np.array([1.1, 1.0, 1.3, 1.2])
    t, rise = linear_trend(y)
    # by hand: slope 0.06, intercept 1.06, residuals (0.04, -0.12, 0.12, -0.04), SSE 0.032, Sxx 5
    assert np.isclose(rise, 0.06 * 3 / 1.06)
    assert np.isclose(t, 0.06 / np.sqrt(0.032 / 2 / 5))


@pytest.mark.slow(minutes=5)
@pytest.mark.parametrize("algo", ["refpo", "ppo"])
def test_humanoid_episodes_get_longer(algo, tmp_run_dir):
    train(["task=humanoid_all_residual", f"algo={algo}", "seed=1", "device=cpu", f"max_iterations={ITERATIONS}",
           "eval.at_end=false", f"run_dir={tmp_run_dir}"])  # fmt: skip
    rows = read_rows(tmp_run_dir)
    assert len(rows) == ITERATIONS
    length = np.array([r["episode_length_mean"] for r in rows])
    t, rise = linear_trend(length)
    print(f"[learning check] humanoid {algo}: episode length trend t = {t:.1f}, rise {100 * rise:.1f} %", flush=True)
    assert t >= MIN_T and rise >= MIN_RISE, (algo, round(t, 2), round(rise, 3), length.round(1).tolist())
