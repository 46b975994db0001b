"""The constraint algorithm with forces (the forced field ξ_L + F^v), against hand derivations.

Example 3.2 of the paper: L = (v1² + v2² - v3²)/2 + q1²/2, φ = v1 + v3, so W = diag(1, 1, -1),
Z = -W⁻¹μ = (-1, 0, 1) on (v1, v2, v3) and C = Z(φ) = 0. With a force Q1 on q1 the free
accelerations are a1 = q1 + Q1, a3 = 0 and ξ(φ) = q1 + Q1:

* Q1 = c (constant): χ2 = q1 + c, ξ(χ2) = v1 = χ3, Z(v1) = -1 fixes λ from
  a1 - λ = 0 on M_3: λ = q1 + c. Three stages, as without the force.
* Q1 = -k v1 + c: χ2 = q1 - k v1 + c with Z(χ2) = k ≠ 0, so λ is fixed at stage 2:
  v1 - k (q1 - k v1 + c - λ) = 0, λ = (k (q1 + c) - (k² + 1) v1) / k. Two stages: the
  force changes the secondary constraints (and dim M_f = 6 - 2 = 4 instead of 3).
"""

import pytest
import sympy as sp

import nhham
from nhham.errors import InputError
from nhham.lagrangian.analysis import analyze_constraints
from nhham.lagrangian.geometry import lagrangian_geometry

q1, q2, q3, v1, v2, v3, k, c, u = sp.symbols("q1 q2 q3 q1_dot q2_dot q3_dot k c u")
L = (v1**2 + v2**2 - v3**2) / 2 + q1**2 / 2


def example_3_2(force, parameters=None, inputs=()):
    return nhham.System(["q1", "q2", "q3"], L, constraints=[v1 + v3],
                        parameters=parameters or {}, forces={"q1": force}, inputs=inputs)


def test_constant_force_keeps_three_stages_and_shifts_them():
    a = analyze_constraints(example_3_2(c, {"c": 0.25}))
    assert len(a.stages) == 3 and a.status == "determined" and a.dimension == 3
    finals = [sp.expand(f) for f in a.final_constraints]
    assert sp.expand(q1 + c) in finals or sp.expand(-q1 - c) in finals
    assert any(sp.expand(f - v1) == 0 or sp.expand(f + v1) == 0 for f in finals)
    (lam,) = a.multipliers.values()
    assert sp.simplify(lam - (q1 + c)) == 0


def test_a_damper_changes_the_secondary_constraints():
    a = analyze_constraints(example_3_2(-k * v1 + c, {"k": 0.5, "c": 0.25}))
    assert len(a.stages) == 2 and a.status == "determined" and a.dimension == 4
    (chi,) = a.stages[0].new_constraints  # found on M_1, defining M_2
    ratio = sp.cancel(chi / (q1 - k * v1 + c))
    assert ratio.is_number and ratio != 0
    (lam,) = a.multipliers.values()
    assert sp.simplify(lam - (k * (q1 + c) - (k**2 + 1) * v1) / k) == 0


def test_without_the_force_the_paper_s_three_stages():
    a = analyze_constraints(nhham.System(["q1", "q2", "q3"], L, constraints=[v1 + v3]))
    assert len(a.stages) == 3 and a.dimension == 3


def test_classification_of_a_regular_system_is_unchanged_by_a_force():
    """C and the classes depend on W and μ only (paper §3): a damped, driven rolling disk
    is classified as the free one."""
    x, y, th, ph = sp.symbols("x y theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    Lr = (xd**2 + yd**2) / 2 + thd**2 / 4 + phd**2 / 8
    cons = [xd - sp.cos(th) * phd, yd - sp.sin(th) * phd]
    free = nhham.System(["x", "y", "theta", "phi"], Lr, constraints=cons)
    forced = nhham.System(["x", "y", "theta", "phi"], Lr, constraints=cons,
                          forces={"phi": "u - phi_dot/10", "theta": "sin(t)"},
                          dissipation="x_dot**2/3", inputs=["u"])
    a, b = analyze_constraints(free), analyze_constraints(forced)
    assert (a.rank_C, a.status, len(a.stages), a.integrable) == \
        (b.rank_C, b.status, len(b.stages), b.integrable) == (2, "determined", 1, False)
    assert lagrangian_geometry(forced).constraint_matrix == \
        lagrangian_geometry(free).constraint_matrix


def test_the_forced_field_is_the_field_plus_the_lift_of_the_force():
    """P(ξ_L + F^v) on a particle in the plane with x' = y and a force (Q_x, Q_y):
    W a + μᵀ λ = F + Q with μ = (1, -y)... checked against the hand solution."""
    x, y, xd, yd, Qx, Qy = sp.symbols("x y x_dot y_dot Q_x Q_y")
    s = nhham.System(["x", "y"], (xd**2 + yd**2) / 2, constraints=[xd - y * yd],
                     forces={"x": Qx, "y": Qy}, inputs=["Q_x", "Q_y"])
    geo = lagrangian_geometry(s)
    # by hand: a_x + λ = Q_x, a_y - y λ = Q_y, d/dt(x' - y y') = a_x - y a_y - y'^2 = 0
    lam = (Qx - y * Qy - yd**2) / (1 + y**2)
    field = geo.projected_field
    assert sp.simplify(field[2] - (Qx - lam)) == 0
    assert sp.simplify(field[3] - (Qy + y * lam)) == 0
    assert sp.simplify(geo.multipliers[0] - lam) == 0


def test_a_secondary_constraint_on_an_input_is_refused_naming_it():
    with pytest.raises(InputError, match=r"secondary\[0\].*depends on u"):
        analyze_constraints(example_3_2(u, inputs=["u"]))


def test_the_sign_of_the_force_field():
    """DESIGN.md §2: i_{F^v} ω_L = -F and i_{ξ_L + F^v} ω_L = dE_L - F, with ω(X, Y) = XᵀΩY
    (Ω from the geometry), on a system with q-dependent W and a gyroscopic term."""
    x, y, xd, yd, a, b = sp.symbols("x y x_dot y_dot a b")
    L = (1 + x**2) * xd**2 / 2 + yd**2 / 2 + x * xd * yd + y * xd - sp.cos(x)
    forced = nhham.System(["x", "y"], L, forces={"x": a * yd, "y": b - xd**2},
                          inputs=["a", "b"])
    free = nhham.System(["x", "y"], L)
    g, g0 = lagrangian_geometry(forced), lagrangian_geometry(free)
    Omega = g.poincare_cartan_2form
    Fv = g.euler_lagrange_field - g0.euler_lagrange_field       # F^v
    assert all(sp.simplify(e) == 0 for e in Fv[:2])              # vertical
    F = sp.Matrix([a * yd, b - xd**2, 0, 0])                     # F = Q_A dq^A on TQ
    i_Fv = (Fv.T * Omega).T                                      # (i_X ω)(Y) = Xᵀ Ω Y
    assert all(sp.simplify(e) == 0 for e in i_Fv + F)
    dE = g.gradient(g.energy)
    i_xi = (g.euler_lagrange_field.T * Omega).T
    assert all(sp.simplify(e) == 0 for e in i_xi - (dE - F))
