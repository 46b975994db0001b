"""Chetaev's rule on TQ: Z_i, C, lambda and P for constraints nonlinear in v, against
values worked out by hand (DESIGN.md §2: mu = d phi/d v, Z = -W^-1 mu^T, C = Z(phi),
lambda = -C^-T xi_L(phi))."""

import sympy as sp

import nhham
from nhham.lagrangian.analysis import analyze_constraints
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.lagrangian.integrability import integrability

m, g, a, c = sp.symbols("m g a c", positive=True)
x, y, z = sp.symbols("x y z")
xd, yd, zd = sp.symbols("x_dot y_dot z_dot")


def appell_hamel():
    return nhham.System(["x", "y", "z"], m * (xd**2 + yd**2 + zd**2) / 2 - m * g * z,
                        [a * sp.sqrt(xd**2 + yd**2) - zd], parameters=[m, g, a])


def isokinetic():
    return nhham.System(["x", "y"], m * (xd**2 + yd**2) / 2 - m * g * y,
                        [(xd**2 + yd**2 - c**2) / 2], parameters=[m, g, c])


def test_appell_hamel_fields_matrix_and_multiplier():
    G = lagrangian_geometry(appell_hamel(), closed_form=True)
    s = sp.sqrt(xd**2 + yd**2)
    # Z = -(1/m)(a x'/s, a y'/s, -1) d/dv; C = -(1 + a^2)/m; xi(phi) = mu . (0, 0, -g) = g
    Z = sp.Matrix([[0, 0, 0, -a * xd / (m * s), -a * yd / (m * s), 1 / m]])
    assert (G.vertical_fields - Z).applyfunc(sp.simplify) == sp.zeros(1, 6)
    assert sp.simplify(G.constraint_matrix[0] + (1 + a**2) / m) == 0
    assert sp.simplify(G.constraint_derivatives[0] - g) == 0
    assert sp.simplify(G.multipliers[0] - m * g / (1 + a**2)) == 0
    # P(xi_L): z'' = -g + lambda/m = -a^2 g/(1 + a^2), x'' = -lambda a x'/(m s)
    field = G.projected_field
    assert sp.simplify(field[5] + a**2 * g / (1 + a**2)) == 0
    assert sp.simplify(field[3] + a * g * xd / ((1 + a**2) * s)) == 0
    P = G.projector_P
    assert (P * P - P).applyfunc(sp.simplify) == sp.zeros(6, 6)


def test_isokinetic_multiplier_at_a_point():
    G = lagrangian_geometry(isokinetic(), closed_form=True)
    # C = -(x'^2 + y'^2)/m (= -c^2/m on M_1), lambda = -m g y'/(x'^2 + y'^2)
    assert sp.expand(G.constraint_matrix[0] + (xd**2 + yd**2) / m) == 0
    point = {xd: sp.Rational(6, 5), yd: sp.Rational(-8, 5), m: 2, g: 10, c: 2}
    assert G.multipliers[0].subs(point) == 2 * 10 * sp.Rational(8, 5) / 4
    Z = G.vertical_fields.subs(point)
    assert list(Z) == [0, 0, sp.Rational(-3, 5), sp.Rational(4, 5)]


def test_nonlinear_constraints_integrability_not_applicable_and_kinds():
    s = isokinetic()
    answer = integrability(s)
    assert answer.integrable is None and answer.method == "not applicable"
    data = analyze_constraints(s).to_dict()
    assert data["constraint_kinds"] == [{"label": "constraints[0]", "kind": "nonlinear (Chetaev)",
                                         "time_dependent": False}]
    assert data["integrability"] == "not applicable for nonlinear constraints"
    assert data["status"] == "determined" and data["regular"] and data["rank_c"] == 1


def test_every_constraint_of_M1_is_labelled_by_kind_and_time():
    """One record per constraint of M_1 on every system: g(q, t) holonomic, its lift linear
    (affine when g moves with t: the lift gains dg/dt), mu(q) v linear, mu(q) v + h(q, t)
    affine, and the Frobenius answer keeps its usual key for affine constraints."""
    t = sp.Symbol("t")
    s = nhham.System(["x", "y", "z"], (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd])
    data = analyze_constraints(s).to_dict()
    assert data["constraint_kinds"] == [{"label": "constraints[0]", "kind": "linear",
                                         "time_dependent": False}]
    assert "integrability" not in data
    w, wd, u, ud = sp.symbols("w w_dot u u_dot")
    moving = nhham.System(["x", "y", "z", "w", "u"],
                          (xd**2 + yd**2 + zd**2 + wd**2 + ud**2) / 2,
                          [zd - y * xd, yd - sp.sin(t)], holonomic=[x - t**2, w - y])
    kinds = [(r["label"], r["kind"], r["time_dependent"])
             for r in analyze_constraints(moving).to_dict()["constraint_kinds"]]
    assert kinds == [("holonomic[0]", "holonomic", True), ("holonomic[1]", "holonomic", False),
                     ("holonomic[0].lift", "affine", True),
                     ("holonomic[1].lift", "linear", False),
                     ("constraints[0]", "linear", False), ("constraints[1]", "affine", True)]


def test_chetaev_decisions_are_exact_at_points_over_F_p():
    """M_1 of a Chetaev constraint is curved in the velocities: its points over F_p (the
    dependent velocity a root mod p) prove a full rank (the isokinetic particle:
    C = -c^2/m on M_1; it was sampled). By
    hand: L = (x'^2 - y'^2)/2 (W = diag(1, -1)) and phi = (x'^2 - y'^2)/2 give
    mu = (x', -y'), C = -mu W^-1 mu^T = -(x'^2 - y'^2) = -2 phi: zero on M_1 (the exact
    reduction sees it)."""
    analysis = analyze_constraints(nhham.System(["x", "y"], m * (xd**2 + yd**2) / 2
                                                - m * g * y, [(xd**2 + yd**2 - 2) / 2],
                                                parameters={m: 1.0, g: 9.81}))
    rank = analysis.stages[0].decisions[0].decision
    assert analysis.regular and rank.method == "exact" and "over F_p" in rank.detail
    assert "M is curved (the constraint solved for" in rank.detail
    null = analyze_constraints(nhham.System(["x", "y"], (xd**2 - yd**2) / 2,
                                            [(xd**2 - yd**2) / 2]))
    decision = null.stages[0].decisions[0].decision
    assert not null.regular and null.rank_C == 0 and decision.method == "exact"
