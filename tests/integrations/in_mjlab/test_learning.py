"""Bounded learning check of ReFPO inside mjlab: mjlab's own ``train`` of ``Mjlab-Cartpole-Balance-ReFPO`` (ReFPO's
settings, the task's 64x64 sizes) for ITERATIONS iterations on 64 envs (seed 1, the CPU), then the deterministic
return rate of its first and last checkpoints (``refpo_warp.integrations.mjlab.evaluate``: 64 envs, 200 steps from
reset, mean reward per simulated second; 1 is upright, centred and still).

Why not the episode length: the balance task ends episodes by time-out only, and mjlab's ``train`` starts them at
random lengths, so rsl_rl's "mean episode length" rises from about 8 to 450 in 30 iterations whatever the policy
does (measured with the learning rate at 1e-12: 8.0 -> 447.5, the curve of a learning run of the same seed).

The bounds (the constants below) were set from 3 seeds and a run that learns nothing (docs/mjlab.md, "Tests and
CI"). Needs mjlab (skipped without it): the mjlab job runs it in its venv (.ci/mjlab), 45 s on the idle 2-core CPU.
"""

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("mjlab", reason="mjlab is not installed: run in the mjlab venv (.ci/mjlab, docs/mjlab.md)")

from refpo_warp.integrations.mjlab.evaluate import evaluate

TASK = "Mjlab-Cartpole-Balance-ReFPO"
ITERATIONS = 30
MIN_FINAL_RATE = 0.30  # measured (3 seeds): 0.351, 0.524, 0.421
MIN_GAIN = 0.05  # final - first checkpoint, measured: +0.085, +0.178, +0.211


@pytest.mark.slow(minutes=1)
@pytest.mark.rsl_rl
def test_refpo_learns_to_balance_the_cartpole_inside_mjlab(tmp_path):
    cmd = [str(Path(sys.executable).parent / "train"), TASK, "--env.scene.num-envs", "64", "--agent.max-iterations",
           str(ITERATIONS), "--agent.seed", "1", "--agent.logger", "tensorboard", "--gpu-ids", "None",
           "--log-root", str(tmp_path)]  # fmt: skip
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=1200, check=False)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    (run_dir,) = (tmp_path / "cartpole_refpo").iterdir()
    first = evaluate(TASK, str(run_dir / "model_0.pt"))["reward_rate"]
    final = evaluate(TASK, str(run_dir / f"model_{ITERATIONS - 1}.pt"))["reward_rate"]
    assert final >= MIN_FINAL_RATE and final - first >= MIN_GAIN, (first, final)
