"""Reliability: what a hostile but fair user types or hands over never crashes a tool, loses a run or runs code.

Every case runs a command as a user would, through the entry point of the ``refpo`` command and ``tools/*.py``
(``call_tool``: in this process, its output and exit code captured), and checks: the exit code (docs/cli.md), a
message naming the culprit, no traceback, files unchanged (hashes) where a run is refused, and that a malicious file's
payload did not run (its marker file is absent). The kill -9 cases, which need a process of their own, live in
test_reliability_kill.py.

CI runs every case; the quick suite (-m "not slow") runs one or two of each kind, listed in QUICK.
"""

from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
import torch
from reliability_helpers import (
    assert_refused,
    call_tool,
    copy_run,
    tiny,
    tree_hash,
    truncate,
    write_malicious,
)

from refpo_warp.motion.amass import write_amass

USAGE, NONFINITE, BAD_FILE, UNEXPECTED = 2, 3, 4, 1
SLOW = pytest.mark.slow
QUICK = {
    "num_envs=0",
    "eval.flow_steps=[0]",
    "algorithm.tau_sampling=gaussian",
    "device=cuda:99",
    "algo=ppo",
    "truncated",
    "zip",
    "one-frame",
}


def cases(rows, ids=None):
    """pytest params of ``rows``, marked slow unless their id is in QUICK."""
    ids = ids or [str(row[0] if isinstance(row, tuple) else row) for row in rows]
    return [
        pytest.param(*(row if isinstance(row, tuple) else (row,)), id=i, marks=() if i in QUICK else SLOW)
        for row, i in zip(rows, ids)
    ]


@pytest.fixture(scope="module")
def base_run(tmp_path_factory):
    """A finished tiny run (model_0..2, progress, config) that cases copy and then damage or misuse."""
    run = tmp_path_factory.mktemp("base") / "run"
    proc = call_tool("train", *tiny("max_iterations=3", "eval.at_end=false", f"run_dir={run}"))
    assert proc.returncode == 0, proc.stderr[-3000:]
    return run


@pytest.fixture
def run(base_run, tmp_path):
    return copy_run(base_run, tmp_path / "run")


# ------------------------------------------------------------------------------------------------ bad options
BAD_OPTIONS = [
    ("num_envs=0", ["num_envs=0"]),
    ("num_envs=-4", ["num_envs=-4"]),
    ("num_envs=1000000000", ["num_envs=1000000000", "4,194,304"]),
    ("runner.num_steps_per_env=0", ["runner.num_steps_per_env=0"]),
    ("runner.save_interval=0", ["runner.save_interval=0"]),
    ("algorithm.num_mini_batches=0", ["algorithm.num_mini_batches=0"]),
    ("algorithm.num_mini_batches=1000", ["algorithm.num_mini_batches=1000", "num_envs=4"]),
    ("algorithm.learning_rate=-1", ["algorithm.learning_rate=-1", "(0, 1]"]),
    ("algorithm.learning_rate=nan", ["algorithm.learning_rate='nan'", "expected a number in (0, 1]"]),  # a word in YAML
    ("algorithm.learning_rate=.nan", ["algorithm.learning_rate=nan", "not a finite number"]),  # YAML's NaN
    ("algorithm.gamma=1.5", ["algorithm.gamma=1.5", "[0, 1]"]),
    ("algorithm.clip_param=0", ["algorithm.clip_param=0"]),
    ("algorithm.tau_sampling=gaussian", ["algorithm.tau_sampling='gaussian'", "'uniform', 'discrete'"]),
    ("actor.activation=relux", ["actor.activation='relux'", "'relu'"]),
    ("actor.hidden_dims=[]", ["actor.hidden_dims=[]"]),
    ("actor.time_embed_dim=7", ["actor.time_embed_dim=7", "multiple of 2"]),
    ("eval.flow_steps=[0]", ["eval.flow_steps[0]=0"]),
    ("max_iterations=0", ["max_iterations=0"]),
    ("max_iterations=-3", ["max_iterations=-3"]),
    ("device=cuda:99", ["device=cuda:99"]),
    ("device=tpu", ["device='tpu'", "cuda:N"]),
    ("runner.logger=foo", ["runner.logger='foo'", "tensorboard"]),
    ("nmu_envs=4", ["nmu_envs", "Did you mean 'num_envs'"]),
    ("seed=abc", ["seed='abc'", "expected an integer"]),
    ("notakeyvalue", ["notakeyvalue", "key=value"]),
]


@pytest.mark.parametrize("arg,culprits", cases(BAD_OPTIONS))
def test_bad_option_is_refused_before_anything_is_created(arg, culprits, tmp_path):
    run_dir = tmp_path / "never"
    proc = call_tool("train", *tiny("max_iterations=2", f"run_dir={run_dir}", arg))
    assert_refused(proc, USAGE, *culprits)
    assert not run_dir.exists()


@pytest.mark.parametrize(
    "args,culprit",
    cases(
        [(["seed=1", "seed=2"], "'seed' is given twice"), (["env.size=9", "size=11"], "'size' and 'env.size'")],
        ["same-key", "alias-key"],
    ),
)
@SLOW
def test_key_given_twice_is_refused(args, culprit, tmp_path):
    proc = call_tool("train", *tiny(f"run_dir={tmp_path / 'never'}"), *args)
    assert_refused(proc, USAGE, culprit)
    assert not (tmp_path / "never").exists()


@SLOW
def test_run_dir_that_is_a_file_is_refused_and_kept(tmp_path):
    afile = tmp_path / "notes.txt"
    afile.write_text("my notes")
    for run_dir in (afile, afile / "sub"):
        proc = call_tool("train", *tiny("max_iterations=2", f"run_dir={run_dir}"))
        assert_refused(proc, USAGE, str(afile))
    assert afile.read_text() == "my notes"


@SLOW
def test_new_run_into_a_foreign_directory_is_refused(tmp_path):
    folder = tmp_path / "my_project"
    folder.mkdir()
    (folder / "config.yaml").write_text("my own config: keep me\n")
    (folder / "eval.json").write_text("{}")
    before = tree_hash(folder)
    assert_refused(
        call_tool("train", *tiny("max_iterations=2", f"run_dir={folder}")),
        USAGE,
        str(folder),
        "not a refpo_warp run directory",
    )
    assert tree_hash(folder) == before


# ------------------------------------------------------------------------------------------------ resume mistakes
RESUME_CHANGES = [
    ("algo=ppo", "algo=ppo"),
    ("task=dmc_cartpole_balance", "task=dmc_cartpole_balance"),
    ("actor.hidden_dims=[32]", "actor.hidden_dims: [16] -> [32]"),
    ("critic.activation=tanh", "critic.activation"),
    ("algorithm.optimizer=sgd", "algorithm.optimizer"),
]


@pytest.mark.parametrize("arg,culprit", cases(RESUME_CHANGES))
def test_resume_that_changes_the_run_is_refused_and_writes_nothing(run, arg, culprit):
    before = tree_hash(run)
    assert_refused(call_tool("train", f"run_dir={run}", "resume=true", arg), USAGE, culprit)
    assert tree_hash(run) == before


@SLOW
def test_resume_without_checkpoint_is_an_error_not_a_fresh_start(run):
    for ckpt in run.glob("model_*.pt"):
        ckpt.unlink()
    before = tree_hash(run)
    assert_refused(call_tool("train", f"run_dir={run}", "resume=true"), USAGE, "holds no checkpoint")
    assert tree_hash(run) == before


@SLOW
def test_resume_of_missing_run_dir_is_refused(tmp_path):
    assert_refused(call_tool("train", f"run_dir={tmp_path / 'gone'}", "resume=true"), USAGE, "no such run directory")
    assert not (tmp_path / "gone").exists()


@SLOW
def test_new_run_into_a_run_dir_with_checkpoints_is_refused(run):
    before = tree_hash(run)
    assert_refused(call_tool("train", *tiny(f"run_dir={run}")), USAGE, "resume=true", "model_2.pt")
    assert tree_hash(run) == before


@pytest.mark.parametrize(
    "content,culprit",
    cases(
        [
            (b"\x80\x81\xfe\xff" * 64, "cannot be read"),
            (b"task: gridworld\ntask: gridworld\n", "given twice"),
            (b"- just\n- a list\n", "mapping"),
            (None, "num_envs=0"),
        ],
        ["binary", "duplicate-key", "not-a-mapping", "bad-value"],
    ),
)
@SLOW
def test_damaged_saved_config_is_named(run, content, culprit):
    config = run / "config.yaml"
    config.write_bytes(content if content is not None else config.read_bytes().replace(b"num_envs: 4", b"num_envs: 0"))
    before = tree_hash(run)
    assert_refused(call_tool("train", f"run_dir={run}", "resume=true"), BAD_FILE, "config.yaml", culprit)
    assert tree_hash(run) == before


@SLOW
def test_saved_config_cannot_select_an_arbitrary_callable(run, tmp_path):
    marker = tmp_path / "PWNED"
    config = run / "config.yaml"
    text = config.read_text().replace("class_name: rsl_rl.models:MLPModel", "class_name: os:system", 1)
    config.write_text(text.replace("\ncritic:\n", f"\ncritic:\n  command: touch {marker}\n", 1))
    before = tree_hash(run)
    assert_refused(call_tool("train", f"run_dir={run}", "resume=true"), BAD_FILE, "config.yaml", "os:system")
    assert not marker.exists() and tree_hash(run) == before


@SLOW
def test_run_dir_in_use_is_refused(run):
    import fcntl
    import os

    fd = os.open(run, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)  # as a running training process holds it
        before = tree_hash(run)
        assert_refused(call_tool("train", f"run_dir={run}", "resume=true", "max_iterations=5"), USAGE, "in use")
        assert tree_hash(run) == before
    finally:
        os.close(fd)


@SLOW
def test_resume_continues_progress_and_honours_learning_rate(run):
    proc = call_tool(
        "train",
        f"run_dir={run}",
        "resume=true",
        "max_iterations=5",
        "algorithm.learning_rate=1e-4",
        "eval.at_end=false",
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    rows = [json.loads(line) for line in (run / "progress.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [0, 1, 2, 3, 4]
    assert [r["env_steps"] for r in rows] == [32 * (i + 1) for i in range(5)]  # 4 envs x 8 steps per iteration
    saved = torch.load(run / "model_4.pt", weights_only=True)
    assert saved["optimizer_state_dict"]["param_groups"][0]["lr"] == pytest.approx(1e-4)
    assert saved["refpo_warp"]["env_steps"] == 160


# ------------------------------------------------------------------------------------------------ checkpoints
CORRUPT = {
    "empty": (lambda run, p: p.write_bytes(b""), "empty file"),
    "truncated": (lambda run, p: p.write_bytes((run / "model_2.pt").read_bytes()[:3000]), "truncated"),
    "text": (lambda run, p: p.write_text("not a checkpoint at all\n" * 20), "cannot be read as a checkpoint"),
    "missing-keys": (lambda run, p: torch.save({"weights": torch.zeros(3)}, p), "missing actor_state_dict"),
    "nan-weights": (lambda run, p: torch.save(_edited(run, nan=True), p), "NaN or infinite"),
    "other-shape": (lambda run, p: torch.save(_edited(run, shape=True), p), "does not fit"),
    "other-task": (lambda run, p: torch.save(_edited(run, task="dmc_cheetah_run"), p), "task=dmc_cheetah_run"),
}


def _edited(run, nan=False, shape=False, task=None):
    data = torch.load(run / "model_2.pt", weights_only=True)
    name = next(iter(data["actor_state_dict"]))
    if nan:
        data["actor_state_dict"][name] = data["actor_state_dict"][name] * float("nan")
    if shape:
        data["actor_state_dict"][name] = torch.zeros(3, 3)
    if task:
        data["refpo_warp"]["task"] = task
    return data


@pytest.mark.parametrize("kind", cases(list(CORRUPT)))
def test_bad_checkpoint_given_to_eval_is_named(run, kind):
    bad = run / f"given_{kind}.pt"
    make, culprit = CORRUPT[kind]
    make(run, bad)
    before = tree_hash(run)
    assert_refused(call_tool("eval", f"run_dir={run}", f"checkpoint={bad}"), BAD_FILE, str(bad), culprit)
    assert tree_hash(run) == before


@pytest.mark.parametrize("kind", cases(["zip", "legacy", "pickle"]))
def test_malicious_checkpoint_is_refused_without_running_it(run, tmp_path, kind):
    marker = tmp_path / "PWNED"
    evil = write_malicious(run / "evil.pt", marker, kind)
    before = tree_hash(run)
    proc = call_tool("eval", f"run_dir={run}", f"checkpoint={evil}")
    assert_refused(proc, BAD_FILE, str(evil))
    assert not marker.exists(), "the checkpoint's payload ran"
    assert tree_hash(run) == before


@SLOW
def test_malicious_newest_checkpoint_is_skipped_on_resume(run, tmp_path):
    marker = tmp_path / "PWNED"
    write_malicious(run / "model_9.pt", marker, "zip")
    proc = call_tool("train", f"run_dir={run}", "resume=true", "max_iterations=4", "eval.at_end=false")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "skipping checkpoint" in proc.stderr and "model_9.pt" in proc.stderr and "model_2.pt" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not marker.exists(), "the checkpoint's payload ran"


@SLOW
def test_malicious_newest_checkpoint_is_skipped_by_eval(run, tmp_path):
    marker = tmp_path / "PWNED"
    write_malicious(run / "model_9.pt", marker, "legacy")
    proc = call_tool("eval", f"run_dir={run}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "model_9.pt" in proc.stderr and not marker.exists()
    assert json.loads((run / "eval.json").read_text())["checkpoint_iteration"] == 2


@SLOW
def test_truncated_newest_checkpoint_falls_back_on_resume(run):
    truncate(run / "model_2.pt")
    proc = call_tool("train", f"run_dir={run}", "resume=true", "max_iterations=3", "eval.at_end=false")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "model_2.pt" in proc.stderr and "continuing from model_1.pt" in proc.stderr
    rows = [json.loads(line) for line in (run / "progress.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [0, 1, 2]  # iteration 2 retrained once, not logged twice
    torch.load(run / "model_2.pt", weights_only=True)  # rewritten whole


@SLOW
def test_all_checkpoints_unusable_is_named_and_writes_nothing(run):
    for ckpt in run.glob("model_*.pt"):
        truncate(ckpt)
    before = tree_hash(run)
    assert_refused(call_tool("train", f"run_dir={run}", "resume=true"), BAD_FILE, "model_0.pt", "model_2.pt")
    assert tree_hash(run) == before


@pytest.mark.parametrize("target", cases(["missing.pt", "."], ["missing", "directory"]))
def test_checkpoint_path_that_is_not_a_file(run, target):
    path = run / target
    assert_refused(call_tool("eval", f"run_dir={run}", f"checkpoint={path}"), BAD_FILE, str(path))


@SLOW
def test_eval_of_run_without_checkpoint(run):
    for ckpt in run.glob("model_*.pt"):
        ckpt.unlink()
    assert_refused(call_tool("eval", f"run_dir={run}"), USAGE, "holds no checkpoint")


# ------------------------------------------------------------------------------------------------ progress files
def _tear(run):
    path = run / "progress.jsonl"
    path.write_text(path.read_text() + '{"iteration": 3, "env_st')  # a write cut off by a crash


def test_torn_progress_line_is_tolerated_by_plot(run):
    _tear(run)
    proc = call_tool("plot", f"run_dirs={run}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (run / "curves.png").stat().st_size > 0


@SLOW
def test_torn_progress_line_is_repaired_on_resume(run):
    _tear(run)
    proc = call_tool("train", f"run_dir={run}", "resume=true", "max_iterations=4", "eval.at_end=false")
    assert proc.returncode == 0, proc.stderr[-3000:]
    rows = [json.loads(line) for line in (run / "progress.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [0, 1, 2, 3]


@SLOW
def test_torn_progress_line_is_tolerated_by_eval(run):
    _tear(run)
    proc = call_tool("eval", f"run_dir={run}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads((run / "eval.json").read_text())["diagnostics"]


@SLOW
def test_damaged_progress_line_is_named(run):
    path = run / "progress.jsonl"
    lines = path.read_text().splitlines()
    path.write_text("\n".join([lines[0], "garbage{", *lines[1:]]) + "\n")
    assert_refused(call_tool("plot", f"run_dirs={run}"), BAD_FILE, "progress.jsonl: line 2")


# ------------------------------------------------------------------------------------------------ motion files
def _amass(path, frames=60, fps=30.0, trans_scale=1.0, nan=False):
    rng = np.random.default_rng(0)
    pose = rng.normal(0.0, 0.1, (frames, 66))
    if nan:
        pose[frames // 2, 5] = np.nan
    trans = np.cumsum(np.full((frames, 3), 0.01), axis=0) * trans_scale
    return write_amass(path, pose[:, :3], pose[:, 3:], trans, fps)


MOTIONS = {
    "one-frame": ({"frames": 1}, "1 frame"),
    "resampled-to-one": ({"frames": 2, "fps": 1000.0}, "too short to resample"),
    "fps-1e9": ({"fps": 1e9}, "mocap_framerate=1e+09"),
    "fps-1e-6": ({"fps": 1e-6}, "mocap_framerate=1e-06"),
    "huge-translation": ({"trans_scale": 1e12}, "'trans' holds values beyond"),
    "nan-pose": ({"nan": True}, "NaN or infinite"),
}


@pytest.mark.parametrize("kind", cases(list(MOTIONS)))
def test_bad_motion_file_is_named(kind, tmp_path):
    options, culprit = MOTIONS[kind]
    src = _amass(tmp_path / f"{kind}_poses.npz", **options)
    out = tmp_path / "out.motionlib.npz"
    assert_refused(call_tool("convert_amass", src, f"out={out}"), BAD_FILE, str(src), culprit)
    assert not out.exists()


@SLOW
def test_bad_library_frame_rate_option(tmp_path):
    src = _amass(tmp_path / "ok_poses.npz")
    assert_refused(call_tool("convert_amass", src, f"out={tmp_path / 'o.motionlib.npz'}", "fps=0"), USAGE, "fps=0")


@pytest.mark.parametrize("damage", cases(["one-frame-clip", "not-a-zip"]))
def test_bad_motion_library_given_to_train_is_named(damage, tmp_path):
    lib = tmp_path / "lib.motionlib.npz"
    assert call_tool("convert_amass", _amass(tmp_path / "ok_poses.npz"), f"out={lib}").returncode == 0
    if damage == "not-a-zip":
        lib.write_bytes(b"PK\x03\x04 broken")
        culprit = "cannot be read"
    else:  # rewrite the library with one clip of a single frame (and consistent tables)
        with np.load(lib) as data:
            arrays = {k: data[k] for k in data.files}
        for key in ("body_pos", "body_rot", "body_vel", "body_angvel", "dof_pos", "dof_vel"):
            arrays[key] = arrays[key][:1]
        arrays["clip_frames"] = np.array([1])
        with open(lib, "wb") as f:
            np.savez(f, **arrays)
        culprit = "has 1 frame(s)"
    proc = call_tool(
        "train",
        "task=humanoid_root",
        "device=cpu",
        "num_envs=2",
        "max_iterations=1",
        f"run_dir={tmp_path / 'never'}",
        f"motion_file={lib}",
    )
    assert_refused(proc, BAD_FILE, str(lib), culprit)
    assert not (tmp_path / "never").exists()


# ------------------------------------------------------------------------------------------------ faults
def _boom(*args, **kwargs):
    raise RuntimeError("injected fault")


def test_unexpected_error_before_the_run_dir_exists_goes_to_a_log_file(tmp_path, monkeypatch):
    from refpo_warp.training import train_run

    monkeypatch.setattr(train_run, "build_runner", _boom)
    proc = call_tool("train", *tiny("max_iterations=2", f"run_dir={tmp_path / 'never'}"))
    assert_refused(proc, UNEXPECTED, "unexpected RuntimeError: injected fault", "full traceback is in")
    log = proc.stderr.rsplit("full traceback is in ", 1)[1].strip()
    assert "Traceback (most recent call last)" in pathlib.Path(log).read_text()
    assert not (tmp_path / "never").exists()


@SLOW
def test_unexpected_error_during_training_goes_to_the_run_dir(tmp_path, monkeypatch):
    from refpo_warp.runner.runner import Runner

    monkeypatch.setattr(Runner, "learn", _boom)
    run_dir = tmp_path / "run"
    proc = call_tool("train", *tiny("max_iterations=2", f"run_dir={run_dir}"))
    assert_refused(proc, UNEXPECTED, "injected fault", str(run_dir / "error.log"))
    assert "Traceback (most recent call last)" in (run_dir / "error.log").read_text()


def _nan_at_update(monkeypatch, n: int) -> None:
    """ReFPO's n-th update reports a NaN surrogate loss (as a diverged update would)."""
    from refpo_warp.algorithms import ReFPO

    original, calls = ReFPO.update, [0]

    def update(self):
        out = original(self)
        calls[0] += 1
        if calls[0] == n:
            out["surrogate"] = float("nan")
        return out

    monkeypatch.setattr(ReFPO, "update", update)


def test_non_finite_loss_without_checkpoint_says_so(tmp_path, monkeypatch):
    run_dir = tmp_path / "run"
    _nan_at_update(monkeypatch, 1)
    proc = call_tool("train", *tiny("max_iterations=4", f"run_dir={run_dir}"))
    assert_refused(proc, NONFINITE, "iteration 0", "No checkpoint was written", "algorithm.learning_rate")
    assert "intact" not in proc.stderr and not list(run_dir.glob("model_*.pt"))


@SLOW
def test_non_finite_loss_advice_works(tmp_path, monkeypatch):
    run_dir = tmp_path / "run"
    _nan_at_update(monkeypatch, 3)
    proc = call_tool("train", *tiny("max_iterations=4", f"run_dir={run_dir}"))
    assert_refused(proc, NONFINITE, "iteration 2", str(run_dir / "model_1.pt"), "resume=true")
    stopped = json.loads((run_dir / "stopped.json").read_text())  # what keeps a sweep from continuing it
    assert (stopped["last_logged_iteration"], stopped["newest_checkpoint"]) == (1, "model_1.pt")
    monkeypatch.undo()  # the advised resume runs the real update
    command = proc.stderr.split("refpo train ", 1)[1].split("\n")[0]
    args = command.replace("<value>", "1e-4").split() + ["max_iterations=4", "eval.at_end=false"]
    resumed = call_tool("train", *args)
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    saved = torch.load(run_dir / "model_3.pt", weights_only=True)
    assert saved["optimizer_state_dict"]["param_groups"][0]["lr"] == pytest.approx(1e-4)
    rows = [json.loads(line) for line in (run_dir / "progress.jsonl").read_text().splitlines()]
    assert [r["iteration"] for r in rows] == [0, 1, 2, 3]
    assert not (run_dir / "stopped.json").exists()  # a resumed run is no longer the stopped one
