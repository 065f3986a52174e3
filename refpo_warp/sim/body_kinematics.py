"""Whole-world body quantities computed from per-world body views (see ``WorldViews``)."""

from __future__ import annotations

from refpo_warp.utils.warp_setup import wp


@wp.func
def world_com_velocity(
    body_qd: wp.array2d(dtype=wp.spatial_vector), body_mass: wp.array2d(dtype=float), world: int
) -> wp.vec3:
    """Linear velocity of the centre of mass of all bodies of ``world``: sum(m_b v_b) / sum(m_b).

    Equals MuJoCo's ``subtreelinvel`` sensor of a root body whose subtree is the whole world (e.g. a walker's torso).
    """
    momentum = wp.vec3(0.0)
    mass = float(0.0)
    for b in range(body_qd.shape[1]):
        momentum += body_mass[world, b] * wp.spatial_top(body_qd[world, b])
        mass += body_mass[world, b]
    return momentum / wp.max(mass, 1.0e-12)
