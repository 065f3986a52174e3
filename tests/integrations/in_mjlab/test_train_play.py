"""mjlab's own ``train`` and ``play --video`` on the ReFPO cartpole, as a user runs them: a short CPU training run
whose report and TensorBoard tags hold ReFPO's statistics as statistics, then ``play`` of its checkpoint recording a
video headless (EGL), read back frame by frame.

Needs mjlab (skipped without it): run in the mjlab job's venv, ``.ci/mjlab`` (docs/mjlab.md)."""

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("mjlab", reason="mjlab is not installed: run in the mjlab venv (.ci/mjlab, docs/mjlab.md)")

TASK = "Mjlab-Cartpole-Balance-ReFPO"
VIDEO_FRAMES = 30
SCRIPTS = Path(sys.executable).parent  # the venv's console scripts: mjlab's train and play


def script(name: str) -> str:
    path = SCRIPTS / name
    assert path.is_file(), f"mjlab's '{name}' script is not in {SCRIPTS}"
    return str(path)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """``train`` for 2 iterations on 16 envs: (its output, its run directory)."""
    root = tmp_path_factory.mktemp("logs")
    cmd = [
        script("train"),
        TASK,
        "--env.scene.num-envs",
        "16",
        "--agent.max-iterations",
        "2",
        "--agent.logger",
        "tensorboard",
        "--gpu-ids",
        "None",
        "--agent.run-name",
        "ci",
        "--log-root",
        str(root),
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    (run_dir,) = (root / "cartpole_refpo").iterdir()
    return out.stdout, run_dir


@pytest.mark.rsl_rl
def test_train_reports_refpo_statistics_as_statistics(trained):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    printed, run_dir = trained
    assert {p.name for p in run_dir.glob("model_*.pt")} == {"model_0.pt", "model_1.pt"}
    assert "Flow/ratio_mean:" in printed and "Flow/explosion_rate:" in printed and "Mean reflow loss:" in printed
    assert "Mean Flow/" not in printed
    events = EventAccumulator(str(run_dir))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert {"Flow/ratio_mean", "Flow/explosion_rate", "Loss/reflow", "Train/mean_episode_length"} <= tags
    assert not [tag for tag in tags if tag.startswith("Loss/Flow")]
    agent = (run_dir / "params" / "agent.yaml").read_text()
    assert "class_name: refpo_warp.algorithms:ReFPO" in agent and "schedule: fixed" in agent


@pytest.mark.rsl_rl
def test_play_records_a_video_of_the_checkpoint(trained):
    """``play --video True`` writes the video after ``--video-length`` frames, then keeps its (headless: viser)
    viewer running, as it does for mjlab's own tasks; the test stops it with Ctrl+C (SIGINT) once the file is
    written, then decodes every frame."""
    import imageio_ffmpeg

    _, run_dir = trained
    video = run_dir / "videos" / "play" / "rl-video-step-0.mp4"
    cmd = [
        script("play"),
        TASK,
        "--agent",
        "trained",
        "--checkpoint-file",
        str(run_dir / "model_1.pt"),
        "--video",
        "True",
        "--video-length",
        str(VIDEO_FRAMES),
        "--num-envs",
        "1",
    ]
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env) as play:
        deadline = time.monotonic() + 300
        size = -1
        while time.monotonic() < deadline and play.poll() is None:
            time.sleep(1.0)
            if video.is_file() and video.stat().st_size == size > 0:  # written, and no longer growing
                break
            size = video.stat().st_size if video.is_file() else -1
        if play.poll() is None:
            play.send_signal(signal.SIGINT)
        printed = play.communicate(timeout=60)[0]
    assert video.is_file(), f"no video at {video}; play printed:\n{printed[-3000:]}"
    reader = imageio_ffmpeg.read_frames(str(video))
    meta = next(reader)
    frames = list(reader)
    width, height = meta["size"]
    assert len(frames) == VIDEO_FRAMES and width > 0 and height > 0
    assert all(len(frame) == width * height * 3 for frame in frames)
    assert len({bytes(frame) for frame in frames}) > 1  # the cartpole moves


def evaluate_here(*argv: str) -> subprocess.CompletedProcess:
    """``python -m refpo_warp.integrations.mjlab.evaluate argv...`` in this process (its ``main``, output and exit
    code captured): the same code from the argument list on, without a new interpreter's imports of mjlab."""
    from refpo_warp.integrations.mjlab.evaluate import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return subprocess.CompletedProcess(argv, code, out.getvalue(), err.getvalue())


def printed_json(proc: subprocess.CompletedProcess) -> dict:
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.rsl_rl
def test_evaluate_reports_both_initial_noise_protocols(trained):
    """The checkpoint's return rate under zero (play's, the default) and random initial noise, as eval.initial_noise
    names them, and at a given number of flow steps; a bad value is one message and exit code 2. The first call as a
    user makes it (``python -m``), the others in this process."""
    _, run_dir = trained
    base = [f"task={TASK}", f"checkpoint={run_dir / 'model_1.pt'}", "num_envs=4", "num_steps=20", "device=cpu"]
    module = [sys.executable, "-m", "refpo_warp.integrations.mjlab.evaluate"]
    rates = printed_json(
        subprocess.run(
            [*module, *base, "initial_noise=[random,zero]"], capture_output=True, text=True, timeout=600, check=False
        )
    )
    zero = printed_json(evaluate_here(*base))
    assert set(rates) == {"reward_rate/random", "reward_rate/zero"} and rates["reward_rate/zero"] == zero["reward_rate"]
    assert rates["reward_rate/random"] != rates["reward_rate/zero"]  # random x_0 is not the deterministic policy
    steps = {n: printed_json(evaluate_here(*base, f"flow_steps={n}"))["reward_rate"] for n in (10, 1)}
    assert steps[10] == zero["reward_rate"] != steps[1]  # the actor's own 10 steps; one Euler step acts otherwise
    bad = evaluate_here(*base, "initial_noise=none")
    assert bad.returncode == 2 and "initial_noise='none' is invalid" in bad.stderr and "Traceback" not in bad.stderr
    bad = evaluate_here(*(a for a in base if not a.startswith("num_envs=")), "num_envs=abc")
    assert bad.returncode == 2 and "num_envs='abc' is invalid" in bad.stderr and "Traceback" not in bad.stderr
