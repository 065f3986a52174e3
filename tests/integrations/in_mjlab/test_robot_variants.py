"""The robot variants end to end on the CPU, one iteration on a few envs each: Go1's velocity task (its runner exports
ONNX on every save: the flow policy's, with the single input ``obs``) and G1's tracking task given a motion file
(a standing clip made here from G1's reset pose, in mjlab's motion npz layout). Slow: the first run compiles the
robots' MuJoCo Warp kernels on the CPU.

Needs mjlab (skipped without it), in the mjlab venv (.ci/mjlab):

    . .venv-mjlab/bin/activate && python -m pytest -q -m slow tests/integrations/in_mjlab
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mjlab", reason="mjlab is not installed: run in the mjlab venv (.ci/mjlab, docs/mjlab.md)")


TRAIN = str(Path(sys.executable).parent / "train")


def train(task: str, log_root: Path, *extra: str) -> tuple[str, Path]:
    cmd = [
        TRAIN,
        task,
        "--env.scene.num-envs",
        "4",
        "--agent.max-iterations",
        "1",
        "--agent.logger",
        "tensorboard",
        "--gpu-ids",
        "None",
        "--log-root",
        str(log_root),
        *extra,
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=3000, check=False)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    (experiment,) = log_root.iterdir()
    (run_dir,) = experiment.iterdir()
    return out.stdout + out.stderr, run_dir


def standing_motion(path: Path, frames: int = 100) -> None:
    """A still clip of G1 at its reset pose (every body of the robot, MuJoCo's order, wxyz quaternions)."""
    from mjlab.envs import ManagerBasedRlEnv
    from mjlab.tasks.registry import load_env_cfg

    cfg = load_env_cfg("Mjlab-Velocity-Flat-Unitree-G1", play=True)
    cfg.scene.num_envs = 1
    env = ManagerBasedRlEnv(cfg=cfg, device="cpu")
    try:
        env.reset()
        data = env.scene["robot"].data
        pose = {"joint_pos": data.joint_pos, "body_pos_w": data.body_link_pos_w, "body_quat_w": data.body_link_quat_w}
        clip = {key: np.repeat(value[:1].cpu().numpy(), frames, axis=0) for key, value in pose.items()}
    finally:
        env.close()
    clip["joint_vel"] = np.zeros_like(clip["joint_pos"])
    clip["body_lin_vel_w"] = np.zeros_like(clip["body_pos_w"])
    clip["body_ang_vel_w"] = np.zeros_like(clip["body_pos_w"])
    np.savez(path, fps=np.array([50]), **clip)


@pytest.mark.slow(minutes=10)
@pytest.mark.rsl_rl
def test_go1_velocity_variant_exports_the_flow_policy_with_obs_only(tmp_path):
    import onnx

    printed, run_dir = train("Mjlab-Velocity-Flat-Unitree-Go1-ReFPO", tmp_path / "logs")
    assert "ONNX export failed" not in printed and "Flow/ratio_mean:" in printed
    model = onnx.load(run_dir / f"{run_dir.name}.onnx")
    assert [i.name for i in model.graph.input] == ["obs"] and [o.name for o in model.graph.output] == ["actions"]
    assert any(prop.key == "joint_names" for prop in model.metadata_props)  # mjlab's metadata, attached as for PPO


@pytest.mark.slow(minutes=12)
@pytest.mark.rsl_rl
def test_g1_tracking_variant_trains_on_a_motion_file_and_exports(tmp_path):
    import onnx

    motion = tmp_path / "standing.npz"
    standing_motion(motion)
    printed, run_dir = train(
        "Mjlab-Tracking-Flat-Unitree-G1-ReFPO", tmp_path / "logs", "--env.commands.motion.motion-file", str(motion)
    )
    assert (run_dir / "model_0.pt").is_file() and "Flow/ratio_mean:" in printed
    assert "ONNX export failed" not in printed, printed[-2000:]
    model = onnx.load(run_dir / f"{run_dir.name}.onnx")
    assert [i.name for i in model.graph.input] == ["obs", "time_step"]  # mjlab's tracking export: obs + clip time
