"""A Newton model of N identical MJCF worlds stepped by ``SolverMuJoCo`` (MuJoCo Warp), graph-capture friendly.

``MuJoCoWorlds`` owns the model, the solver, one canonical ``state`` (every view and kernel reads and writes it) and
a scratch state for the solver's ping-pong. ``simulate()`` runs the physics substeps of one control step and always
leaves the result in ``state``, so a captured graph replays correctly for any substep count. Resets write joint
coordinates into ``state`` (the solver copies them into MuJoCo at its next step), then ``after_reset`` clears the
solver's per-world memory (``SolverMuJoCo.reset``: warm start, controls, applied forces) and recomputes body poses by
forward kinematics.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from refpo_warp.sim.mjcf_worlds import build_mjcf_worlds, mjcf_timestep
from refpo_warp.sim.world_views import make_world_views
from refpo_warp.utils.warp_setup import wp


@wp.kernel
def _articulations_of_worlds(
    world_mask: wp.array(dtype=wp.bool), articulation_world: wp.array(dtype=wp.int32), out: wp.array(dtype=wp.bool)
):
    a = wp.tid()
    out[a] = world_mask[articulation_world[a]]


class MuJoCoWorlds:
    """``num_worlds`` copies of an MJCF model on one Warp device, advanced ``substeps`` MuJoCo steps per ``simulate``.

    Args:
        mjcf_path: The MJCF file; its ``<option timestep>`` is the physics step.
        num_worlds: Number of worlds.
        device: Warp device name.
        substeps: Physics steps per control step.
        solver_options: Extra ``SolverMuJoCo`` keyword arguments (e.g. ``iterations``); the file's options otherwise.
        physics_dt: Physics step in seconds; default: the file's ``<option timestep>``.
        warn_overflow: Let MuJoCo Warp print a line when a capacity or iteration cap is hit.
        build_options: Keyword arguments of ``build_mjcf_worlds`` (``edit_world``, ``ground``, ``add_mjcf`` options).
    """

    def __init__(
        self,
        mjcf_path: str | Path,
        num_worlds: int,
        device: str,
        substeps: int = 1,
        solver_options: dict | None = None,
        physics_dt: float | None = None,
        warn_overflow: bool = True,
        **build_options,
    ) -> None:
        import newton

        if substeps < 1:
            raise ValueError(f"substeps must be >= 1, got {substeps}")
        self.mjcf_path = Path(mjcf_path)
        self.dt = physics_dt or mjcf_timestep(self.mjcf_path)
        self.substeps = int(substeps)
        self.model = build_mjcf_worlds(self.mjcf_path, num_worlds, device, **build_options)
        # Every movable root would otherwise get an inactive weld constraint (only needed for kinematic switching).
        options = {"kinematic_switchable_roots": False, **(solver_options or {})}
        self.solver = newton.solvers.SolverMuJoCo(self.model, **options)
        if not warn_overflow:
            self.solver.mjw_model.opt.warn_overflow = 0
        self._use_mujoco_c_inverse_weights()
        self.state = self.model.state()
        self._scratch = self.model.state()
        self.control = self.model.control()
        self.views = make_world_views(self.model, self.state, self.control)
        # SolverMuJoCo.reset takes a (worlds + 1) mask (the last entry is the global world); envs write the first W.
        self._world_mask = wp.zeros(num_worlds + 1, dtype=wp.bool, device=self.model.device)
        self.reset_mask = self._world_mask[:num_worlds]
        self._articulation_mask = wp.zeros(self.model.articulation_count, dtype=wp.bool, device=self.model.device)
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
                shape = target.numpy().shape  # with the vector dimension of vec2/vec3 entries
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

    def after_reset(self, world_mask=None) -> None:
        """Finish a reset whose new joint coordinates were written into ``state`` for the worlds in ``world_mask``
        (default: ``reset_mask``, which needs no copy): clear their solver memory, then recompute body poses."""
        if world_mask is not None and world_mask.ptr != self.reset_mask.ptr:
            wp.copy(self.reset_mask, world_mask)
        self.solver.reset(self.state, world_mask=self._world_mask, flags=0)
        # Forward kinematics of the reset worlds only (the solver's step already did it for the others); the FK mask
        # is per articulation, and a world may hold several (e.g. ball and cup).
        wp.launch(
            _articulations_of_worlds,
            dim=self.model.articulation_count,
            inputs=[self.reset_mask, self.model.articulation_world, self._articulation_mask],
            device=self.model.device,
        )
        self._eval_fk(self.model, self.state.joint_q, self.state.joint_qd, self.state, mask=self._articulation_mask)
