"""Point mass around a wall (this project's, after point_mass): reach a target behind a wall, passing it left or right.

The DMC point mass (``point_mass.xml``'s sphere, joints, motors and 0.02 s control step) in ``point_mass_wall.xml``:
contacts on, and a frictionless box across the middle of the arena, centred on the origin along y (half-sizes
``wall_half_thickness`` x ``wall_half_length``, set from the env options after the import). The mass starts at rest
at (-0.2 + U(-s, s), U(-s, s)) (s = ``start_spread``) on the wall's axis, the target (radius 0.015) sits at (0.2, 0)
on the other side; both ends of the wall leave a gap, so the left (+y) and right (-y) ways are mirror images.

Episode metrics (``Episode/<name>``, ``eval.json``'s ``<name>_mean``): ``success``, the mass's centre within the
target's radius after the episode's last step; ``went_left`` / ``went_right``, the sign of y where the centre first
had x > 0 (past the wall's middle; both 0 if it never did).

Observation (4): x, y positions and velocities (point_mass's; the target and the wall are fixed).
Reward, max 1: (near + progress) / 2 * small_control, with
near = tolerance(|p - target|, bounds=(0, 0.015), margin=0.015) (point_mass's Gaussian term, 0.1 at the margin),
progress = tolerance(path, bounds=(0, 0.015), margin=1, linear, 0 at the margin) = 1 - (path - 0.015) beyond the
radius, where path is the length of the shortest path of the mass's centre to the target around the wall grown by
the mass's radius (straight where the target is in sight, else over the nearer pair of corners), and
small_control = (4 + mean_j tolerance(u_j, margin=1, 0, quadratic)) / 5. The path length is the same by both ways
on the axis (y = 0 behind the wall), so the reward favours neither; it also has no local optimum against the wall
(a Euclidean distance term would: pressed against the wall's middle the mass is nearer the target than anywhere on
the way around).
"""

from __future__ import annotations

import numpy as np

from refpo_warp.tasks.dmc.point_mass_wall_cfg import PATH_MARGIN, START_X, TARGET_RADIUS, TARGET_X
from refpo_warp.tasks.dmc.rewards import DEFAULT_VALUE_AT_MARGIN, GAUSSIAN, LINEAR, small_control, tolerance
from refpo_warp.tasks.dmc.task import DmcTask
from refpo_warp.utils.warp_setup import wp

TARGET = wp.constant(wp.vec2(TARGET_X, 0.0))
RADIUS = wp.constant(TARGET_RADIUS)
MARGIN = wp.constant(PATH_MARGIN)


@wp.func
def sight_blocked(p: wp.vec2, q: wp.vec2, a: float, b: float) -> bool:
    """Whether the segment p-q passes through the open box (-a, a) x (-b, b) (grazing a face or corner does not)."""
    t0 = float(0.0)
    t1 = float(1.0)
    d = q - p
    for k in range(2):
        half = wp.where(k == 0, a, b)
        if wp.abs(d[k]) < 1.0e-12:
            if wp.abs(p[k]) >= half:
                return False
        else:
            ta = (-half - p[k]) / d[k]
            tb = (half - p[k]) / d[k]
            t0 = wp.max(t0, wp.min(ta, tb))
            t1 = wp.min(t1, wp.max(ta, tb))
    return t0 < t1


@wp.func
def path_length(p: wp.vec2, a: float, b: float) -> float:
    """Shortest path from p to the target around the box (-a, a) x (-b, b): straight where the target is in sight,
    else the shorter of the two ways, each over the far corner (a, +-b) when p sees it, else over both corners."""
    if not sight_blocked(p, TARGET, a, b):
        return wp.length(TARGET - p)
    best = float(1.0e9)
    for k in range(2):
        s = wp.where(k == 0, 1.0, -1.0)
        near = wp.vec2(-a, s * b)
        far = wp.vec2(a, s * b)
        tail = wp.length(TARGET - far)
        way = wp.length(far - p) + tail
        if sight_blocked(p, far, a, b):
            way = wp.length(near - p) + 2.0 * a + tail
        best = wp.min(best, way)
    return best


@wp.kernel
def point_mass_wall_reward(
    body_q: wp.array2d(dtype=wp.transform),
    ctrl: wp.array2d(dtype=float),
    mass: int,
    a: float,
    b: float,
    rewards: wp.array(dtype=float),
):
    i = wp.tid()
    q = wp.transform_get_translation(body_q[i, mass])
    p = wp.vec2(q[0], q[1])
    near = tolerance(wp.length(TARGET - p), 0.0, RADIUS, RADIUS, GAUSSIAN, DEFAULT_VALUE_AT_MARGIN)
    progress = tolerance(path_length(p, a, b), 0.0, RADIUS, MARGIN, LINEAR, 0.0)
    control = 0.5 * (small_control(ctrl[i, 0]) + small_control(ctrl[i, 1]))
    rewards[i] = 0.5 * (near + progress) * control


@wp.kernel
def point_mass_wall_metrics(
    body_q: wp.array2d(dtype=wp.transform),
    mass: int,
    way: wp.array(dtype=int),
    success: wp.array(dtype=float),
    went_left: wp.array(dtype=float),
    went_right: wp.array(dtype=float),
):
    i = wp.tid()
    q = wp.transform_get_translation(body_q[i, mass])
    if way[i] == 0 and q[0] > 0.0:
        way[i] = wp.where(q[1] > 0.0, 1, -1)
    success[i] = wp.where(wp.length(TARGET - wp.vec2(q[0], q[1])) <= RADIUS, 1.0, 0.0)
    went_left[i] = wp.where(way[i] == 1, 1.0, 0.0)
    went_right[i] = wp.where(way[i] == -1, 1.0, 0.0)


@wp.kernel
def forget_way(mask: wp.array(dtype=wp.bool), way: wp.array(dtype=int)):
    i = wp.tid()
    if mask[i]:
        way[i] = 0


@wp.kernel
def point_mass_wall_obs(
    joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float), obs: wp.array2d(dtype=float)
):
    i = wp.tid()
    for j in range(2):
        obs[i, j] = joint_q[i, j]
        obs[i, 2 + j] = joint_qd[i, j]


class PointMassWall(DmcTask):
    render_view, render_distance = (-90.0, 90.0), 1.1  # planar in x-y: the whole arena seen from above
    model_file = "point_mass_wall.xml"
    substeps = 1  # ctrl_dt = sim_dt = 0.02 (point_mass's)
    num_obs = 4
    num_actions = 2
    reward_summary = "(point_mass's term + 1 - path length around the wall) / 2 x small_control"
    reset_summary = "x -.2 + U(-s,s), y U(-s,s), s = .02"
    episode_metrics = ("success", "went_left", "went_right")

    def __init__(self, sim, cfg, rng) -> None:
        super().__init__(sim, cfg, rng)
        self.mass = self.views.body_index("pointmass")
        self.a, self.b = cfg.wall_box()
        s = cfg.start_spread
        self.reset_ranges = self.uniform_ranges([START_X - s, -s], [START_X + s, s])
        self.way = wp.zeros(self.num_envs, dtype=int, device=self.device)  # +1 left, -1 right, 0 not yet past x = 0

    def _wall_shapes(self) -> list[int]:
        walls = [k for k, label in enumerate(self.sim.model.shape_label) if label.endswith("/wall")]
        if len(walls) != self.num_envs:
            raise ValueError(f"{self.model_file}: expected one geom 'wall' per world, found {len(walls)}")
        return walls

    def prepare(self) -> None:
        """Give the wall of every world the options' size (the file has the defaults): Newton's shape scale (a box's
        half-sizes), which the solver copies into MuJoCo Warp's geom sizes and bounding volumes."""
        import newton

        model, walls = self.sim.model, self._wall_shapes()
        scale = model.shape_scale.numpy()
        scale[walls, 0] = self.cfg.wall_half_thickness
        scale[walls, 1] = self.cfg.wall_half_length
        model.shape_scale.assign(scale)
        self.sim.solver.notify_model_changed(newton.ModelFlags.SHAPE_PROPERTIES)

    def reset(self, mask) -> None:
        self.reset_uniform_joints(mask, self.reset_ranges)
        self.launch(forget_way, [mask, self.way])

    def reward(self, rewards) -> None:
        v = self.views
        self.launch(point_mass_wall_reward, [v.body_q, v.ctrl, self.mass, self.a, self.b, rewards])

    def record_metrics(self, metrics: dict) -> None:
        m = metrics
        self.launch(
            point_mass_wall_metrics,
            [self.views.body_q, self.mass, self.way, m["success"], m["went_left"], m["went_right"]],
        )

    def observe(self, obs, reset_mask) -> None:
        self.launch(point_mass_wall_obs, [self.views.joint_q, self.views.joint_qd, obs])

    def wall_half_sizes(self) -> np.ndarray:
        """The wall's (x, y, z) half-sizes that MuJoCo Warp collides, one row per world (tests)."""
        solver = self.sim.solver
        names = [solver.mj_model.geom(k).name for k in range(solver.mj_model.ngeom)]
        geom = next(k for k, name in enumerate(names) if name.rsplit("/", 1)[-1].startswith("wall"))
        return solver.mjw_model.geom_size.numpy()[:, geom]
