"""A Newton model of N identical MJCF worlds stepped by ``SolverMuJoCo`` (MuJoCo Warp), graph-capture friendly.

``MuJoCoWorlds`` owns the model, the solver, one canonical ``state`` (every view and kernel reads and writes it) and
a scratch state for the solver's ping-pong. ``simulate()`` runs the physics substeps of one control step and always
leaves the result in ``state``, so a captured graph replays correctly for any substep count. Resets write joint
coordinates into ``state`` (the solver copies them into MuJoCo at its next step), then ``after_reset`` clears the
solver's per-world memory (warm start, applied forces) and recomputes body poses by forward kinematics.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import warp as wp

from refpo_warp.sim.mjcf_worlds import build_mjcf_worlds, mjcf_timestep
from refpo_warp.sim.world_views import make_world_views


@wp.kernel
def _clear_masked_rows(mask: wp.array(dtype=wp.bool), values: wp.array2d(dtype=float)):
    w, j = wp.tid()
    if mask[w]:
        values[w, j] = 0.0


@wp.kernel
def _clear_masked_wrenches(mask: wp.array(dtype=wp.bool), values: wp.array2d(dtype=wp.spatial_vector)):
    w, j = wp.tid()
    if mask[w]:
        values[w, j] = wp.spatial_vector()


class MuJoCoWorlds:
    """``num_worlds`` copies of an MJCF model on one Warp device, advanced ``substeps`` MuJoCo steps per ``simulate``.

    Args:
        mjcf_path: The MJCF file; its ``<option timestep>`` is the physics step.
        num_worlds: Number of worlds.
        device: Warp device name.
        substeps: Physics steps per control step.
        solver_options: Extra ``SolverMuJoCo`` keyword arguments (e.g. ``iterations``); the file's options otherwise.
    """

    def __init__(self, mjcf_path: str | Path, num_worlds: int, device: str, substeps: int = 1,
                 solver_options: dict | None = None) -> None:  # fmt: skip
        import newton

        if substeps < 1:
            raise ValueError(f"substeps must be >= 1, got {substeps}")
        self.mjcf_path = Path(mjcf_path)
        self.dt = mjcf_timestep(self.mjcf_path)
        self.substeps = int(substeps)
        self.model = build_mjcf_worlds(self.mjcf_path, num_worlds, device)
        # Every movable root would otherwise get an inactive weld constraint (only needed for kinematic switching).
        options = {"kinematic_switchable_roots": False, **(solver_options or {})}
        self.solver = newton.solvers.SolverMuJoCo(self.model, **options)
        # MuJoCo Warp prints a line per step when the (deliberately low) iteration caps of the DMC models are hit.
        self.solver.mjw_model.opt.warn_overflow = 0
        self._use_mujoco_c_inverse_weights()
        self.state = self.model.state()
        self._scratch = self.model.state()
        self.control = self.model.control()
        self.views = make_world_views(self.model, self.state, self.control)
        self._eval_fk = newton.eval_fk
        self.forward_kinematics()

    def _use_mujoco_c_inverse_weights(self) -> None:
        """Copy MuJoCo C's inverse-weight constants into the MuJoCo Warp model.

        MuJoCo Warp's ``set_const_0`` (run by ``SolverMuJoCo``) replaces a zero translational body inverse weight by
        the rotational one (e.g. a body spinning on a hinge through its centre of mass), where MuJoCo C keeps 0.
        Contacts on such a body then come out ~60x softer than in MuJoCo C (finger spin). The C values, compiled from
        the same exported model, make both libraries simulate the same constraints.
        """
        mj, mjw = self.solver.mj_model, self.solver.mjw_model
        for name in ("body_invweight0", "dof_invweight0", "tendon_invweight0"):
            target, source = getattr(mjw, name), np.asarray(getattr(mj, name), dtype=np.float32)
            if target.size:
                shape = target.numpy().shape
                target.assign(np.ascontiguousarray(np.broadcast_to(source.reshape(shape[1:]), shape)))

    @property
    def num_worlds(self) -> int:
        return self.model.world_count

    @property
    def control_dt(self) -> float:
        return self.dt * self.substeps

    def simulate(self) -> None:
        """Advance every world by ``substeps`` physics steps; the result is in ``self.state``."""
        states = (self.state, self._scratch)
        for k in range(self.substeps):
            self.solver.step(states[k % 2], states[(k + 1) % 2], self.control, None, self.dt)
        if self.substeps % 2 == 1:
            # An odd count ends in the scratch state; copy back (Python-side swaps are invisible to a graph).
            self.state.assign(self._scratch)

    def simulate_many(self, control_steps: int) -> None:
        """``control_steps`` calls of ``simulate`` (e.g. to let a model settle), replayed as a graph after the first."""
        if control_steps < 1:
            return
        self.simulate()
        device = wp.get_device(self.model.device)
        if control_steps > 1 and (device.is_cpu or device.is_mempool_enabled):
            with wp.ScopedCapture(device=device) as capture:
                self.simulate()
            for _ in range(control_steps - 1):
                wp.capture_launch(capture.graph)
        else:
            for _ in range(control_steps - 1):
                self.simulate()

    def forward_kinematics(self) -> None:
        """Recompute body poses and velocities of all worlds from ``state.joint_q``/``joint_qd``."""
        self._eval_fk(self.model, self.state.joint_q, self.state.joint_qd, self.state)

    def clear_solver_memory(self, world_mask) -> None:
        """Zero MuJoCo's per-world carry-over (warm start, controls, applied forces) where ``world_mask`` is true."""
        data = self.solver.mjw_data
        for values in (data.qacc_warmstart, data.qfrc_applied, data.ctrl, data.act):
            if values.shape[1] > 0:
                wp.launch(_clear_masked_rows, dim=values.shape, inputs=[world_mask, values], device=self.model.device)
        wp.launch(_clear_masked_wrenches, dim=data.xfrc_applied.shape, inputs=[world_mask, data.xfrc_applied],
                  device=self.model.device)  # fmt: skip

    def after_reset(self, world_mask) -> None:
        """Finish a reset whose new joint coordinates were written into ``state`` for the worlds in ``world_mask``."""
        self.clear_solver_memory(world_mask)
        self.forward_kinematics()
