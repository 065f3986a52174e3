"""One MuJoCo model drawn offscreen at a fixed size: a camera that is fixed, tracks a body or is one of the model's,
markers added to the scene (spheres, capsules: e.g. a reference motion's bodies), shadows off by default.

``MujocoScene(model, 640, 480, camera="track", track_body="torso").render(qpos)`` sets the model's joint positions
(MuJoCo's ``qpos``), runs MuJoCo's forward kinematics and returns an RGB frame (height, width, 3) of uint8. The
OpenGL platform must be chosen before MuJoCo is imported (``refpo_warp.render.gl.select_gl_platform``).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from refpo_warp.utils.errors import ConfigError, SystemRefusedError

CAMERA_MODES = ("track", "fixed")
DEFAULT_RGBA = (0.5, 0.5, 0.5, 1.0)  # MuJoCo's geom colour when a file sets none
BODY_RGBA = (0.75, 0.52, 0.3, 1.0)  # such geoms are drawn in DM Control's body colour
FLOOR_RGBA = (0.22, 0.3, 0.38, 1.0)  # and such planes as a blue-grey floor
TARGET_RGBA = (0.85, 0.2, 0.2, 0.85)  # geoms named *target*: what a task asks the body to reach


@dataclass(frozen=True)
class Marker:
    """A geom drawn into the scene only: a sphere at ``start`` or a capsule from ``start`` to ``end``."""

    start: tuple[float, float, float]
    size: float
    rgba: tuple[float, float, float, float]
    end: tuple[float, float, float] | None = None


def themed(model) -> None:
    """Colours for a model file that sets none (every geom grey), and a brighter headlight; drawing only."""
    import mujoco

    plain = np.all(np.isclose(model.geom_rgba, DEFAULT_RGBA), axis=1)
    planes = model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE
    targets = np.array(
        ["target" in (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or "") for g in range(model.ngeom)],
        dtype=bool,
    )
    model.geom_rgba[plain & ~planes] = BODY_RGBA
    model.geom_rgba[plain & planes] = FLOOR_RGBA
    model.geom_rgba[plain & targets] = TARGET_RGBA
    model.vis.headlight.ambient[:] = 0.35
    model.vis.headlight.diffuse[:] = 0.6


def model_extent(model, data) -> tuple[np.ndarray, float]:
    """(centre, radius) of the model's geoms other than planes (a ground plane would dwarf the robot), after
    kinematics: where a camera should look and how far it should stand."""
    import mujoco

    keep = model.geom_type != mujoco.mjtGeom.mjGEOM_PLANE
    if not keep.any():
        return np.asarray(model.stat.center, dtype=np.float64), float(model.stat.extent)
    pos, rbound = data.geom_xpos[keep], model.geom_rbound[keep]
    centre = pos.mean(axis=0)
    return centre, float(np.max(np.linalg.norm(pos - centre, axis=1) + rbound))


def camera_choices(model) -> list[str]:
    import mujoco

    return [*CAMERA_MODES, *(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) for i in range(model.ncam))]


class MujocoScene:
    """An offscreen renderer of ``model`` (see the module docstring)."""

    def __init__(
        self,
        model,
        width: int = 640,
        height: int = 480,
        camera: str = "fixed",
        track_body: str | None = None,
        shadows: bool = False,
        distance: float | None = None,
        elevation: float = -20.0,
        azimuth: float = 90.0,
    ) -> None:
        """``distance``: of the free camera from what it looks at (default: from the size of the model's geoms at
        its initial pose); ``elevation``, ``azimuth``: its angles in degrees (-90 looks straight down)."""
        import mujoco

        self._mj = mujoco
        model = copy.copy(model)  # room for the frame size in the offscreen buffer, without touching the caller's
        model.vis.global_.offwidth = max(int(model.vis.global_.offwidth), width)
        model.vis.global_.offheight = max(int(model.vis.global_.offheight), height)
        themed(model)
        self.model, self.data = model, mujoco.MjData(model)
        self.width, self.height = int(width), int(height)
        choices = camera_choices(model)
        if camera not in choices:
            raise ConfigError(f"camera={camera!r} is invalid; expected one of {', '.join(map(repr, choices))}")
        try:
            self.renderer = mujoco.Renderer(model, self.height, self.width, max_geom=model.ngeom + 256)
        except Exception as err:  # (each GL platform fails in its own way)
            raise SystemRefusedError(
                f"MuJoCo's offscreen renderer could not start ({type(err).__name__}: {err}); "
                f"set MUJOCO_GL=egl or MUJOCO_GL=osmesa (docs/videos.md)"
            ) from None
        self.camera = mujoco.MjvCamera()
        if camera in CAMERA_MODES:
            mujoco.mj_forward(model, self.data)
            centre, radius = model_extent(model, self.data)
            mujoco.mjv_defaultFreeCamera(model, self.camera)
            self.camera.lookat[:] = centre
            self.camera.distance = distance or 2.8 * radius
            self.camera.elevation, self.camera.azimuth = elevation, azimuth
            if camera == "track":
                body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, track_body) if track_body else 1
                if body < 0:
                    raise ConfigError(f"track_body={track_body!r} is not a body of the model")
                self.camera.type, self.camera.trackbodyid = mujoco.mjtCamera.mjCAMERA_TRACKING, body
        else:
            self.camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            self.camera.fixedcamid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        self.shadows = bool(shadows)

    def render(
        self, qpos: np.ndarray, mocap_pos: np.ndarray | None = None, markers: tuple[Marker, ...] = ()
    ) -> np.ndarray:
        """The frame of the model at joint positions ``qpos`` (and mocap body positions), with ``markers``."""
        mj, data = self._mj, self.data
        data.qpos[:] = qpos
        if mocap_pos is not None:
            data.mocap_pos[:] = mocap_pos
        mj.mj_forward(self.model, data)
        self.renderer.update_scene(data, camera=self.camera)
        scene = self.renderer.scene
        scene.flags[mj.mjtRndFlag.mjRND_SHADOW] = self.shadows
        for marker in markers:
            if scene.ngeom >= scene.maxgeom:
                break
            geom = scene.geoms[scene.ngeom]
            rgba = np.asarray(marker.rgba, dtype=np.float32)
            if marker.end is None:
                mj.mjv_initGeom(
                    geom,
                    mj.mjtGeom.mjGEOM_SPHERE,
                    np.full(3, marker.size),
                    np.asarray(marker.start),
                    np.eye(3).flatten(),
                    rgba,
                )
            else:
                mj.mjv_initGeom(geom, mj.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.eye(3).flatten(), rgba)
                mj.mjv_connector(
                    geom,
                    mj.mjtGeom.mjGEOM_CAPSULE,
                    marker.size,
                    np.asarray(marker.start, np.float64),
                    np.asarray(marker.end, np.float64),
                )
            scene.ngeom += 1
        return self.renderer.render()

    def close(self) -> None:
        """Free the GL context now (its finaliser at interpreter exit may find the platform gone)."""
        renderer, self.renderer = getattr(self, "renderer", None), None
        if renderer is not None:
            renderer.close()

    def __enter__(self) -> MujocoScene:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
