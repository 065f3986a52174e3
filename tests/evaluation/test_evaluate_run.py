"""What an evaluation keeps: one name per metric in eval.json, and the previous eval.json when tools/eval.py replaces
it."""

import json
import re
import subprocess
import sys

import pytest

from refpo_warp.evaluation.evaluate_run import evaluate_run
from refpo_warp.training import train
from refpo_warp.utils.paths import REPO_ROOT as ROOT

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

RSL_RL_CHATTER = (
    "Actor Model:",
    "Critic Model:",
    "Resolved observation sets",
    "Storing git diff",
    "Could not find git repository",
)


def test_one_name_per_metric_in_eval_json(tmp_run_dir, quick_run):
    results = train(quick_run + [f"run_dir={tmp_run_dir}"])
    for summary in results["results"].values():
        # success_mean (= success_rate) and reached_top_mean (= top_share x success_rate) are not repeated
        assert set(summary) == {
            "episodes",
            "unfinished",
            "return_mean",
            "return_std",
            "length_mean",
            "success_rate",
            "top_share",
            "bottom_share",
        }
        # shares of the successes (none: both 0); the return is 20 per success, GridWorld's only reward
        shares = summary["top_share"] + summary["bottom_share"]
        assert shares == pytest.approx(1.0 if summary["success_rate"] else 0.0)
        assert summary["return_mean"] == pytest.approx(20.0 * summary["success_rate"])


def test_eval_keeps_the_previous_eval_json_and_says_so(tmp_run_dir, quick_run):
    train(quick_run + [f"run_dir={tmp_run_dir}"])
    first = (tmp_run_dir / "eval.json").read_text()
    proc = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "eval.py"), f"run_dir={tmp_run_dir}", "eval.flow_steps=[1]"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert (tmp_run_dir / "eval.prev.json").read_text() == first
    second = json.loads((tmp_run_dir / "eval.json").read_text())
    assert set(second["results"]) == {"N=1"} and set(json.loads(first)["results"]) == {"N=1", "N=2"}
    assert "the previous one is kept as" in proc.stdout
    assert re.search(r"^  previous eval +.*eval\.prev\.json$", proc.stdout, flags=re.MULTILINE), proc.stdout
    assert "Evaluated gridworld / refpo at iteration 2" in proc.stdout
    assert "Could not find or load the NVIDIA CUDA driver" not in proc.stderr
    assert not [m for m in RSL_RL_CHATTER if m in proc.stdout]
    evaluate_run(tmp_run_dir, overrides={"eval.flow_steps": [2]})  # again: the previous is now the N=1 file
    assert set(json.loads((tmp_run_dir / "eval.prev.json").read_text())["results"]) == {"N=1"}
