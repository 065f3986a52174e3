"""Independent numpy references of the DMC observations and rewards, computed from MuJoCo C data (``MjData``).

They follow the Playground / dm_control task definitions directly (body frames ``xmat``, sites, sensors), so the
Warp kernels can be checked against MuJoCo's own kinematics. ``data`` must be forwarded (``mj_forward``) at the
state of interest; ``touch`` is the touch sensor data of the last physics step (finger only).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

GAUSS_SCALE = math.sqrt(-2.0 * math.log(0.1))  # gaussian tolerance with value 0.1 at the margin


def tol(x: float, lower: float, upper: float, margin: float = 0.0, sigmoid: str = "gaussian", vam: float = 0.1):
    if lower <= x <= upper:
        return 1.0
    if margin == 0.0:
        return 0.0
    d = (lower - x if x < lower else x - upper) / margin
    if sigmoid == "gaussian":
        return math.exp(-0.5 * (d * math.sqrt(-2.0 * math.log(vam))) ** 2)
    if sigmoid == "linear":
        s = d * (1.0 - vam)
        return 1.0 - s if abs(s) < 1.0 else 0.0
    if sigmoid == "quadratic":
        s = d * math.sqrt(1.0 - vam)
        return 1.0 - s * s if abs(s) < 1.0 else 0.0
    raise ValueError(sigmoid)


def small_control(u: np.ndarray) -> float:
    return (4.0 + float(np.mean([tol(float(x), 0, 0, 1.0, "quadratic", 0.0) for x in u]))) / 5.0


def _xmat(m, d, body):
    return d.xmat[m.body(body).id].reshape(3, 3)


def cartpole(m, d, ctrl, extra):
    r = _xmat(m, d, "pole_1")
    obs = [d.qpos[0], r[2, 2], r[0, 2], d.qvel[0], d.qvel[1]]
    reward = (
        ((r[2, 2] + 1) / 2)
        * (1 + tol(d.qpos[0], 0, 0, 2.0))
        / 2
        * small_control(ctrl)
        * (1 + tol(d.qvel[1], 0, 0, 5.0))
        / 2
    )
    return obs, reward


def pendulum(m, d, ctrl, extra):
    r = _xmat(m, d, "pole")
    return [r[2, 2], r[0, 2], d.qvel[0]], float(r[2, 2] >= math.cos(math.radians(8)))


def point_mass(m, d, ctrl, extra):
    dist = np.linalg.norm(d.geom_xpos[m.geom("target").id] - d.geom_xpos[m.geom("pointmass").id])
    return [*d.qpos, *d.qvel], tol(dist, 0, 0.015, 0.015) * small_control(ctrl)


def wall_path_length(p, target, a: float, b: float, inside_tol: float = 1e-5) -> float:
    """Shortest path from ``p`` to ``target`` (2-D) around the open box (-a, a) x (-b, b): Floyd-Warshall over the
    visibility graph of the two points and the box's four corners, a segment being visible when none of 2001 points
    along it lies inside the box shrunk by ``inside_tol`` (a mass pressed into a soft wall sits that little inside)."""
    nodes = [np.asarray(p, float), np.asarray(target, float)] + [np.array([x, y]) for x in (-a, a) for y in (-b, b)]
    t = np.linspace(0.0, 1.0, 2001)[:, None]

    def visible(u, v):
        pts = u + t * (v - u)
        return not np.any((np.abs(pts[:, 0]) < a - inside_tol) & (np.abs(pts[:, 1]) < b - inside_tol))

    n = len(nodes)
    dist = np.full((n, n), np.inf)
    for i in range(n):
        for j in range(n):
            if i == j or visible(nodes[i], nodes[j]):
                dist[i, j] = np.linalg.norm(nodes[i] - nodes[j])
    for k in range(n):
        dist = np.minimum(dist, dist[:, k : k + 1] + dist[k : k + 1, :])
    return float(dist[0, 1])


def point_mass_wall(m, d, ctrl, extra):
    """(near + progress) / 2 * small_control: near, point_mass's term; progress, linear in the path length around the
    wall grown by the mass's radius, 0 at 1 m beyond the target's radius."""
    radius = m.geom_size[m.geom("pointmass").id][0]
    half = m.geom_size[m.geom("wall").id][:2] + radius
    target = d.geom_xpos[m.geom("target").id][:2]
    pos = d.geom_xpos[m.geom("pointmass").id][:2]
    near = tol(float(np.linalg.norm(target - pos)), 0, 0.015, 0.015)
    progress = tol(wall_path_length(pos, target, *half), 0, 0.015, 1.0, "linear", 0.0)
    return [*d.qpos, *d.qvel], (near + progress) / 2 * small_control(ctrl)


def ball_in_cup(m, d, ctrl, extra):
    delta = np.abs(d.site_xpos[m.site("target").id] - d.xpos[m.body("ball").id])[[0, 2]]
    half = m.site_size[m.site("target").id][[0, 2]] - m.geom_size[m.geom("ball").id][0]
    return [*d.qpos, *d.qvel], float(np.all(delta < half))


def finger_spin(m, d, ctrl, extra):
    tip = (d.site_xpos[m.site("tip").id] - d.xpos[m.body("spinner").id])[[0, 2]]
    touch = np.log1p(extra["touch"])
    return [d.qpos[0], d.qpos[1], *tip, *d.qvel, *touch], float(d.qvel[2] <= -15.0)


def reacher_easy(m, d, ctrl, extra):
    to_target = (d.geom_xpos[m.geom("target").id] - d.geom_xpos[m.geom("finger").id])[:2]
    radii = m.geom_size[m.geom("target").id][0] + m.geom_size[m.geom("finger").id][0]
    return [*d.qpos, *to_target, *d.qvel], float(np.linalg.norm(to_target) <= radii)


def acrobot(m, d, ctrl, extra):
    upper, lower = _xmat(m, d, "upper_arm"), _xmat(m, d, "lower_arm")
    dist = np.linalg.norm(d.site_xpos[m.site("target").id] - d.site_xpos[m.site("tip").id])
    obs = [upper[0, 2], lower[0, 2], upper[2, 2], lower[2, 2], *d.qvel]
    return obs, tol(dist, 0, m.site_size[m.site("target").id][0], 1.0)


def _com_x_velocity(m, d):
    mujoco.mj_subtreeVel(m, d)
    return d.subtree_linvel[m.body("torso").id][0]


def cheetah(m, d, ctrl, extra):
    return [*d.qpos[1:], *d.qvel], tol(_com_x_velocity(m, d), 10.0, math.inf, 10.0, "linear", 0.0)


def walker(m, d, ctrl, extra):
    bodies = ("torso", "right_thigh", "right_leg", "right_foot", "left_thigh", "left_leg", "left_foot")
    frames = [_xmat(m, d, b) for b in bodies]
    obs = [v for r in frames for v in (r[0, 0], r[0, 2])] + [frames[0][2, 2], *d.qvel]
    standing = tol(d.xpos[m.body("torso").id][2], 1.2, math.inf, 0.6)
    stand = (3 * standing + (1 + frames[0][2, 2]) / 2) / 4
    move = tol(_com_x_velocity(m, d), 1.0, math.inf, 0.5, "linear", 0.5)
    return obs, stand * (5 * move + 1) / 6


REFERENCES = {
    "cartpole_balance": cartpole,
    "cartpole_swingup": cartpole,
    "pendulum_swingup": pendulum,
    "point_mass": point_mass,
    "point_mass_wall": point_mass_wall,
    "ball_in_cup": ball_in_cup,
    "finger_spin": finger_spin,
    "reacher_easy": reacher_easy,
    "acrobot_swingup": acrobot,
    "cheetah_run": cheetah,
    "walker_walk": walker,
}
