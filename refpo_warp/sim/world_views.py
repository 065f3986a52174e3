"""Zero-copy per-world 2-D views of a replicated Newton model's state, control and constants.

With ``num_worlds`` identical worlds, Newton stores every per-body / per-coordinate array world after world, so a
reshape to ``(num_worlds, per_world)`` is a view of the same memory: kernels index ``[world, i]``, and writes through
the views are what the solver reads on its next step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from refpo_warp.utils.warp_setup import wp


@dataclass
class WorldViews:
    """Per-world views (first axis = world) of one Newton state, its control and model constants."""

    joint_q: wp.array  # (W, coords) generalized positions in Newton's convention (MuJoCo qpos - ref)
    joint_qd: wp.array  # (W, dofs) generalized velocities
    body_q: wp.array  # (W, bodies) wp.transform: body frame pose in world
    body_qd: wp.array  # (W, bodies) wp.spatial_vector: (linear velocity of the COM, angular velocity), world frame
    body_mass: wp.array  # (W, bodies)
    ctrl: wp.array | None  # (W, actuators) MuJoCo actuator controls (control.mujoco.ctrl), None without actuators
    joint_target: wp.array  # (W, coords) joint position targets of Newton's joint PD (control.joint_target_q)
    coord_ref: wp.array | None  # (coords,) MJCF joint ``ref``: MuJoCo qpos = joint_q + coord_ref; None with free joints
    limit_lower: np.ndarray  # (dofs,) joint limits in Newton coordinates (huge for unlimited joints); host only
    limit_upper: np.ndarray
    body_labels: list[str]  # labels of the bodies of one world, in body order

    def body_index(self, name: str) -> int:
        """Index (within a world) of the body whose MJCF name is ``name``."""
        for i, label in enumerate(self.body_labels):
            if label == name or label.endswith("/" + name):
                return i
        names = [label.rsplit("/", 1)[-1] for label in self.body_labels]
        raise KeyError(f"No body named '{name}' in this model; bodies: {', '.join(names)}")


def make_world_views(model, state, control) -> WorldViews:
    """Build the views for ``state``/``control`` of a model made of identical worlds."""
    w = model.world_count
    coords, dofs, bodies = model.joint_coord_count // w, model.joint_dof_count // w, model.body_count // w
    coord_ref: wp.array | None = None
    if coords == dofs:  # MuJoCo qpos = joint_q + ref holds coordinate-wise only without free/ball joints
        dof_ref = getattr(getattr(model, "mujoco", None), "dof_ref", None)
        ref = dof_ref.numpy()[:coords] if dof_ref is not None else np.zeros(coords, np.float32)
        coord_ref = wp.array(ref.astype(np.float32), dtype=float, device=model.device)
    ctrl = getattr(getattr(control, "mujoco", None), "ctrl", None)
    return WorldViews(
        joint_q=state.joint_q.reshape((w, coords)),
        joint_qd=state.joint_qd.reshape((w, dofs)),
        body_q=state.body_q.reshape((w, bodies)),
        body_qd=state.body_qd.reshape((w, bodies)),
        body_mass=model.body_mass.reshape((w, bodies)),
        ctrl=ctrl.reshape((w, ctrl.shape[0] // w)) if ctrl is not None and ctrl.shape[0] else None,
        joint_target=control.joint_target_q.reshape((w, coords)),
        coord_ref=coord_ref,
        limit_lower=model.joint_limit_lower.numpy()[:dofs].copy(),
        limit_upper=model.joint_limit_upper.numpy()[:dofs].copy(),
        body_labels=list(model.body_label[:bodies]),
    )
