"""Finger spin (Playground ``FingerSpin``): flick a hinged spinner into fast rotation.

Observation (9): proximal and distal joint angles (MuJoCo qpos, i.e. including the proximal ``ref`` of -90 deg),
spinner tip position relative to the spinner frame (x, z), joint velocities (3), log(1 + touch) of the two fingertip
touch sensors. Reward: 1 when the spinner hinge velocity is <= -15 rad/s, else 0.
Reset: proximal and distal U(-110, 110) deg, spinner U(-pi, pi), zero velocity.

The touch sensors follow MuJoCo's ``touch``: the summed normal force of every constraint contact of the fingertip
body whose normal ray, cast from the contact point, hits the sensor's ellipsoid site. They are read from the
solver's contact data of the last physics substep (as MuJoCo's sensor data is); right after a reset they are 0.
"""

from __future__ import annotations

import math

from refpo_warp.tasks.dmc.task import DmcTask
from refpo_warp.utils.warp_setup import wp

SPIN_VELOCITY = wp.constant(15.0)
TIP = wp.constant(wp.vec3(0.0, 0.0, 0.13))  # tip site in the spinner frame
TOUCH_TOP = wp.constant(wp.vec3(0.01, 0.0, -0.17))  # touch sites in the distal frame
TOUCH_BOTTOM = wp.constant(wp.vec3(-0.01, 0.0, -0.17))
TOUCH_SIZE = wp.constant(wp.vec3(0.025, 0.03, 0.025))  # ellipsoid semi-axes of both touch sites


@wp.func
def ray_hits_ellipsoid(origin: wp.vec3, direction: wp.vec3, size: wp.vec3) -> bool:
    """Whether the half-line origin + t * direction (t >= 0) meets the axis-aligned ellipsoid ``size`` at 0."""
    p = wp.cw_div(origin, size)
    v = wp.cw_div(direction, size)
    a = wp.dot(v, v)
    b = wp.dot(p, v)
    c = wp.dot(p, p) - 1.0
    det = b * b - a * c
    if det < 0.0 or a <= 0.0:
        return False
    return (-b + wp.sqrt(det)) / a >= 0.0  # the far root is >= 0 whenever any intersection lies ahead


@wp.kernel
def clear_touch(touch: wp.array2d(dtype=float)):
    i, j = wp.tid()
    touch[i, j] = 0.0


@wp.kernel
def accumulate_touch(
    nacon: wp.array(dtype=int),
    contact_pos: wp.array(dtype=wp.vec3),
    contact_frame: wp.array(dtype=wp.mat33),
    contact_dim: wp.array(dtype=int),
    contact_geom: wp.array(dtype=wp.vec2i),
    contact_efc_address: wp.array2d(dtype=int),
    contact_worldid: wp.array(dtype=int),
    efc_force: wp.array2d(dtype=float),
    geom_bodyid: wp.array(dtype=int),
    body_xpos: wp.array2d(dtype=wp.vec3),
    body_xmat: wp.array2d(dtype=wp.mat33),
    pyramidal: int,
    distal: int,
    touch: wp.array2d(dtype=float),
):
    c = wp.tid()
    if c >= nacon[0]:
        return
    b0 = geom_bodyid[contact_geom[c][0]]
    b1 = geom_bodyid[contact_geom[c][1]]
    address = contact_efc_address[c, 0]
    if address < 0 or (b0 != distal and b1 != distal):
        return
    w = contact_worldid[c]
    force = efc_force[w, address]
    if pyramidal != 0:  # the normal force is the sum over the pyramid's edges
        for k in range(1, 2 * (contact_dim[c] - 1)):
            force += efc_force[w, contact_efc_address[c, k]]
    if force <= 0.0:
        return
    frame = contact_frame[c]
    ray = wp.vec3(frame[0, 0], frame[0, 1], frame[0, 2])  # normal, pointing from geom 0 to geom 1
    if b1 == distal:
        ray = -ray
    rot = body_xmat[w, distal]
    local_pos = wp.transpose(rot) * (contact_pos[c] - body_xpos[w, distal])
    local_ray = wp.transpose(rot) * ray
    if ray_hits_ellipsoid(local_pos - TOUCH_TOP, local_ray, TOUCH_SIZE):
        wp.atomic_add(touch, w, 0, force)
    if ray_hits_ellipsoid(local_pos - TOUCH_BOTTOM, local_ray, TOUCH_SIZE):
        wp.atomic_add(touch, w, 1, force)


@wp.kernel
def finger_reward(joint_qd: wp.array2d(dtype=float), rewards: wp.array(dtype=float)):
    i = wp.tid()
    rewards[i] = wp.where(joint_qd[i, 2] <= -SPIN_VELOCITY, 1.0, 0.0)


@wp.kernel
def finger_obs(
    joint_q: wp.array2d(dtype=float),
    joint_qd: wp.array2d(dtype=float),
    coord_ref: wp.array(dtype=float),
    body_q: wp.array2d(dtype=wp.transform),
    spinner: int,
    touch: wp.array2d(dtype=float),
    reset_mask: wp.array(dtype=wp.bool),
    obs: wp.array2d(dtype=float),
):
    i = wp.tid()
    tip = wp.transform_vector(body_q[i, spinner], TIP)
    obs[i, 0] = joint_q[i, 0] + coord_ref[0]
    obs[i, 1] = joint_q[i, 1] + coord_ref[1]
    obs[i, 2] = tip[0]
    obs[i, 3] = tip[2]
    for j in range(3):
        obs[i, 4 + j] = joint_qd[i, j]
    fresh = reset_mask[i]
    obs[i, 7] = wp.where(fresh, 0.0, wp.log(1.0 + touch[i, 0]))
    obs[i, 8] = wp.where(fresh, 0.0, wp.log(1.0 + touch[i, 1]))


class FingerSpin(DmcTask):
    model_file = "finger_spin.xml"
    substeps = 4  # ctrl_dt 0.02, sim_dt 0.005
    num_obs = 9
    num_actions = 2
    reward_summary = "1 when the spinner turns at <= -15 rad/s"
    reset_summary = "fingers U(-110,110) deg, spinner U(-pi,pi)"

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.spinner = self.views.body_index("spinner")
        newton_distal = self.views.body_index("distal")
        mj_to_newton = sim.solver.mjc_body_to_newton.numpy()[0]
        self.mj_distal = int(list(mj_to_newton).index(newton_distal))
        self.touch = wp.zeros((self.num_envs, 2), dtype=float, device=self.device)
        self.pyramidal = int(sim.solver.mj_model.opt.cone == 0)
        lower, upper = self.joint_limits()  # the two finger joints within their limits (Newton coordinates)
        lower[2], upper[2] = -math.pi, math.pi  # the spinner anywhere
        self.reset_ranges = self.uniform_ranges(lower, upper)

    def reset(self, mask) -> None:
        self.reset_uniform_joints(mask, self.reset_ranges)

    def after_physics(self) -> None:
        d, m = self.sim.solver.mjw_data, self.sim.solver.mjw_model
        wp.launch(clear_touch, dim=self.touch.shape, inputs=[self.touch], device=self.device)
        con = d.contact
        wp.launch(
            accumulate_touch,
            dim=con.pos.shape[0],
            inputs=[
                d.nacon,
                con.pos,
                con.frame,
                con.dim,
                con.geom,
                con.efc_address,
                con.worldid,
                d.efc.force,
                m.geom_bodyid,
                d.xpos,
                d.xmat,
                self.pyramidal,
                self.mj_distal,
                self.touch,
            ],
            device=self.device,
        )

    def reward(self, rewards) -> None:
        self.launch(finger_reward, [self.views.joint_qd, rewards])

    def observe(self, obs, reset_mask) -> None:
        v = self.views
        self.launch(
            finger_obs, [v.joint_q, v.joint_qd, v.coord_ref, v.body_q, self.spinner, self.touch, reset_mask, obs]
        )
