"""What tools/train.py prints: rsl_rl's messages only with verbose=true, 0-based iteration numbers that match the
checkpoints and progress.jsonl, and the closing summary block."""

import json
import re

import pytest
import torch

from refpo_warp.training import train
from refpo_warp.utils.machine import cpu_model

pytestmark = pytest.mark.rsl_rl  # runs again on the lowest supported rsl-rl-lib (.ci/run)

RSL_RL_CHATTER = (
    "Actor Model:",
    "Critic Model:",
    "Resolved observation sets",
    "Storing git diff",
    "Could not find git repository",
)


def test_rsl_rl_messages_only_with_verbose(tmp_path, capsys, quick_run):
    train(quick_run + [f"run_dir={tmp_path / 'quiet'}", "eval.at_end=false"])
    quiet = capsys.readouterr().out
    assert not [m for m in RSL_RL_CHATTER if m in quiet], quiet
    train(quick_run + [f"run_dir={tmp_path / 'verbose'}", "eval.at_end=false", "verbose=true"])
    verbose = capsys.readouterr().out
    assert "Actor Model: FlowActor" in verbose and "Resolved observation sets" in verbose
    assert "Storing git diff" in verbose or "Could not find git repository" in verbose  # in a checkout or not


def test_iterations_count_from_zero_everywhere_and_the_run_ends_with_its_summary(tmp_run_dir, capsys, quick_run):
    results = train(quick_run + [f"run_dir={tmp_run_dir}"])
    out = capsys.readouterr().out
    shown = [int(m) for m in re.findall(r"^\[it (\d+)/2\]", out, flags=re.MULTILINE)]
    rows = [json.loads(line) for line in (tmp_run_dir / "progress.jsonl").read_text().splitlines()]
    assert shown == [r["iteration"] for r in rows] == [0, 1, 2]
    assert sorted(p.name for p in tmp_run_dir.glob("model_*.pt")) == ["model_0.pt", "model_2.pt"]
    assert results["checkpoint_iteration"] == 2
    # the machine that trained it, as every benchmark file records its own
    assert results["machine"]["cpu"] == cpu_model() and results["machine"]["torch_threads"] == torch.get_num_threads()
    block = out[out.index("Trained gridworld / refpo") :]
    for name, where in [
        ("checkpoint", tmp_run_dir / "model_2.pt"),
        ("config", tmp_run_dir / "config.yaml"),
        ("eval.json", tmp_run_dir / "eval.json"),
        ("TensorBoard", tmp_run_dir),
    ]:
        assert re.search(rf"^  {name} +{re.escape(str(where))}", block, flags=re.MULTILINE), (name, block)
    assert "curves.png" in block and "gridworld_field_N1.png" in block
    n1 = results["results"]["N=1"]
    assert f"return {n1['return_mean']:.2f}" in block and f"success_rate {n1['success_rate']:.4g}" in block
