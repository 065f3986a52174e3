"""tools/play.py as a user runs it: a video of a random agent, one step beside ten for a trained run, and one clear
message with its exit code for a bad option or a machine without an OpenGL platform."""

import math
import os
import subprocess
import sys

from video_frames import read_video  # tests/ is on sys.path under pytest

from refpo_warp.cli.main import main
from refpo_warp.training import train
from refpo_warp.utils.paths import REPO_ROOT

SMALL = ["video.width=64", "video.height=48"]


def play(*args, env=None):
    return subprocess.run(
        [sys.executable, "tools/play.py", *map(str, args)],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        check=False,
    )


def test_a_random_agents_video_in_both_formats(tmp_path):
    proc = play(
        "task=dmc_cartpole_balance", "agent=random", "video.length=9", "video.format=both", f"out={tmp_path}", *SMALL
    )
    assert proc.returncode == 0, proc.stderr
    every = math.ceil(100 / 30)  # cartpole steps at 100 Hz, a video at most 30 frames per second
    frames = math.ceil(9 / every) + 1  # the drawn steps and the final frame
    assert read_video(tmp_path / "dmc_cartpole_balance_random.mp4").shape == (frames, 48, 64, 3)
    assert read_video(tmp_path / "dmc_cartpole_balance_random.gif").shape == (frames, 48, 64, 3)
    assert str(tmp_path / "dmc_cartpole_balance_random.mp4") in proc.stdout


def test_one_step_beside_ten_from_a_trained_run(tmp_path):
    run_dir = tmp_path / "run"
    train(
        [
            "task=gridworld",
            "algo=refpo",
            "device=cpu",
            "max_iterations=1",
            "num_envs=8",
            "runner.num_steps_per_env=8",
            "algorithm.num_mc_samples=2",
            "eval.at_end=false",
            "eval.interval=0",
            f"run_dir={run_dir}",
        ]
    )
    proc = play(f"run_dir={run_dir}", "video.flow_steps=[1, 10]", "video.num_envs=2", "video.length=5", *SMALL)
    assert proc.returncode == 0, proc.stderr
    (video,) = (run_dir / "videos").glob("*.mp4")
    assert video.name == "model_0_N1-10.mp4"
    frames = read_video(video)
    assert frames.shape[1:] == (48, 2 * 2 * 64, 3)  # two panels side by side, two envs tiled in each
    # both initial-noise protocols: one panel per (protocol, N)
    proc = play(
        f"run_dir={run_dir}",
        "video.flow_steps=[1]",
        "eval.initial_noise=[random, zero]",
        "video.num_envs=1",
        "video.length=3",
        *SMALL,
    )
    assert proc.returncode == 0, proc.stderr
    video = run_dir / "videos" / "model_0_N1_random-zero.mp4"
    assert read_video(video).shape[1:] == (48, 2 * 64, 3)
    proc = play(f"run_dir={run_dir}", "eval.initial_noise=none", *SMALL)
    assert proc.returncode == 2 and "eval.initial_noise='none' is invalid" in proc.stderr


def test_bad_options_and_a_missing_gl_platform_get_one_message_and_an_exit_code(tmp_path, capsys):
    # the bad options through the command's own entry point here (tools/play.py calls the same); the GL platform in a
    # fresh interpreter, since MuJoCo reads MUJOCO_GL once, when first imported
    bad = [
        (
            ("agent=random", "video.camera=overhead", "video.length=2", *SMALL),
            "camera='overhead' is invalid; expected one of 'track', 'fixed'",
        ),
        (("agent=walk",), "agent='walk' is invalid; expected null or one of 'zero', 'random'"),
        (("agent=zero", "video.widht=64"), "Did you mean 'video.width'"),
        (("agent=zero", "env.action_transfrom=tanh"), "Did you mean 'env.action_transform'"),
        # the spellings refpo play once took, refused with the names refpo train gives them
        (("agent=zero", "length=2"), "'length=' is spelled 'video.length='"),
        (("agent=zero", "flow_steps=[1]"), "'flow_steps=' is spelled 'video.flow_steps='"),
        (("agent=zero", "action_transform=tanh"), "'action_transform=' is spelled 'env.action_transform='"),
        (("agent=zero", "initial_noise=zero"), "'initial_noise=' is spelled 'eval.initial_noise='"),
        (("agent=zero", "fps=30"), "'fps=' is spelled 'video.fps='"),
        # the video options that say when a training run records, bare or not: refpo play's own refusal
        (("agent=zero", "at_end=true"), "'at_end=': video.at_end says when a training run records"),
        (("agent=zero", "video.interval=3"), "'video.interval=': video.interval says when a training run records"),
    ]
    for options, message in bad:
        code = main(["play", "task=dmc_cartpole_balance", *options, f"out={tmp_path}"])
        err = capsys.readouterr().err
        assert code == 2 and message in err and "Traceback" not in err, (options, err)
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"} | {"MUJOCO_GL": "glx"}
    proc = play("task=dmc_cartpole_balance", "agent=zero", "video.length=2", f"out={tmp_path}", *SMALL, env=env)
    assert proc.returncode == 5 and "no OpenGL platform" in proc.stderr and "MUJOCO_GL=egl needs" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not list(tmp_path.glob("*.mp4"))


def test_a_runs_video_keys_are_refused_by_play_before_the_run_is_read(tmp_path, capsys):
    """The same refusals for a trained run's video (checked before its run dir is read: this one does not exist) and
    under --explain, instead of passing a bare key on as a run option."""
    missing = f"run_dir={tmp_path / 'none'}"
    for argv, message in [
        ((missing, "at_end=true"), "'at_end=': video.at_end says when a training run records"),
        ((missing, "interval=5"), "'interval=': video.interval says when a training run records"),
        ((missing, "video.at_end=true"), "'video.at_end=': video.at_end says when a training run records"),
        ((missing, "fps=30"), "'fps=' is spelled 'video.fps='"),
        (("--explain", missing, "fps=30"), "'fps=' is spelled 'video.fps='"),
        (("--explain", "task=gridworld", "agent=zero", "at_end=true"), "video.at_end says when a training run"),
    ]:
        assert main(["play", *argv]) == 2
        err = capsys.readouterr().err
        assert message in err, (argv, err)
        assert "Traceback" not in err and "no such run directory" not in err, (argv, err)
    assert main(["play", "--explain", "device", missing, "video.fps=30"]) == 0  # the right spelling passes on
    assert "passed on: video.fps=30" in capsys.readouterr().out
