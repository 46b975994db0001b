"""First/second-class classification on M_f (the result object: test_classes.py; the
Dirac bracket: test_dirac.py).

Hand derivations in the comments use {f, g} = f_q g_p - f_p g_q and, for functions
linear in p, f = a(q).p and h = b(q).p: {f, h} = p . ((b.grad) a - (a.grad) b).
"""


import numpy as np
import pytest
import sympy as sp

import nhham

import handmade
from nhham.hamiltonian.classification import classify_constraints

S = sp.Symbol


def pendulum():
    return handmade.pendulum()


def example_3_2():
    q1 = S("q1")
    v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
    return nhham.System(["q1", "q2", "q3"], (v1**2 + v2**2 - v3**2) / 2 + q1**2 / 2, [v1 + v3])


def on(classes, expr):
    return classes.manifold.vanishes(expr).value


# ------------------------------------------------ hand-derived classifications
def test_pendulum_holonomic_pair_is_second_class():
    c = classify_constraints(pendulum())
    x, y = sp.symbols("x y")
    m = S("m")
    # chi = (g, g^c) with g = x^2 + y^2 - l^2 and g^c o Leg^{-1} = 2 (x p_x + y p_y)/m:
    # B_12 = {g, g^c} = grad(g) . d g^c/dp = (2x)(2x/m) + (2y)(2y/m) = 4 l^2/m != 0 on M_f.
    assert c.labels == ("holonomic[0]", "holonomic[0].lift")
    assert on(c, c.bracket_matrix[0, 1] - 4 * S("l") ** 2 / m)
    assert c.rank == 2 and c.second_class == 2 and c.first_class == 0
    assert c.second_class_set == c.labels
    assert c.first_class_combinations == () and c.individually_first_class == ()


def test_first_class_combination_of_individually_second_class_constraints():
    s = handmade.sphere_with_knife()
    c = classify_constraints(s)
    x, y, z = s.coordinates
    px, py, pz = c.side.momenta
    m = S("m")
    r2 = x**2 + y**2 + z**2
    # chi_1 = g = (r^2 - l^2)/2, chi_2 = (x p_x + y p_y + z p_z)/m, chi_3 = (p_z - y p_x)/m.
    # B_12 = grad g . (x, y, z)/m = r^2/m;  B_13 = grad g . (-y, 0, 1)/m = (z - x y)/m;
    # B_23 = p . ((b.grad) a - (a.grad) b) with a = (x, y, z)/m, b = (-y, 0, 1)/m:
    #   (b.grad) a = (-y, 0, 1)/m^2, (a.grad) b = (-y, 0, 0)/m^2, so B_23 = p_z/m^2 = y p_x/m^2 on M_f.
    B = c.bracket_matrix
    assert on(c, B[0, 1] - r2 / m)
    assert on(c, B[0, 2] - (z - x * y) / m)
    assert on(c, B[1, 2] - y * px / m**2)
    # Every row has a nonzero entry: each chi_a is second class on its own ...
    assert c.individually_first_class == ()
    # ... but a 3x3 antisymmetric [[0, a, b], [-a, 0, k], [-b, -k, 0]] has rank 2 and kernel
    # (k, -b, a): gamma = (y p_x/m^2) chi_1 - ((z - x y)/m) chi_2 + (r^2/m) chi_3 is first class.
    assert c.rank == 2 and c.first_class == 1 and c.second_class == 2
    assert c.second_class_set == ("holonomic[0]", "holonomic[0].lift")
    (coeffs,) = c.combination_coefficients
    hand = {"holonomic[0]": y * px / m**2, "holonomic[0].lift": -(z - x * y) / m,
            "constraints[0]": r2 / m}
    # The reported combination is normalised to coefficient 1 on chi_3.
    for label, value in hand.items():
        assert on(c, coeffs[label] - value / hand["constraints[0]"])
    (gamma,) = c.first_class_combinations
    for chi in c.constraints:
        assert on(c, c.side.algebra.bracket(gamma, chi))
    assert c.decisions["gamma[constraints[0]]"].value


def test_paper_example_3_2_combination():
    s = example_3_2()
    q1 = s.coordinates[0]
    v1, _, v3 = s.velocities
    p1, p2, p3 = sp.symbols("p_q1 p_q2 p_q3")
    # M_3 = {phi = v1 + v3, psi = q1, psi' = v1}; on T*Q (p1 = v1, p3 = -v3):
    # (p1 - p3, q1, p1).  {p1 - p3, q1} = -1, {p1 - p3, p1} = 0, {q1, p1} = 1:
    # B = [[0, -1, 0], [1, 0, 1], [0, -1, 0]], rank 2, kernel (1, 0, -1) up to sign:
    # -(p1 - p3) + p1 = p3 is first class though all three are second class alone.
    given = classify_constraints(s, [v1 + v3, q1, v1], ["phi", "psi", "psi'"])
    assert given.bracket_matrix == sp.Matrix([[0, -1, 0], [1, 0, 1], [0, -1, 0]])
    assert given.rank == 2 and given.second_class_set == ("phi", "psi")
    assert given.first_class_combinations == (p3,)
    assert given.individually_first_class == ()
    assert given.decisions["rank"].method == "exact"
    # The same through the constraint algorithm (final constraints of M_3).
    algo = classify_constraints(s)
    assert algo.labels == ("constraints[0]", "secondary[0]", "secondary[1]")
    assert algo.rank == 2 and algo.first_class == 1
    assert [sp.expand(g) for g in algo.first_class_combinations] in ([p3], [-p3])


def test_two_particle_rod():
    x1, x2, y1, y2 = sp.symbols("x1 x2 y1 y2")
    v = x1d, x2d, y1d, y2d = sp.symbols("x1_dot x2_dot y1_dot y2_dot")
    g, l = sp.symbols("g l")
    X, Y = x2 - x1, y2 - y1
    s = nhham.System(["x1", "x2", "y1", "y2"], sum(w**2 for w in v) / 2 - g * (y1 + y2),
                     [X * (y2d + y1d) - (x2d + x1d) * Y], holonomic=[(X**2 + Y**2 - l**2) / 2],
                     parameters={"g": 9.81, "l": 1.2})
    c = classify_constraints(s)
    # With relative and total momenta u = p2 - p1, P = p1 + p2 and D = q2 - q1:
    # {D_i, u_j} = 2 delta_ij, {D, P} = {u, P} = 0. h = (|D|^2 - l^2)/2, phi1 = D.u, phi2 = D x P.
    # {h, phi1} = D . 2 D = 2 |D|^2 = 2 l^2; {h, phi2} = 0; {phi1, phi2} = -2 D x P = -2 phi2 = 0 on M_f.
    B = c.bracket_matrix
    assert on(c, B[0, 1] - 2 * l**2)
    assert B[0, 2] == 0 and B[1, 2] == 0
    assert sp.expand(c.side.algebra.bracket(c.constraints[1], c.constraints[2])
                     + 2 * c.constraints[2]) == 0
    assert c.rank == 2 and c.second_class_set == ("holonomic[0]", "holonomic[0].lift")
    assert c.individually_first_class == ("constraints[0]",)
    assert c.first_class_combinations == (c.constraints[2],)
    assert c.blocks == (("holonomic[0]", "holonomic[0].lift"), ("constraints[0]",))


def test_rolling_disk_constraints_are_first_class():
    x, y, th, ph = sp.symbols("x y theta phi")
    xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
    m, I1, I2, R = sp.symbols("m I1 I2 R")
    s = nhham.System(["x", "y", "theta", "phi"],
                     m * (xd**2 + yd**2) / 2 + I1 * thd**2 / 2 + I2 * phd**2 / 2,
                     [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd],
                     parameters={"m": 1.3, "I1": 0.5, "I2": 0.25, "R": 0.7})
    c = classify_constraints(s)
    # phi1 = p_x/m - R cos(theta) p_phi/I2 depends on theta but not on p_theta, and neither
    # depends on p_x's or p_y's conjugates crosswise: {phi1, phi2} = 0 identically.
    assert c.bracket_matrix == sp.zeros(2, 2)
    assert c.rank == 0 and c.first_class == 2 and c.second_class_set == ()
    assert c.first_class_combinations == c.constraints


def test_numbers_only_example_decides_exactly():
    # x = 0 (holonomic), x_dot + y_dot = 0: chi = (x, p_x, p_x + p_y),
    # B = [[0, 1, 1], [-1, 0, 0], [-1, 0, 0]]: p_y = chi_3 - chi_2 is first class.
    xd, yd, zd = sp.symbols("x_dot y_dot z_dot")
    s = nhham.System(["x", "y", "z"], (xd**2 + yd**2 + zd**2) / 2, [xd + yd],
                     holonomic=[S("x")])
    c = classify_constraints(s)
    assert c.bracket_matrix == sp.Matrix([[0, 1, 1], [-1, 0, 0], [-1, 0, 0]])
    assert c.first_class_combinations == (S("p_y"),)
    assert all(d.method == "exact" for d in c.decisions.values())


def test_sampled_mode_agrees_with_exact():
    s = handmade.sphere_with_knife()
    exact = classify_constraints(s, method="exact")
    sampled = classify_constraints(s, method="sampled")
    assert sampled.method == "sampled" and sampled.constraints is None
    assert (sampled.rank, sampled.second_class_set) == (exact.rank, exact.second_class_set)
    assert sampled.decisions["gamma[constraints[0]]"].value
    for B in sampled.bracket_samples:
        assert np.allclose(B, -B.T)


def test_classify_accepts_an_analysis():
    from nhham.lagrangian.analysis import analyze_constraints

    s = example_3_2()
    analysis = analyze_constraints(s)
    c = classify_constraints(analysis)
    assert c.analysis is analysis
    assert c.labels == tuple(analysis.final_labels)
    assert c.rank == 2 and c.first_class == 1


ALL = dict(__import__("nhham.system.models", fromlist=["MODELS"]).MODELS)
ALL["snake"] = lambda: __import__("nhham.system.models", fromlist=["snake"]).snake(3)


@pytest.mark.parametrize("name", sorted(ALL))
def test_every_model_classifies_consistently(name):
    c = classify_constraints(ALL[name]())
    k = len(c.labels)
    assert c.rank % 2 == 0 and c.second_class == c.rank == len(c.second_class_set)
    assert c.first_class + c.second_class == k
    assert len(c.combination_coefficients) == c.first_class
    for label in c.labels:
        if label not in c.second_class_set:
            assert c.decisions[f"gamma[{label}]"].value
    if c.method == "exact":
        assert len(c.first_class_combinations) == c.first_class
        B = c.bracket_matrix
        assert (B + B.T) == sp.zeros(k, k)


def test_sampled_points_where_C_is_not_finite_are_left_out():
    """W_theta = 1 + log(theta)^2 and x' = theta': M_1's equation is finite everywhere, but
    at its sample points with theta < 0, C^H = -(1 + 1/W_theta) and the bracket matrix are
    NaN (an SVD that did not converge: an internal error). Those points are left out; at
    the others C^H != 0. One constraint: {phi, phi} = 0, first class. (atan2 in V: no exact
    points, so float points decide.)"""
    s = nhham.System(["x", "theta"],
                     "(x_dot**2 + (1 + log(theta)**2)*theta_dot**2)/2 + atan2(x, 2)",
                     ["x_dot - theta_dot"])
    c = classify_constraints(s, method="sampled")
    assert c.rank == 0 and c.first_class == 1
