"""Unit-free generic ranks (nhham.system.rank) and the validation that uses them.

Expected ranks are known by construction (diagonal matrices, products of a column and
a row), not computed by the code under test.
"""

import numpy as np
import pytest
import sympy as sp

import nhham
from nhham.errors import SingularLagrangianError
from nhham.system.rank import float_rank, precise_ranks

x, y, th, R, m = sp.symbols("x y th R m")
xd, yd, thd, phd = sp.symbols("x_dot y_dot th_dot ph_dot")


def test_float_rank_is_relative_to_the_largest_entry_and_may_underestimate():
    assert float_rank(np.diag([1.0, 1.0, 1.0])) == 3
    assert float_rank(np.diag([1e-16, 1e-16, 1.0, 1.0])) == 2  # the reason to confirm


@pytest.mark.parametrize("scale", [1e-16, 1e-12, 1.0, 1e12])
def test_precise_rank_of_a_diagonal_is_its_count_of_nonzero_entries(scale):
    W = sp.diag(m, m, 1, 1)
    assert precise_ranks(W, [{m: scale}], [[0, 1, 2, 3], [0, 1], [2]]) == [4, 2, 1]


def test_precise_rank_of_an_outer_product_is_one_at_any_scale():
    W = sp.Matrix([[y**2, x * y], [x * y, x**2]])  # (y, x)^T (y, x)
    for s in (1e-10, 1.0, 1e10):
        assert precise_ranks(W, [{x: 0.3 * s, y: -0.7 * s}], [[0, 1]]) == [1]


def test_an_entry_zero_by_cancellation_is_not_scaled_up():
    """sin^2 + cos^2 - 1 evaluates to rounding noise; equilibration must not make it 1."""
    N = sp.Matrix([[1, 0], [sp.sin(x)**2 + sp.cos(x)**2 - 1, 0]])
    assert precise_ranks(N, [{x: 0.7}], [[0, 1]]) == [1]


@pytest.mark.parametrize("small, large", [(1e-16, 1.0), (1e-12, 1e12)])
def test_a_regular_lagrangian_in_extreme_units_is_accepted(small, large):
    """W = diag(m, m, I1, I2) is invertible for every positive value (issue: m = 1e-16 was
    refused as 'rank 2 of 4')."""
    disk = nhham.System(
        ["x", "y", "th", "ph"],
        "m*(x_dot**2 + y_dot**2)/2 + I1*th_dot**2/2 + I2*ph_dot**2/2",
        ["x_dot - R*cos(th)*ph_dot", "y_dot - R*sin(th)*ph_dot"],
        parameters={"m": small, "I1": 1.0, "I2": large, "R": 1.0})
    assert disk.n == 4 and disk.m == 2


def test_a_singular_lagrangian_is_still_found_at_any_scale():
    s = nhham.System(["x", "y"], "k*(y*x_dot + x*y_dot)**2/2", parameters={"k": 1e-20})
    assert not s.regular_lagrangian
    with pytest.raises(SingularLagrangianError, match="rank 1 of 2"):
        s.require_regular_lagrangian("simulate")
    assert nhham.System(["x", "y"], "k*(x_dot**2 + y_dot**2)/2",
                        parameters={"k": 1e-20}).regular_lagrangian


def test_constraints_in_extreme_units_are_not_redundant():
    """R = 1e12: the rows [1, 0, 0, -R cos], [0, 1, 0, -R sin] are independent (they were
    dropped as 'a combination of the others')."""
    disk = nhham.System(
        ["x", "y", "th", "ph"], "(x_dot**2 + y_dot**2 + th_dot**2 + ph_dot**2)/2",
        ["x_dot - R*cos(th)*ph_dot", "y_dot - R*sin(th)*ph_dot"], parameters={"R": 1e12})
    assert disk.m == 2 and disk.dropped == ()


def test_truly_dependent_constraints_are_still_found_at_any_scale():
    from nhham.errors import RedundantConstraintError

    with pytest.raises(RedundantConstraintError, match=r"constraints\[1\]"):
        nhham.System(["x", "y", "th"], "(x_dot**2 + y_dot**2 + th_dot**2)/2",
                     ["x_dot - R*th_dot", "k*x_dot - k*R*th_dot"],
                     parameters={"R": 1e12, "k": 1e-12})
