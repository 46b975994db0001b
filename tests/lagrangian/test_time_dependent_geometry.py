"""Time-dependent L and constraints on TQ (DESIGN.md §2): the drift gains ∂φ/∂t, the
forcing −∂²L/∂v∂t, the tangency rows ∂χ/∂t; t is a parameter of M_k without a value.

Every expected value is worked out by hand below, not read from nhham.
"""

import sympy as sp

from nhham import System, analyze_constraints, lagrangian_geometry
from nhham.lagrangian.formulas import bordered_system, tangency_rows
from nhham.lagrangian.linalg import ListMatrix
from nhham.lagrangian.projection import gradient_rows, tangency_equations, time_rates

x, y, xd, yd, t, m, g = sp.symbols("x y x_dot y_dot t m gamma")


def same(a, b):
    return sp.simplify(a - b) == 0


def test_a_particle_on_a_time_dependent_slope_has_its_multiplier_by_hand():
    # φ = y' − t x' (μ = (−t, 1), ∂φ/∂t = −x'); m x'' = t λ, m y'' = −λ, and
    # d/dt φ = y'' − x' − t x'' = 0 gives λ = −m x'/(1 + t²), x'' = −t x'/(1 + t²).
    s = System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2", constraints=["y_dot - t*x_dot"],
               parameters={"m": None})
    geometry = lagrangian_geometry(s, closed_form=True)
    assert geometry.drift.T == sp.Matrix([[-xd]])
    assert same(geometry.multipliers[0], -m * xd / (1 + t**2))
    field = geometry.projected_field
    assert same(field[2], -t * xd / (1 + t**2)) and same(field[3], xd / (1 + t**2))


def test_a_lagrangian_in_t_has_the_term_of_d_dt_dl_dv():
    # Caldirola-Kanai: L = e^{γt}(x'² − x²)/2, so d/dt(e^{γt} x') = −e^{γt} x:
    # x'' = −γ x' − x (the damped oscillator).
    s = System(["x"], "exp(gamma*t)*(x_dot**2 - x**2)/2", parameters={"gamma": None})
    assert s.lagrangian_depends_on_time
    assert same(lagrangian_geometry(s).accelerations[0], -g * xd - x)


def test_the_tangency_rows_carry_the_time_derivative():
    # χ = x − sin t with ξ = (x', 0, 0, 0) and Z = (0, 0, −1, 0): b = x' − cos t, A = 0
    chi = x - sp.sin(t)
    grads = gradient_rows([chi], (x, y, xd, yd))
    A, b = tangency_equations(grads, sp.Matrix([xd, 0, 0, 0]), sp.Matrix([[0, 0, -1, 0]]),
                              rates=time_rates([chi], t))
    assert A == sp.Matrix([[0]]) and same(b[0], xd - sp.cos(t))
    assert tangency_equations(grads, sp.Matrix([xd, 0, 0, 0]), None)[1][0] == xd


def test_the_bordered_system_carries_the_time_derivative_and_its_schur_complement_agrees():
    # W = I, χ = φ with μ = (−2, 1), F = (1, 0), ∂χ/∂q v = −9, ∂χ/∂t = 4: c = [1, 0, 9 − 4].
    # With a = F − μᵀλ, d/dt χ = −9 + 4 + μ a = −5 − 2 − 5λ: A = −5, b = −7.
    W, mu = ListMatrix([[1, 0], [0, 1]]), ListMatrix([[-2, 1]])
    F, Jq_v, Jt = ListMatrix([[1], [0]]), ListMatrix([[-9]]), ListMatrix([[4]])
    K, c = bordered_system(W, mu, F, Jq_v, mu, Jt)
    assert K.rows == [[1, 0, -2], [0, 1, 1], [-2, 1, 0]] and c.rows == [[1], [0], [5]]
    A, b = tangency_rows(W, mu, F, Jq_v + Jt, mu)
    assert A.rows == [[-5]] and b.rows == [[-7]]
    # the bordered solve: a = F − μᵀλ with λ = −b/A = −7/5 satisfies μ a = −(Jq_v + Jt) = 5
    lam = sp.Rational(-7, 5)
    a = [1 + 2 * lam, -lam]
    assert -2 * a[0] + a[1] == 5


def test_secondary_constraints_in_t_are_found_with_their_multiplier():
    # L = (x'² − y'²)/2 − x²/2, φ = x' + y' − sin t: C = 0 (W = diag(1, −1), μ = (1, 1)).
    # Tangency of φ: −x − cos t = 0 (χ₁ = x + cos t); of χ₁: x' − sin t = 0 (χ₂); of χ₂:
    # x'' − cos t = −x − λ − cos t = 0, so λ = −x − cos t (zero on M_f).
    s = System(["x", "y"], "(x_dot**2 - y_dot**2)/2 - x**2/2",
               constraints=["x_dot + y_dot - sin(t)"])
    analysis = analyze_constraints(s)
    assert analysis.status == "determined"
    secondary = analysis.final_constraints[1:]
    assert len(secondary) == 2
    assert same(secondary[0] ** 2, (x + sp.cos(t)) ** 2)
    assert same(secondary[1] ** 2, (xd - sp.sin(t)) ** 2)
    assert same(list(analysis.multipliers.values())[0], -x - sp.cos(t))


def test_a_constraint_whose_rate_cannot_be_met_is_inconsistent():
    # L = (x'² − y'²)/2 with φ = x' + y' − t: C = 0 and d/dt φ = x'' + y'' − 1 = −1 ≠ 0 for
    # every λ (without ∂φ/∂t the algorithm would find φ preserved, λ free).
    s = System(["x", "y"], "(x_dot**2 - y_dot**2)/2", constraints=["x_dot + y_dot - t"])
    assert analyze_constraints(s).status == "inconsistent"
    autonomous = System(["x", "y"], "(x_dot**2 - y_dot**2)/2", constraints=["x_dot + y_dot - 1"])
    assert analyze_constraints(autonomous).status == "underdetermined"
