"""Detect worlds whose physics state stopped being finite (a diverged MuJoCo step), so they can be reset."""

from __future__ import annotations

from refpo_warp.utils.warp_setup import wp


@wp.func
def world_state_finite(joint_q: wp.array2d(dtype=float), joint_qd: wp.array2d(dtype=float), world: int) -> bool:
    """True when every generalized position and velocity of ``world`` is finite (no NaN or inf)."""
    for i in range(joint_q.shape[1]):
        if not wp.isfinite(joint_q[world, i]):
            return False
    for i in range(joint_qd.shape[1]):  # noqa: SIM110  (Warp function code: Warp compiles no generator or all())
        if not wp.isfinite(joint_qd[world, i]):
            return False
    return True
