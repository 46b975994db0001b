"""T*Q with a time-dependent constraint: Ψ(q, p, t) = φ ∘ Leg⁻¹ and ∂Ψ/∂t in the
consistency condition; the cross-check through Leg agrees at a generic instant."""

import pytest
import sympy as sp

from nhham import System, cross_check, hamiltonian_side
from nhham.errors import InputError

x, y, px, py, t, m, W = sp.symbols("x y p_x p_y t m Omega")


def bead():
    return System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2",
                  holonomic=["y*cos(Omega*t) - x*sin(Omega*t)"],
                  parameters={"m": 1.0, "Omega": 2.0})


def test_the_consistency_condition_carries_the_time_derivative_of_psi():
    # Ψ = (−sin Ωt p_x + cos Ωt p_y)/m − Ω(x cos Ωt + y sin Ωt); {Ψ, H} = −Ω(cos p_x +
    # sin p_y)/m (H = |p|²/2m) and ∂Ψ/∂t = −Ω(cos p_x + sin p_y)/m + Ω²(x sin − y cos)
    side = hamiltonian_side(bead())
    c, s = sp.cos(W * t), sp.sin(W * t)
    expected = -2 * W * (c * px + s * py) / m + W**2 * (x * s - y * c)
    assert sp.simplify(side.constraint_derivatives[0] - expected) == 0


def test_the_cross_check_agrees_for_a_moving_constraint():
    report = cross_check(bead())
    assert report.agree


def test_compare_refuses_a_lagrangian_in_t_naming_it():
    s = System(["x", "y"], "exp(t)*(x_dot**2 + y_dot**2)/2", constraints=["y_dot - x*x_dot"])
    with pytest.raises(InputError, match="Legendre map") as e:
        cross_check(s)
    assert e.value.key == "lagrangian"
