"""First-class combinations in closed form when the classes are decided at points.

Systems whose W depends on q and is not diagonal (a dynamic car with a trailer, the
differential drive with its mass ahead of the axle) are classified at exact points
of M_f. They used to report "first class 1" with an empty list of combinations.

Hand derivations, for L = T purely kinetic and constraints linear in v: with
X_a = W^{-1} mu_a (a vector field on Q), chi_a o Leg^{-1} = X_a . p and
{chi_a, chi_b} = -p . [X_a, X_b]. Three constraints with rank B = 2 leave one
first-class combination, along the kernel of the antisymmetric 3 x 3 matrix B:
c = (B_23, -B_13, B_12). In coordinates where W is diagonal the X_a, hence the
brackets, are short; a point transformation (x, y) -> (x + d cos theta,
y + d sin theta) carries them to the scene's coordinates, with p_x, p_y unchanged
and p_theta(G) = p_theta - d (-p_x sin theta + p_y cos theta).
"""

import random
from pathlib import Path

import pytest
import sympy as sp

import nhham
from nhham.hamiltonian.classification import classify_constraints
from nhham.hamiltonian.combinations import NotFormed, closed_form_combinations
from nhham.system.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
S = sp.Symbol


def e(p, angle):
    """p . (cos a, sin a)."""
    return p[0] * sp.cos(angle) + p[1] * sp.sin(angle)


def n(p, angle):
    """p . (-sin a, cos a)."""
    return -p[0] * sp.sin(angle) + p[1] * sp.cos(angle)


def car_with_trailer():
    """A car (rear-axle midpoint x, y; heading theta; steering psi; wheelbase l) whose mass
    centre is d ahead of the rear axle, towing from the rear-axle midpoint a trailer of
    heading beta with its axle lt behind the hitch (inertia K about the hitch).

    L = m |v_G|^2 / 2 + I theta'^2 / 2 + J psi'^2 / 2 + K beta'^2 / 2 with
    v_G = v + d theta' (-sin theta, cos theta): W is not diagonal and depends on theta.
    Constraints (no side slip): rear axle, front axle at l e_theta (its wheels turned by
    psi), trailer axle at -lt e_beta.
    """
    x, y, th, ps, be = sp.symbols("x y theta psi beta")
    xd, yd, thd, psd, bed = sp.symbols("x_dot y_dot theta_dot psi_dot beta_dot")
    m, I, J, K, d, l, lt = sp.symbols("m I J K d l lt")
    vG = (xd - d * thd * sp.sin(th), yd + d * thd * sp.cos(th))
    L = m * (vG[0] ** 2 + vG[1] ** 2) / 2 + I * thd**2 / 2 + J * psd**2 / 2 + K * bed**2 / 2
    rear = -xd * sp.sin(th) + yd * sp.cos(th)
    front = -(xd - l * thd * sp.sin(th)) * sp.sin(th + ps) \
        + (yd + l * thd * sp.cos(th)) * sp.cos(th + ps)
    trailer = -(xd + lt * bed * sp.sin(be)) * sp.sin(be) + (yd - lt * bed * sp.cos(be)) * sp.cos(be)
    return nhham.System([x, y, th, ps, be], sp.expand(L), [rear, front, trailer],
                        parameters={"m": 1200.0, "I": 1500.0, "J": 3.0, "K": 400.0,
                                    "d": 1.2, "l": 2.6, "lt": 3.0},
                        name="car with trailer")


def car_kernel():
    """(B_23, -B_13, B_12) by hand, in the scene's (x, y) momenta (see the module doc).

    In G coordinates W = diag(m, m, I, J, K) and
      X_1 = (n_theta / m, -d / I, 0, 0), X_2 = (n_{theta+psi} / m, (l - d) cos psi / I, 0, 0),
      X_3 = (n_beta / m, -d cos(theta - beta) / I, 0, -lt / K);
    d/dtheta n_theta = -e_theta etc. give
      [X_1, X_2] = (d e_{theta+psi} + (l - d) cos psi e_theta) / (I m)       (x, y part),
      [X_1, X_3] = (-d cos(theta - beta) e_theta / (I m), -d^2 sin(theta - beta) / I^2),
      [X_2, X_3] = (-d cos(theta - beta) e_{theta+psi} / (I m),
                    (l - d) d cos psi sin(theta - beta) / I^2)              (x, y; theta),
    and B_ab = -p . [X_a, X_b].
    """
    th, ps, be = sp.symbols("theta psi beta")
    m, I, d, l = sp.symbols("m I d l")
    p = sp.symbols("p_x p_y")
    pth = S("p_theta") - d * n(p, th)           # p_theta in G coordinates
    B12 = -(d * e(p, th + ps) + (l - d) * sp.cos(ps) * e(p, th)) / (I * m)
    B13 = d * sp.cos(th - be) * e(p, th) / (I * m) + d**2 * sp.sin(th - be) * pth / I**2
    B23 = d * sp.cos(th - be) * e(p, th + ps) / (I * m) \
        - (l - d) * d * sp.cos(ps) * sp.sin(th - be) * pth / I**2
    return [B23, -B13, B12]


def proportional(coefficients, labels, kernel, names, trials=4):
    """The coefficients {label: c_a} are parallel to the hand kernel (values at random
    points, 30 digits): c_a h_b = c_b h_a for every pair."""
    rng = random.Random(7)
    c = [coefficients.get(lab, 0) for lab in labels]
    symbols = set().union(*[sp.sympify(x).free_symbols for x in c + kernel])
    for _ in range(trials):
        point = {s: sp.Rational(rng.randint(1, 97), rng.randint(5, 40)) for s in symbols}
        cv = [sp.N(sp.sympify(x).subs(point), 30) for x in c]
        hv = [sp.N(x.subs(point), 30) for x in kernel]
        scale = max(abs(x) for x in cv) * max(abs(x) for x in hv)
        for a in range(3):
            for b in range(a + 1, 3):
                assert abs(cv[a] * hv[b] - cv[b] * hv[a]) <= 1e-25 * scale, (names, a, b)


def test_car_with_trailer_combination_matches_the_hand_kernel():
    system = car_with_trailer()
    classes = classify_constraints(system)
    assert classes.method != "exact"            # W(q) not diagonal: decided at points
    assert (classes.first_class, classes.second_class) == (1, 2)
    assert classes.first_class_combinations is not None
    assert len(classes.first_class_combinations) == 1
    coeffs = classes.combination_coefficients[0]
    proportional(coeffs, classes.labels, car_kernel(), "car with trailer")
    # the combination is sum_a c_a (chi_a o Leg^-1): check it against its coefficients
    leg = nhham.legendre_map(system)
    chi_h = [leg.transport(c) for c in system.phi]
    gamma = classes.first_class_combinations[0]
    rebuilt = sum(coeffs.get(lab, 0) * c for lab, c in zip(classes.labels, chi_h))
    rng = random.Random(3)
    for _ in range(3):
        point = {s: sp.Rational(rng.randint(1, 50), 13) for s in gamma.free_symbols
                 | rebuilt.free_symbols}
        assert abs(sp.N((gamma - rebuilt).subs(point), 30)) < 1e-20


def test_car_without_offset_tows_a_first_class_trailer():
    """d = 0: B_13 = B_23 = 0 (the brackets above), so the trailer's constraint is first
    class by itself, chi_3 o Leg^{-1} = (-p_x sin beta + p_y cos beta) / m - lt p_beta / K.
    (W is then diagonal: the exact path; the closed-form one must agree.)"""
    system = car_with_trailer()
    flat = nhham.System(system.coordinates, system.lagrangian.subs(S("d"), 0),
                        [c.subs(S("d"), 0) for c in system.phi], parameters=["m", "I", "J",
                                                                             "K", "l", "lt"])
    px, py, pb = sp.symbols("p_x p_y p_beta")
    m, K, lt, be = sp.symbols("m K lt beta")
    hand = n((px, py), be) / m - lt * pb / K
    gammas, coeffs = closed_form_combinations(flat, list(flat.phi), [0, 1])
    assert sp.simplify(gammas[0] - hand) == 0
    assert coeffs[0] == {2: 1}
    exact = classify_constraints(flat)
    assert exact.method == "exact" and sp.simplify(exact.first_class_combinations[0] - hand) == 0


def test_differential_drive_example_combination():
    """examples/differential_drive.toml: mass mc at d ahead of the axle, wheels mw at +-b.
    With x, y moved to the whole robot's mass centre (d' = mc d / M, M = mc + 2 mw) W is
    diag(M, M, J', Iw, Iw) and, as for the car (X_1 = (n/M, -d'/J', 0, 0),
    X_{2,3} = (e/M, -+b/J', -r/Iw or 0)): B_12 = (b u - d' w)/(J' M),
    B_13 = -(b u + d' w)/(J' M), B_23 = -2 b w/(J' M) with u = p.e_theta,
    w = p.(sin theta, -cos theta). Kernel (times M): (-2 b M w, mc d w + b M u,
    b M u - mc d w)."""
    scene = load_scene(EXAMPLES / "differential_drive.toml")
    classes = classify_constraints(scene.system)
    assert (classes.first_class, classes.second_class) == (1, 2)
    th = S("theta")
    b, mc, mw, d = sp.symbols("b mc mw d")
    p = sp.symbols("p_x p_y")
    M, u, w = mc + 2 * mw, e(p, th), -n(p, th)
    kernel = [-2 * b * M * w, mc * d * w + b * M * u, b * M * u - mc * d * w]
    proportional(classes.combination_coefficients[0], classes.labels, kernel, "drive")


def test_not_formed_is_said():
    """Beyond the size bound the combinations stay None and a warning says so."""
    system = car_with_trailer()
    try:
        closed_form_combinations(system, list(system.phi), [0, 1], max_terms=5)
    except NotFormed as exc:
        assert "terms" in str(exc)
    else:
        raise AssertionError("a 5-term bound should not be met")


def test_curvilinear_pair_combinations_are_first_class():
    """examples/curvilinear_pair.toml: 6 final constraints, 4 second class (a 4 x 4 block:
    the sub-Pfaffians beyond 3 x 3). By hand on T*Q the final constraints are
    p_q1 - p_q3 + p_q6 cos q3, p_q2 sin q4 + p_q4 - p_q6, q1, q4, p_q1, p_q2 sin q4 + p_q4,
    so on M_f q1 = q4 = 0 and p_q1 = p_q3 = p_q4 = p_q6 = 0; each reported combination must
    vanish there and bracket to zero with every constraint there (canonical brackets
    written out here, not nhham's)."""
    system = load_scene(EXAMPLES / "curvilinear_pair.toml").system
    classes = classify_constraints(system)
    assert (classes.first_class, classes.second_class) == (2, 4)
    q = [S(f"q{i}") for i in range(1, 7)]
    p = [S(f"p_q{i}") for i in range(1, 7)]
    chi = [p[0] - p[2] + p[5] * sp.cos(q[2]), p[1] * sp.sin(q[3]) + p[3] - p[5], q[0], q[3],
           p[0], p[1] * sp.sin(q[3]) + p[3]]
    on_mf = {q[0]: 0, q[3]: 0, p[0]: 0, p[2]: 0, p[3]: 0, p[5]: 0}

    def bracket(f, g):
        return sum(sp.diff(f, a) * sp.diff(g, b) - sp.diff(f, b) * sp.diff(g, a)
                   for a, b in zip(q, p))

    assert len(classes.first_class_combinations) == 2
    for gamma in classes.first_class_combinations:
        assert sp.simplify(gamma.xreplace(on_mf)) == 0
        for c in chi:
            assert sp.simplify(bracket(gamma, c).xreplace(on_mf)) == 0
    # and they are independent: not proportional on M_f
    g1, g2 = classes.first_class_combinations
    assert sp.simplify(sp.diff(g1, p[2]) * sp.diff(g2, p[5])
                       - sp.diff(g1, p[5]) * sp.diff(g2, p[2])) != 0


def test_a_closed_form_beyond_reach_is_given_up_quickly():
    """The 3-link snake's bracket entries are products of polynomials of thousands of terms
    (100 s to reach the term bound): refused before they are formed, with the reason."""
    from nhham.system import models

    system = models.snake(3)
    with pytest.raises(NotFormed, match="product of polynomials|within"):
        closed_form_combinations(system, list(system.phi), [0, 1])
