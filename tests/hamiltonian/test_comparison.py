"""Where the cross-check compares the two sides: the tolerance of a numeric comparison,
and the Lagrangian side evaluated at a point by numeric solves with W, against the
rolling disk's closed forms (paper Example 2.1, worked out by hand below)."""

import numpy as np
import pytest

import handmade
from nhham import models
from nhham.hamiltonian.comparison import ComparisonPoints, NumericLagrangian, lag_C
from nhham.system.evaluation import Backend


def test_sampler_comparison_tolerance():
    s = ComparisonPoints(models.rolling_disk(), (), None, 3, 1, 1e-9)
    assert s.compare([(np.array([1.0, 2.0]), np.array([1.0, 2.0 + 1e-12]))])[2]
    ab, rel, ok = s.compare([(np.array([100.0]), np.array([100.0 + 1e-6]))])
    assert not ok and ab == pytest.approx(1e-6) and rel == pytest.approx(1e-8)
    ab, rel, ok = s.compare([(np.array([np.inf]), np.array([1.0])),
                             (np.array([1.0]), np.array([1.0]))])
    assert ok and s.skipped == 1


def _disk_at(rng):
    """The rolling disk, its (q, v, parameters) order, and a hand-built point of M_1."""
    system, point = handmade.rolling_disk()
    args = tuple(system.coordinates) + tuple(system.velocities) + tuple(system.parameters)
    pt = point(rng)
    return system, args, pt, [pt[s] for s in args]


def test_lagrangian_side_at_a_point_against_the_closed_forms():
    """Disk: W = diag(m, m, I1, I2) (constant, so the mixed Hessian is 0 and Leg_* (v, a)
    = (v, W a)); on M_1 x' = R c phi', y' = R s phi', and the constrained motion has
    theta'' = phi'' = 0, x'' = -R s theta' phi', y'' = R c theta' phi' (differentiate the
    constraints), with lambda = m R theta' phi' (s, -c) (the paper's Example 2.1)."""
    rng = np.random.default_rng(5)
    for _ in range(3):
        system, args, pt, vals = _disk_at(rng)
        x, y, th, ph, xd, yd, thd, phd, m, I1, I2, R = args
        lag = NumericLagrangian(system, args)
        pushed, lam, C = lag.projected(Backend(None), vals)
        s, c, w = np.sin(pt[th]), np.cos(pt[th]), pt[thd] * pt[phd]
        acc = [-pt[R] * s * w, pt[R] * c * w, 0.0, 0.0]
        W = [pt[m], pt[m], pt[I1], pt[I2]]
        expected = [pt[xd], pt[yd], pt[thd], pt[phd]] + [Wi * a for Wi, a in zip(W, acc)]
        assert np.allclose(pushed, expected, rtol=1e-12, atol=1e-12)
        assert np.allclose(lam, [pt[m] * pt[R] * w * s, -pt[m] * pt[R] * w * c],
                           rtol=1e-12, atol=1e-12)


def test_constraint_matrix_at_a_point():
    """C = -mu W^-1 mu^T with mu = [[1, 0, 0, -R c], [0, 1, 0, -R s]]:
    -[[1/m + R^2 c^2/I2, R^2 c s/I2], [R^2 c s/I2, 1/m + R^2 s^2/I2]]."""
    system, args, pt, vals = _disk_at(np.random.default_rng(6))
    th, m, I2, R = args[2], args[8], args[10], args[11]
    s, c = np.sin(pt[th]), np.cos(pt[th])
    k = pt[R] ** 2 / pt[I2]
    expected = -np.array([[1 / pt[m] + k * c * c, k * c * s], [k * c * s, 1 / pt[m] + k * s * s]])
    C = lag_C(NumericLagrangian(system, args), Backend(None), vals)
    assert np.allclose(np.asarray(C, dtype=float), expected, rtol=1e-13, atol=1e-14)


def test_sides_finite_at_no_point_are_refused_not_reported_as_a_disagreement():
    """W_zz = pi/q where the holonomic q = 0 holds: every point of M_f had both sides
    infinite, and the cross-check told the user to report a bug; it is the input's."""
    from nhham.errors import InputError

    s = ComparisonPoints(models.rolling_disk(), (), None, 3, 1, 1e-9)
    with pytest.raises(InputError, match="not finite at any of 2 points of M_f"):
        s.compare([(np.array([np.inf]), np.array([1.0])), (np.array([1.0]),
                                                           np.array([np.nan]))])
