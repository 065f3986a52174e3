"""Layout of the 934-dim tracking observation and the goal-conditioning masks of the three regimes.

Self part (358): root height (1); body positions relative to the root, root excluded (23 x 3); body rotations as
tan-norm 6D (24 x 6); linear velocities (24 x 3); angular velocities (24 x 3).
Task part (576), in blocks over the 24 bodies like the reference implementation: position difference ref - sim
(24 x 3), rotation difference (24 x 6), velocity difference (24 x 3), angular-velocity difference (24 x 3),
reference position relative to the simulated root (24 x 3), reference rotation (24 x 6).
Everything is expressed in the root's heading frame.

Conditioning (the policy sees ``obs * mask``; the critic sees the full observation): ``all`` hides nothing;
``root_hands`` keeps the self part and only the Pelvis, L_Wrist and R_Wrist entries of the position-difference and
reference-position blocks; ``root`` keeps the self part and only the Pelvis entries of those two blocks.
"""

from __future__ import annotations

import numpy as np

from refpo_warp.motion import skeleton as sk

NB = sk.NUM_BODIES
# (name, width) of each block, in order.
BLOCKS: tuple[tuple[str, int], ...] = (
    ("root_height", 1),
    ("body_pos", 3 * (NB - 1)),
    ("body_rot", 6 * NB),
    ("body_vel", 3 * NB),
    ("body_angvel", 3 * NB),
    ("diff_pos", 3 * NB),
    ("diff_rot", 6 * NB),
    ("diff_vel", 3 * NB),
    ("diff_angvel", 3 * NB),
    ("ref_pos", 3 * NB),
    ("ref_rot", 6 * NB),
)
OFFSET = dict(zip([b[0] for b in BLOCKS], np.cumsum([0] + [b[1] for b in BLOCKS[:-1]]).tolist()))
SELF_DIM = OFFSET["diff_pos"]  # 358
OBS_DIM = sum(b[1] for b in BLOCKS)  # 934

CONDITIONING_REGIMES = tuple(sk.CONDITIONED_BODIES)  # ("all", "root_hands", "root")


def block_slice(name: str, body: int | None = None) -> slice:
    """Observation indices of a block, or of one body's entries in it (``body_pos`` has no root entry)."""
    width = dict(BLOCKS)[name]
    start = OFFSET[name]
    if body is None:
        return slice(start, start + width)
    per_body = width // (NB - 1 if name == "body_pos" else NB)
    index = body - 1 if name == "body_pos" else body
    if name == "body_pos" and body == 0:
        raise ValueError("body_pos excludes the root body")
    return slice(start + per_body * index, start + per_body * (index + 1))


def conditioning_mask(regime: str) -> np.ndarray:
    """The (934,) 0/1 mask of the policy observation for a conditioning regime."""
    if regime not in sk.CONDITIONED_BODIES:
        raise ValueError(f"Unknown conditioning regime '{regime}'; valid: {', '.join(CONDITIONING_REGIMES)}")
    mask = np.zeros(OBS_DIM, dtype=np.float32)
    if regime == "all":
        mask[:] = 1.0
        return mask
    mask[:SELF_DIM] = 1.0
    for name in sk.CONDITIONED_BODIES[regime]:
        body = sk.body_index(name)
        mask[block_slice("diff_pos", body)] = 1.0
        mask[block_slice("ref_pos", body)] = 1.0
    return mask
