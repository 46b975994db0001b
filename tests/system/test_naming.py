"""The names of generated symbols (nhham.system.naming), as the documentation and the
command's JSON spell them: x -> x_dot, x_ddot, p_x; the i-th multiplier lambda_i."""

import pytest
import sympy as sp

from nhham.system.naming import (
    acceleration_symbol,
    as_symbol,
    momentum_symbol,
    multiplier_symbol,
    velocity_symbol,
)


def test_names_of_a_coordinates_derived_symbols():
    theta = sp.Symbol("theta")
    assert velocity_symbol(theta) == sp.Symbol("theta_dot")
    assert acceleration_symbol(theta) == sp.Symbol("theta_ddot")
    assert momentum_symbol(theta) == sp.Symbol("p_theta")
    assert [multiplier_symbol(i).name for i in (1, 2, 10)] == ["lambda_1", "lambda_2",
                                                               "lambda_10"]


def test_plain_symbols_from_names_and_symbols():
    """Assumptions are dropped: a positive x and the plain x are one symbol here."""
    assert as_symbol("x") == sp.Symbol("x")
    plain = as_symbol(sp.Symbol("x", positive=True))
    assert plain == sp.Symbol("x") and plain.is_positive is None
    with pytest.raises(TypeError, match="name or a sympy Symbol"):
        as_symbol(3)
