"""Frames of DMC envs: the task's own MJCF file in MuJoCo's offscreen renderer, at env i's MuJoCo ``qpos`` (and its
task state that only shows, e.g. reacher's target: ``DmcTask.render_mocap``). The camera is the task's
(``DmcTask.render_camera``: cheetah and walker track their torso, the others look at the whole arena)."""

from __future__ import annotations

import numpy as np

from refpo_warp.render.mujoco_scene import MujocoScene


class DmcFrames:
    """``frame(i)`` of a ``DmcEnv`` (see the module docstring)."""

    def __init__(self, env, width: int, height: int, camera: str = "default", shadows: bool = False) -> None:
        import mujoco

        self.env = env
        task = env.task
        model = mujoco.MjModel.from_xml_path(str(task.model_path()))
        if camera == "default":
            camera = task.render_camera
        elevation, azimuth = task.render_view
        self.scene = MujocoScene(
            model, width, height, camera, task.track_body, shadows, task.render_distance, elevation, azimuth
        )
        self.control_hz = 1.0 / env.sim.control_dt

    def frame(self, i: int) -> tuple[np.ndarray, list[str]]:
        qpos = self.env.qpos[i].cpu().numpy()
        return self.scene.render(qpos, self.env.task.render_mocap(i)), []

    def close(self) -> None:
        self.scene.close()


def frame_source(env, width: int, height: int, camera: str = "default", shadows: bool = False, **_) -> DmcFrames:
    return DmcFrames(env, width, height, camera, shadows)
