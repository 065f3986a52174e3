"""The dm_control ``tolerance`` reward primitive as Warp functions.

``tolerance(x, lower, upper, margin, sigmoid, value_at_margin)`` is 1 when ``lower <= x <= upper``. Outside the
bounds it is 0 when ``margin == 0``; otherwise it decays with the distance ``d`` to the nearest bound, measured in
margins, along ``sigmoid(d)``, which equals ``value_at_margin`` at ``d = 1``. The sigmoid shapes (``v`` is
``value_at_margin``):

- GAUSSIAN: ``exp(-0.5 (d s)^2)``, ``s = sqrt(-2 ln v)``
- HYPERBOLIC: ``1 / cosh(d s)``, ``s = arccosh(1 / v)``
- LONG_TAIL: ``1 / ((d s)^2 + 1)``, ``s = sqrt(1 / v - 1)``
- RECIPROCAL: ``1 / (|d| s + 1)``, ``s = 1 / v - 1``
- COSINE: ``(1 + cos(pi d s)) / 2`` for ``|d s| < 1`` else 0, ``s = arccos(2 v - 1) / pi``
- LINEAR: ``1 - d s`` for ``|d s| < 1`` else 0, ``s = 1 - v``
- QUADRATIC: ``1 - (d s)^2`` for ``|d s| < 1`` else 0, ``s = sqrt(1 - v)``
- TANH_SQUARED: ``1 - tanh(d s)^2``, ``s = arctanh(sqrt(1 - v))``

Bounds may be infinite (``wp.inf``). dm_control's default ``value_at_margin`` is 0.1 (``DEFAULT_VALUE_AT_MARGIN``).
"""

from __future__ import annotations

from refpo_warp.utils.warp_setup import wp

GAUSSIAN = wp.constant(0)
HYPERBOLIC = wp.constant(1)
LONG_TAIL = wp.constant(2)
RECIPROCAL = wp.constant(3)
COSINE = wp.constant(4)
LINEAR = wp.constant(5)
QUADRATIC = wp.constant(6)
TANH_SQUARED = wp.constant(7)
DEFAULT_VALUE_AT_MARGIN = wp.constant(0.1)

SIGMOIDS = {
    "gaussian": 0,
    "hyperbolic": 1,
    "long_tail": 2,
    "reciprocal": 3,
    "cosine": 4,
    "linear": 5,
    "quadratic": 6,
    "tanh_squared": 7,
}


@wp.func
def sigmoid(d: float, value_at_1: float, kind: int) -> float:
    """The sigmoid ``kind`` at distance ``d`` (in margins), scaled so that ``sigmoid(1) == value_at_1``."""
    if kind == GAUSSIAN:
        s = wp.sqrt(-2.0 * wp.log(value_at_1))
        return wp.exp(-0.5 * (d * s) * (d * s))
    if kind == HYPERBOLIC:
        y = 1.0 / value_at_1
        s = wp.log(y + wp.sqrt(y * y - 1.0))  # arccosh(y)
        return 1.0 / wp.cosh(d * s)
    if kind == LONG_TAIL:
        s = wp.sqrt(1.0 / value_at_1 - 1.0)
        return 1.0 / ((d * s) * (d * s) + 1.0)
    if kind == RECIPROCAL:
        s = 1.0 / value_at_1 - 1.0
        return 1.0 / (wp.abs(d) * s + 1.0)
    if kind == COSINE:
        sd = d * wp.acos(2.0 * value_at_1 - 1.0) / wp.pi
        return wp.where(wp.abs(sd) < 1.0, 0.5 * (1.0 + wp.cos(wp.pi * sd)), 0.0)
    if kind == LINEAR:
        sd = d * (1.0 - value_at_1)
        return wp.where(wp.abs(sd) < 1.0, 1.0 - sd, 0.0)
    if kind == QUADRATIC:
        sd = d * wp.sqrt(1.0 - value_at_1)
        return wp.where(wp.abs(sd) < 1.0, 1.0 - sd * sd, 0.0)
    # TANH_SQUARED
    y = wp.sqrt(1.0 - value_at_1)
    s = 0.5 * wp.log((1.0 + y) / (1.0 - y))  # arctanh(y)
    t = wp.tanh(d * s)
    return 1.0 - t * t


@wp.func
def tolerance(x: float, lower: float, upper: float, margin: float, kind: int, value_at_margin: float) -> float:
    """dm_control ``rewards.tolerance(x, bounds=(lower, upper), margin, sigmoid=kind, value_at_margin)``."""
    in_bounds = x >= lower and x <= upper
    if in_bounds:
        return 1.0
    if margin <= 0.0:
        return 0.0
    d = wp.where(x < lower, lower - x, x - upper) / margin
    return sigmoid(d, value_at_margin, kind)


@wp.func
def small_control(u: float) -> float:
    """Per-actuator control-cost factor of the DMC tasks: ``(4 + tolerance(u, margin=1, 0, quadratic)) / 5``."""
    return (4.0 + tolerance(u, 0.0, 0.0, 1.0, QUADRATIC, 0.0)) / 5.0
