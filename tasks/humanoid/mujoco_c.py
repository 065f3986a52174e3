"""The humanoid's MuJoCo C twin: the model ``HumanoidSim`` compiled, stepped by the MuJoCo C library.

Used as the speed anchor of ``refpo bench humanoid`` and by the agreement test. The MjModel is the one Newton's
``SolverMuJoCo`` compiled from ``smpl_humanoid.xml`` for MuJoCo Warp (one world: the humanoid and the ground plane),
so both libraries see the same bodies, geoms, contact filtering, joint limits, PD actuators (Newton exports each
hinge's joint target gains as a MuJoCo position actuator ``kp``/``kv`` with the 500 N m effort limit as the joint's
actuator force range) and solver options (integrator, Newton solver, iterations, line-search iterations, tolerance,
cone). Only the timestep needs setting: Newton passes it to MuJoCo Warp at every step.

States convert from Newton's coordinates: the root quaternion is xyzw in Newton and wxyz in MuJoCo; Newton's free
joint velocity is the root COM's linear velocity and the world angular velocity, MuJoCo's the body origin's linear
velocity and the angular velocity in the body frame. The 69 hinge angles and rates are the same numbers.
"""

from __future__ import annotations

import copy

import numpy as np

from refpo_warp.motion.rotations import quat_rotate


def c_model(sim):
    """A MuJoCo C copy of the model ``sim`` (a ``HumanoidSim``) simulates, with the physics timestep set."""
    model = copy.copy(sim.solver.mj_model)
    model.opt.timestep = sim.dt
    return model


def solver_settings(model) -> dict:
    """The MuJoCo options that decide the cost and result of a step (for printing and comparing)."""
    import mujoco

    o = model.opt
    return {
        "timestep": float(o.timestep),
        "integrator": mujoco.mjtIntegrator(o.integrator).name,
        "solver": mujoco.mjtSolver(o.solver).name,
        "iterations": int(o.iterations),
        "ls_iterations": int(o.ls_iterations),
        "tolerance": float(o.tolerance),
        "cone": mujoco.mjtCone(o.cone).name,
        "jacobian": mujoco.mjtJacobian(o.jacobian).name,
    }


def newton_to_mujoco(joint_q: np.ndarray, joint_qd: np.ndarray, root_com: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo ``qpos``/``qvel`` (N, 76)/(N, 75) of Newton ``joint_q``/``joint_qd``; ``root_com`` is the pelvis COM
    offset in its body frame."""
    q = np.asarray(joint_q, np.float64)
    qd = np.asarray(joint_qd, np.float64)
    rot = q[:, 3:7]  # xyzw
    omega = qd[:, 3:6]
    v_origin = qd[:, :3] - np.cross(omega, quat_rotate(rot, np.asarray(root_com, np.float64)))
    omega_body = quat_rotate(rot * np.array([-1.0, -1.0, -1.0, 1.0]), omega)
    qpos = np.concatenate([q[:, :3], q[:, 6:7], q[:, 3:6], q[:, 7:]], axis=1)
    qvel = np.concatenate([v_origin, omega_body, qd[:, 6:]], axis=1)
    return qpos, qvel


def c_states(model, sim) -> np.ndarray:
    """MuJoCo full-physics states (N, nstate) of every world of ``sim`` (warm start and actuator state zero)."""
    import mujoco

    qpos, qvel = newton_to_mujoco(sim.joint_q.numpy(), sim.joint_qd.numpy(), sim.body_com.numpy()[0])
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    data = mujoco.MjData(model)
    states = np.zeros((len(qpos), mujoco.mj_stateSize(model, spec)))
    for i in range(len(qpos)):
        data.qpos[:], data.qvel[:] = qpos[i], qvel[i]
        mujoco.mj_getState(model, data, states[i], spec)
    return states


def rollout(model, states: np.ndarray, targets: np.ndarray, substeps: int, data=None) -> np.ndarray:
    """Roll every world from ``states`` through PD targets ``targets`` (N, T, 69), each held for ``substeps``
    physics steps (one thread); returns the states after each physics step (N, T * substeps, nstate)."""
    import mujoco
    from mujoco import rollout as mj_rollout

    controls = np.repeat(np.asarray(targets, np.float64), substeps, axis=1)
    data = data if data is not None else mujoco.MjData(model)
    out, _ = mj_rollout.rollout(model, data, states, controls, nstep=controls.shape[1])
    return out
