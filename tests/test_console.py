"""What train.py and eval.py print and keep: rsl_rl's messages only with verbose=true, 0-based iteration numbers that
match the checkpoints and progress.jsonl, the closing summary block, one name per metric, the previous eval.json."""

import json
import re
import subprocess
import sys
from pathlib import Path

from refpo_warp.evaluation.evaluate_run import evaluate_run
from refpo_warp.training import train
from refpo_warp.utils.console import quiet_stdout

ROOT = Path(__file__).resolve().parents[1]
QUICK = ["task=gridworld", "algo=refpo", "num_envs=8", "runner.num_steps_per_env=16", "max_iterations=3",
         "algorithm.num_mc_samples=4", "algorithm.num_learning_epochs=1", "runner.save_interval=2",
         "eval.num_envs=8", "eval.flow_steps=[1, 2]", "eval.interval=0", "device=cpu"]  # fmt: skip
RSL_RL_CHATTER = ("Actor Model:", "Critic Model:", "Resolved observation sets", "Storing git diff",
                  "Could not find git repository")  # fmt: skip


def test_rsl_rl_messages_only_with_verbose(tmp_path, capsys):
    train(QUICK + [f"run_dir={tmp_path / 'quiet'}", "eval.at_end=false"])
    quiet = capsys.readouterr().out
    assert not [m for m in RSL_RL_CHATTER if m in quiet], quiet
    train(QUICK + [f"run_dir={tmp_path / 'verbose'}", "eval.at_end=false", "verbose=true"])
    verbose = capsys.readouterr().out
    assert "Actor Model: FlowActor" in verbose and "Resolved observation sets" in verbose
    assert "Storing git diff" in verbose or "Could not find git repository" in verbose  # in a checkout or not


def test_quiet_stdout_replays_what_it_hid_when_the_block_fails(capsys):
    try:
        with quiet_stdout():
            print("a clue")
            raise RuntimeError("boom")
    except RuntimeError:
        pass
    captured = capsys.readouterr()
    assert captured.out == "" and "a clue" in captured.err


def test_iterations_count_from_zero_everywhere_and_the_run_ends_with_its_summary(tmp_run_dir, capsys):
    results = train(QUICK + [f"run_dir={tmp_run_dir}"])
    out = capsys.readouterr().out
    shown = [int(m) for m in re.findall(r"^\[it (\d+)/2\]", out, flags=re.M)]
    rows = [json.loads(line) for line in (tmp_run_dir / "progress.jsonl").read_text().splitlines()]
    assert shown == [r["iteration"] for r in rows] == [0, 1, 2]
    assert sorted(p.name for p in tmp_run_dir.glob("model_*.pt")) == ["model_0.pt", "model_2.pt"]
    assert results["checkpoint_iteration"] == 2
    block = out[out.index("Trained gridworld / refpo"):]
    for name, where in [("checkpoint", tmp_run_dir / "model_2.pt"), ("config", tmp_run_dir / "config.yaml"),
                        ("eval.json", tmp_run_dir / "eval.json"), ("TensorBoard", tmp_run_dir)]:  # fmt: skip
        assert re.search(rf"^  {name} +{re.escape(str(where))}", block, flags=re.M), (name, block)
    assert "curves.png" in block and "gridworld_field_N1.png" in block
    n1 = results["results"]["N=1"]
    assert f"return {n1['return_mean']:.2f}" in block and f"success_rate {n1['success_rate']:.4g}" in block


def test_one_name_per_metric_in_eval_json(tmp_run_dir):
    results = train(QUICK + [f"run_dir={tmp_run_dir}"])
    for summary in results["results"].values():
        # success_mean (= success_rate) and reached_top_mean (= top_share x success_rate) are not repeated
        assert set(summary) == {"episodes", "unfinished", "return_mean", "return_std", "length_mean", "success_rate",
                                "top_share", "bottom_share"}  # fmt: skip
        assert abs(summary["top_share"] + summary["bottom_share"] - 1.0) < 1e-9 or summary["success_rate"] == 0.0


def test_eval_keeps_the_previous_eval_json_and_says_so(tmp_run_dir):
    train(QUICK + [f"run_dir={tmp_run_dir}"])
    first = (tmp_run_dir / "eval.json").read_text()
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "eval.py"), f"run_dir={tmp_run_dir}",
                           "eval.flow_steps=[1]"], capture_output=True, text=True, timeout=300)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert (tmp_run_dir / "eval.prev.json").read_text() == first
    second = json.loads((tmp_run_dir / "eval.json").read_text())
    assert set(second["results"]) == {"N=1"} and set(json.loads(first)["results"]) == {"N=1", "N=2"}
    assert "the previous one is kept as" in proc.stdout
    assert re.search(r"^  previous eval +.*eval\.prev\.json$", proc.stdout, flags=re.M), proc.stdout
    assert "Evaluated gridworld / refpo at iteration 2" in proc.stdout
    assert "Could not find or load the NVIDIA CUDA driver" not in proc.stderr
    assert not [m for m in RSL_RL_CHATTER if m in proc.stdout]
    evaluate_run(tmp_run_dir, overrides={"eval.flow_steps": [2]})  # again: the previous is now the N=1 file
    assert set(json.loads((tmp_run_dir / "eval.prev.json").read_text())["results"]) == {"N=1"}


def test_only_warps_no_driver_warning_is_dropped(capfd):
    import os

    from refpo_warp.utils.device import NO_DRIVER_WARNING, _stderr_without

    with _stderr_without(NO_DRIVER_WARNING):  # native code writes to file descriptor 2, as Warp's library does
        os.write(2, f"Warp CUDA warning: {NO_DRIVER_WARNING}. GPU execution will not be available.\n".encode())
        os.write(2, b"Warp CUDA error: something else\n")
        print("python-level warning", file=sys.stderr)
    err = capfd.readouterr().err
    assert NO_DRIVER_WARNING not in err
    assert "Warp CUDA error: something else" in err and "python-level warning" in err


def test_benchmark_tables_are_titled_blocks(capsys):
    from refpo_warp.utils.timing import print_table

    print_table([{"a": 1, "b": "x"}], ["a", "b"], title="First", notes=("ratio 2.0x",))
    print_table([{"a": 22}], ["a"], title="Second")
    lines = capsys.readouterr().out.split("\n")
    assert lines[:7] == ["", "### First", "", "| a | b |", "|---|---|", "| 1 | x |", ""]
    assert lines[7:10] == ["ratio 2.0x", "", "### Second"]  # one blank line before each title
