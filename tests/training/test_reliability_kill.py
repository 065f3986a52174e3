"""kill -9 at the worst moments: during training, during a checkpoint write, during a motion-library write.

Afterwards no file may be corrupt (every checkpoint loads, progress.jsonl reads, config.yaml parses, the previous
motion library is byte-identical), and a resume continues from the newest checkpoint. The numbers (iterations lost,
corrupt files) are printed (``pytest -s``) and asserted: corrupt files must be 0, iterations lost at most the
checkpoint interval.
"""

from __future__ import annotations

import itertools
import json
import re
from pathlib import Path

import numpy as np
import pytest
from reliability_helpers import kill_when, run_tool, start_tool, tiny, tree_hash

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.motion.amass import write_amass
from refpo_warp.motion.motion_library import MotionLibrary
from refpo_warp.runner.checkpoints import list_checkpoints, read_checkpoint
from refpo_warp.runner.progress import read_rows
from refpo_warp.utils.errors import DataFileError

pytestmark = pytest.mark.slow


def corrupt_files(run_dir: Path) -> list[str]:
    """Files of a run that a reader cannot use (temp files of an interrupted write are not run files)."""
    bad = []
    for ckpt in list_checkpoints(run_dir):
        try:
            read_checkpoint(ckpt)
        except DataFileError as err:
            bad.append(str(err))
    for reader, name in ((read_rows, "progress.jsonl"), (lambda d: load_yaml(d / "config.yaml"), "config.yaml")):
        if (run_dir / name).exists():
            try:
                reader(run_dir)
            except Exception as err:
                bad.append(f"{name}: {err}")
    return bad


def last_logged(run_dir: Path) -> int:
    rows = read_rows(run_dir) if (run_dir / "progress.jsonl").exists() else []
    return rows[-1]["iteration"] if rows else -1


def resume(run_dir: Path, max_iterations: int) -> tuple[int, str]:
    proc = run_tool(
        "train", f"run_dir={run_dir}", "resume=true", f"max_iterations={max_iterations}", "eval.at_end=false"
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr
    found = re.search(r"from model_(\d+)\.pt: iteration (\d+)", proc.stdout)
    assert found, proc.stdout[-2000:]
    return int(found.group(2)), proc.stderr


def assert_continuous(run_dir: Path) -> None:
    rows = read_rows(run_dir)
    assert [r["iteration"] for r in rows] == list(range(len(rows))), "iterations repeat or skip after resume"
    steps = [r["env_steps"] for r in rows]
    assert all(b > a for a, b in itertools.pairwise(steps)), "env_steps go back after resume"


def test_kill_during_training(tmp_path):
    run_dir = tmp_path / "run"
    numbers = []
    proc = start_tool(
        "train", *tiny("max_iterations=400", "runner.save_interval=3", "eval.at_end=false", f"run_dir={run_dir}")
    )
    for round_, at in enumerate((4, 11)):
        assert kill_when(proc, lambda at=at: last_logged(run_dir) >= at), proc.stderr.read() if proc.stderr else ""
        logged, bad = last_logged(run_dir), corrupt_files(run_dir)
        resumed_from, _ = resume(run_dir, logged + 2)
        numbers.append(
            {
                "round": round_,
                "last_logged_iteration": logged,
                "resumed_from": resumed_from,
                "iterations_lost": logged - resumed_from,
                "corrupt_files": len(bad),
            }
        )
        assert not bad, bad
        assert logged - resumed_from <= 3  # save_interval
        assert_continuous(run_dir)
        if round_ == 0:
            proc = start_tool("train", f"run_dir={run_dir}", "resume=true", "max_iterations=400", "eval.at_end=false")
    print("\n[reliability] kill -9 during training:", json.dumps(numbers))


def test_kill_during_checkpoint_write(tmp_path):
    run_dir = tmp_path / "run"
    big = "[768, 768, 768]"  # ~30 MB checkpoints: a write takes long enough to be hit
    args = tiny(
        "max_iterations=50",
        "eval.at_end=false",
        f"run_dir={run_dir}",
        f"actor.hidden_dims={big}",
        f"critic.hidden_dims={big}",
    )
    hit = False
    for _attempt in range(5):  # each attempt kills the first checkpoint write after model_0.pt exists
        proc = (
            start_tool("train", *args)
            if not run_dir.exists()
            else start_tool("train", f"run_dir={run_dir}", "resume=true", "max_iterations=50", "eval.at_end=false")
        )
        kill_when(proc, lambda: (run_dir / "model_0.pt").exists() and any(run_dir.glob(".model_*.pt.*.tmp")))
        if any(run_dir.glob(".model_*.pt.*.tmp")):
            hit = True
            break
    assert hit, "the kill never landed during a checkpoint write"
    before = {p.name for p in list_checkpoints(run_dir)}
    bad = corrupt_files(run_dir)
    logged = last_logged(run_dir)
    resumed_from, _ = resume(run_dir, logged + 2)
    print(
        "\n[reliability] kill -9 during a checkpoint write:",
        json.dumps(
            {
                "checkpoints_before_kill": sorted(before),
                "last_logged_iteration": logged,
                "resumed_from": resumed_from,
                "iterations_lost": logged - resumed_from,
                "corrupt_files": len(bad),
            }
        ),
    )
    assert not bad, bad
    assert not list(run_dir.glob(".*.tmp")), "the resume removes the interrupted write's temp file"
    assert_continuous(run_dir)


def test_kill_during_motion_library_write(tmp_path):
    rng = np.random.default_rng(1)
    frames = 20_000  # about 11 minutes of motion at 30 fps: a library of ~40 MB, compressed for a second or two
    src = write_amass(
        tmp_path / "long_poses.npz",
        rng.normal(0, 0.2, (frames, 3)),
        rng.normal(0, 0.2, (frames, 63)),
        np.cumsum(rng.normal(0, 0.001, (frames, 3)), axis=0),
        30.0,
    )
    small = write_amass(
        tmp_path / "small" / "s_poses.npz", np.zeros((40, 3)), np.zeros((40, 63)), np.zeros((40, 3)), 30.0
    )
    out = tmp_path / "lib.motionlib.npz"
    assert run_tool("convert_amass", small, f"out={out}").returncode == 0
    good = tree_hash(out)
    hits = 0
    for _attempt in range(3):
        proc = start_tool("convert_amass", src, f"out={out}")
        if kill_when(proc, lambda: any(tmp_path.glob(".lib.motionlib.npz.*.tmp"))):
            hits += 1
        assert tree_hash(out) == good, "the previous library was damaged"
    library = MotionLibrary.load(out)
    print(
        "\n[reliability] kill -9 during a motion-library write:",
        json.dumps(
            {"kills_during_write": hits, "previous_file_intact": tree_hash(out) == good, "clips": library.num_clips}
        ),
    )
    assert hits >= 1 and library.num_clips == 1
