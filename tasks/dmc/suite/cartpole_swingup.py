"""Cartpole swing-up (Playground ``CartpoleSwingup``): swing a hanging pole up and balance it (dense reward).

The balance task's model, reward and observation (``cartpole_balance.py``) with another reset: cart 0.01 N(0,1),
pole pi + 0.01 N(0,1), velocities 0.01 N(0,1).
"""

from __future__ import annotations

from refpo_warp.tasks.dmc.suite.cartpole_balance import CartpoleBalance


class CartpoleSwingup(CartpoleBalance):
    swing_up = 1
    reset_summary = "cart .01 N, pole pi + .01 N, vel .01 N"
