"""Frames of the humanoid: the simulated body (MuJoCo's compiled copy of Newton's model, at env i's state) and its
reference motion beside it, a translucent stick figure at the reference's 24 body positions (spheres, capsules to
each parent), with the clip, the reference frame and the current MPJPE written top left. The camera tracks the
pelvis."""

from __future__ import annotations

import copy

import numpy as np

from refpo_warp.motion import skeleton as sk
from refpo_warp.render.mujoco_scene import Marker, MujocoScene
from refpo_warp.tasks.humanoid.mujoco_c import newton_to_mujoco
from refpo_warp.utils.warp_setup import wp

REFERENCE_RGBA = (0.15, 0.75, 1.0, 0.45)
JOINT_RADIUS, BONE_RADIUS = 0.045, 0.025


class HumanoidFrames:
    """``frame(i)`` of a ``HumanoidTrackingEnv`` (see the module docstring)."""

    def __init__(
        self, env, width: int, height: int, camera: str = "default", shadows: bool = False, reference: bool = True
    ) -> None:
        self.env = env
        model = copy.copy(env.sim.solver.mj_model)  # one world: the humanoid and the ground
        camera = "track" if camera == "default" else camera
        pelvis = next(n for n in (model.body(b).name for b in range(model.nbody)) if n.endswith("Pelvis"))
        self.scene = MujocoScene(model, width, height, camera, pelvis, shadows, distance=3.2, elevation=-15)
        self.reference = bool(reference)
        self.control_hz = 1.0 / env.step_dt
        self._root_com = np.asarray(env.sim.root_com, dtype=np.float64)

    def _reference_bodies(self) -> np.ndarray:
        """(num_envs, 24, 3) reference body positions at each env's current reference time."""
        return self.env.reference_at().body_pos.numpy()

    def frame(self, i: int) -> tuple[np.ndarray, list[str]]:
        env = self.env
        q, qd = wp.to_torch(env.sim.joint_q)[i : i + 1].cpu().numpy(), wp.to_torch(env.sim.joint_qd)[i : i + 1]
        qpos, _ = newton_to_mujoco(q, qd.cpu().numpy(), self._root_com)
        ref = self._reference_bodies()[i]
        body = wp.to_torch(env.sim.body_q)[i, :, :3].cpu().numpy()  # (24, 3) simulated body origins
        mpjpe_mm = 1000.0 * float(np.linalg.norm(body - ref, axis=-1).mean())
        markers = []
        if self.reference:
            markers = [Marker(tuple(p), JOINT_RADIUS, REFERENCE_RGBA) for p in ref]
            markers += [
                Marker(tuple(ref[k]), BONE_RADIUS, REFERENCE_RGBA, tuple(ref[parent]))
                for k, parent in enumerate(sk.PARENTS)
                if parent >= 0
            ]
        clip = int(wp.to_torch(env.clip_id)[i])
        frame_index = int(round(float(wp.to_torch(env.ref_time)[i]) * env.motion.fps))
        lines = [f"clip {env.motion.clip_names[clip]}  frame {frame_index}", f"MPJPE {mpjpe_mm:.0f} mm"]
        return self.scene.render(qpos[0], markers=tuple(markers)), lines

    def close(self) -> None:
        self.scene.close()


def frame_source(
    env, width: int, height: int, camera: str = "default", shadows: bool = False, reference: bool = True, **_
) -> HumanoidFrames:
    return HumanoidFrames(env, width, height, camera, shadows, reference)
