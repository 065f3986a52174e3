"""The dm_control ``tolerance`` primitive (tasks/dmc/rewards.py) against hand-worked values."""

import math

import numpy as np
import pytest

from refpo_warp.tasks.dmc import rewards
from refpo_warp.tasks.dmc.rewards import SIGMOIDS, small_control, tolerance
from refpo_warp.utils.warp_setup import init_warp, wp

init_warp()


@wp.kernel
def _tolerance_kernel(
    x: wp.array(dtype=float),
    lower: float,
    upper: float,
    margin: float,
    kind: int,
    vam: float,
    out: wp.array(dtype=float),
):
    i = wp.tid()
    out[i] = tolerance(x[i], lower, upper, margin, kind, vam)


@wp.kernel
def _small_control_kernel(u: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = small_control(u[i])


def tol(x, lower=0.0, upper=0.0, margin=0.0, sigmoid="gaussian", value_at_margin=0.1):
    xs = wp.array(np.atleast_1d(np.asarray(x, np.float32)), dtype=float, device="cpu")
    out = wp.zeros(xs.shape[0], dtype=float, device="cpu")
    wp.launch(
        _tolerance_kernel,
        dim=xs.shape[0],
        device="cpu",
        inputs=[xs, lower, upper, margin, SIGMOIDS[sigmoid], value_at_margin, out],
    )
    return out.numpy()


def test_inside_bounds_is_one_for_every_sigmoid():
    for name in SIGMOIDS:
        np.testing.assert_allclose(tol([-0.2, 0.0, 0.3], -0.2, 0.3, 1.0, name, 0.1), 1.0)


def test_zero_margin_is_an_indicator():
    np.testing.assert_array_equal(tol([-0.01, 0.0, 0.5, 0.51], 0.0, 0.5), [0.0, 1.0, 1.0, 0.0])


@pytest.mark.parametrize("name", sorted(SIGMOIDS))
def test_value_at_margin_is_reached_at_one_margin(name):
    # d = 1 (one margin outside on either side) must give exactly value_at_margin, for every shape.
    np.testing.assert_allclose(tol([1.5, -1.5], -0.5, 0.5, 1.0, name, 0.3), 0.3, rtol=1e-5)


def test_gaussian_hand_worked():
    # d = 0.25 (x = 0.5, margin 2): exp(-0.5 * (0.25 * sqrt(-2 ln 0.1))^2) = 0.1 ** (0.25 ** 2) = 0.86596
    np.testing.assert_allclose(tol(0.5, 0.0, 0.0, 2.0), 0.1**0.0625, rtol=1e-6)
    np.testing.assert_allclose(tol(0.5, 0.0, 0.0, 2.0), 0.865964, rtol=1e-5)
    # below the lower bound: x = 0.8, bounds (1.2, inf), margin 0.6 -> d = 2/3 -> 0.1 ** (4/9) = 0.35938
    np.testing.assert_allclose(tol(0.8, 1.2, math.inf, 0.6), 0.359381, rtol=1e-5)


def test_linear_hand_worked():
    # cheetah: bounds (10, inf), margin 10, value 0 at margin: speed 4 -> d = 0.6 -> 1 - 0.6 = 0.4
    np.testing.assert_allclose(
        tol([4.0, 0.0, -3.0, 12.0], 10.0, math.inf, 10.0, "linear", 0.0), [0.4, 0.0, 0.0, 1.0], atol=1e-6
    )
    # walker move: bounds (1, inf), margin 0.5, value 0.5 at margin: v = 0.8 -> d = 0.4 -> 1 - 0.4 * 0.5 = 0.8;
    # v = 0.5 -> d = 1 -> 0.5; v = 0 -> d = 2 -> d * 0.5 = 1 is not < 1 -> 0
    np.testing.assert_allclose(tol([0.8, 0.5, 0.0], 1.0, math.inf, 0.5, "linear", 0.5), [0.8, 0.5, 0.0], atol=1e-6)


def test_quadratic_hand_worked():
    # small-control term: margin 1, value 0 at margin: u = 0.5 -> 1 - 0.25; |u| >= 1 -> 0
    np.testing.assert_allclose(
        tol([0.5, -0.5, 1.0, 2.0], 0.0, 0.0, 1.0, "quadratic", 0.0), [0.75, 0.75, 0.0, 0.0], atol=1e-6
    )


def test_long_tail_hyperbolic_reciprocal_cosine_tanh_hand_worked():
    # d = 2, v = 0.1
    np.testing.assert_allclose(tol(2.0, 0, 0, 1.0, "long_tail"), 1.0 / (4.0 * 9.0 + 1.0), rtol=1e-5)  # s^2 = 9
    np.testing.assert_allclose(tol(2.0, 0, 0, 1.0, "reciprocal"), 1.0 / (2.0 * 9.0 + 1.0), rtol=1e-5)  # s = 9
    np.testing.assert_allclose(tol(2.0, 0, 0, 1.0, "hyperbolic"), 1.0 / math.cosh(2.0 * math.acosh(10.0)), rtol=1e-4)
    # cosine with v = 0.5: s = acos(0) / pi = 0.5; d = 1.5 -> (1 + cos(0.75 pi)) / 2; d = 2.5 -> 0
    np.testing.assert_allclose(
        tol([1.5, 2.5], 0, 0, 1.0, "cosine", 0.5), [(1 + math.cos(0.75 * math.pi)) / 2, 0.0], atol=1e-6
    )
    np.testing.assert_allclose(
        tol(0.5, 0, 0, 1.0, "tanh_squared", 0.1), 1.0 - math.tanh(0.5 * math.atanh(math.sqrt(0.9))) ** 2, rtol=1e-5
    )


def test_small_control_factor():
    u = wp.array(np.array([0.0, 0.5, -1.0, 3.0], np.float32), dtype=float, device="cpu")
    out = wp.zeros(4, dtype=float, device="cpu")
    wp.launch(_small_control_kernel, dim=4, inputs=[u, out], device="cpu")
    np.testing.assert_allclose(out.numpy(), [1.0, (4 + 0.75) / 5, 0.8, 0.8], atol=1e-6)


def test_default_value_at_margin_is_dm_controls():
    assert pytest.approx(0.1) == rewards.DEFAULT_VALUE_AT_MARGIN
