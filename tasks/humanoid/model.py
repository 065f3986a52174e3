"""The simulated SMPL humanoid on Newton + MuJoCo Warp: ``num_envs`` worlds of ``smpl_humanoid.xml`` on a ground plane.

Joint PD control uses Newton's joint target gains (target mode POSITION, the reference's per-joint kp/kd, effort
limit 500 N m); the MJCF carries no stiffness, so there are no passive springs. Self-collision follows MuJoCo's rule
(every pair of geoms of one humanoid except parent-child pairs); every geom touches the ground (friction 1).

Time stepping: 120 Hz physics with 4 substeps per 30 Hz control step (as ProtoMotions' Newton backend). At 60 Hz
the reference gains on the light distal bodies (armature 0.02, kp up to 500) sit at the stability edge of the
integrator: the PD-held standing pose tips over within 3 s, while at 120 Hz it holds (see docs/humanoid.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from refpo_warp.motion import skeleton as sk
from refpo_warp.sim import MuJoCoWorlds
from refpo_warp.tasks.humanoid.mjcf_builder import MJCF_PATH
from refpo_warp.utils.warp_setup import wp

FREE_COORDS = 7  # root position (3) + quaternion xyzw (4)
FREE_DOFS = 6  # root linear (COM) velocity (3) + angular velocity (3), world frame
EFFORT_LIMIT = 500.0
CONTROL_HZ = 30.0  # control steps per second; the motion library is sampled at this rate too
GROUND_FRICTION = 1.0


@dataclass(frozen=True)
class SimOptions:
    """Physics options of the humanoid worlds."""

    substeps: int = 4
    control_dt: float = 1.0 / CONTROL_HZ
    nconmax: int = 32  # contact points per world (MuJoCo Warp pools nconmax x worlds)
    njmax: int = 160  # constraint rows per world (4 per pyramidal contact + joint limits)
    iterations: int = 100
    ls_iterations: int = 50
    integrator: str = "implicitfast"

    @property
    def physics_dt(self) -> float:
        return self.control_dt / self.substeps


class HumanoidSim(MuJoCoWorlds):
    """``num_envs`` humanoid worlds on a ground plane (``MuJoCoWorlds`` with the PD gains set in code).

    Views (first axis = world): ``joint_q`` (N, 76) root pose then 69 hinge angles; ``joint_qd`` (N, 75) root COM
    velocity and angular velocity then 69 hinge rates; ``body_q`` (N, 24) transforms; ``body_qd`` (N, 24) twists
    (COM linear velocity, angular velocity); ``joint_target`` (N, 76) PD targets (only the hinge entries are used).
    After writing joint coordinates of the worlds in ``reset_mask``, ``after_reset()`` recomputes their body poses and
    clears the solver's carried-over buffers (warm start), so a diverged world cannot poison its next episode.
    """

    def __init__(self, num_envs: int, device, options: SimOptions = SimOptions()) -> None:
        import newton

        solver_options = {
            "njmax": options.njmax,
            "nconmax": options.nconmax,
            "iterations": options.iterations,
            "ls_iterations": options.ls_iterations,
            "integrator": options.integrator,
        }
        super().__init__(
            MJCF_PATH,
            num_envs,
            device,
            options.substeps,
            solver_options,
            physics_dt=options.physics_dt,
            edit_world=_set_pd_gains,
            ground=newton.ModelBuilder.ShapeConfig(mu=GROUND_FRICTION, gap=0.0),
            floating=True,
            enable_self_collisions=True,
        )
        self.options = options
        self.num_envs = num_envs
        self.device = device
        v = self.views
        self.joint_q, self.joint_qd, self.body_q, self.body_qd = v.joint_q, v.joint_qd, v.body_q, v.body_qd
        self.joint_target = v.joint_target
        body_com = self.model.body_com.numpy()[: sk.NUM_BODIES]
        self.body_com: wp.array = wp.array(body_com, dtype=wp.vec3, device=device)
        self.root_com = wp.vec3(*body_com[0])  # the root's COM offset in its frame (a kernel argument)

    def constraint_usage(self) -> tuple[int, int]:
        """(largest constraint-row count of any world, total contacts) after the last substep (host sync; tests)."""
        data = self.solver.mjw_data
        return int(data.nefc.numpy().max()), int(data.nacon.numpy()[0])


def _set_pd_gains(robot) -> None:
    """Check the imported layout, then give every hinge the reference's PD gains as Newton joint target gains."""
    import newton

    _check_layout(robot, MJCF_PATH)
    for body in range(1, sk.NUM_BODIES):
        kp, kd = sk.PD_GAINS[body]
        for axis in range(3):
            dof = robot.joint_qd_start[body] + axis
            robot.joint_target_ke[dof] = float(kp)
            robot.joint_target_kd[dof] = float(kd)
            robot.joint_target_mode[dof] = int(newton.JointTargetMode.POSITION)
            robot.joint_effort_limit[dof] = EFFORT_LIMIT


def _check_layout(robot, mjcf: Path) -> None:
    """The importer must give body i = skeleton body i, a free root and one 3-hinge joint per body."""
    names = [label.rsplit("/", 1)[-1] for label in robot.body_label]
    if tuple(names) != sk.BODY_NAMES:
        raise ValueError(f"{mjcf}: body order {names} differs from skeleton.BODY_NAMES")
    if robot.joint_coord_count != FREE_COORDS + sk.NUM_DOFS or robot.joint_dof_count != FREE_DOFS + sk.NUM_DOFS:
        raise ValueError(
            f"{mjcf}: expected {FREE_COORDS + sk.NUM_DOFS} coordinates and {FREE_DOFS + sk.NUM_DOFS} "
            f"DoF, got {robot.joint_coord_count} and {robot.joint_dof_count}"
        )
    expected = FREE_DOFS + 3 * np.arange(sk.NUM_JOINTS)
    if list(robot.joint_qd_start[1:]) != expected.tolist():
        raise ValueError(f"{mjcf}: joint DoF starts {robot.joint_qd_start} are not one 3-DoF joint per body")
    if any(robot.joint_target_ke[d] != 0.0 for d in range(robot.joint_dof_count)):
        raise ValueError(f"{mjcf}: the MJCF must not author actuators; PD gains are set in code")
