"""The paper's formulas written once (nhham.lagrangian.formulas), in every arithmetic.

The bracket {chi_a, chi_b}_L is checked against the canonical Poisson bracket on T*Q
computed by sympy from the Legendre transform (a second formulation), then the same
formula is evaluated at one rational point in every arithmetic nhham decides in:
rationals as lists and as DomainMatrix over QQ, residues modulo p as lists and over
GF(p), float64, and Degree bounds. They must agree (the residues with the reduction of
the rationals, the floats to rounding, the degree with the true degree). A defect
planted in one arithmetic (the modular solve) is caught by that comparison.
"""

from __future__ import annotations

import random

import numpy as np
import pytest
import sympy as sp
from sympy import GF, QQ
from sympy.external.gmpy import MPQ
from sympy.polys.matrices import DomainMatrix

from nhham.lagrangian import linalg
from nhham.lagrangian.domains import PRIME, Degree, ModP
from nhham.lagrangian.formulas import lagrangian_bracket
from nhham.lagrangian.linalg import FloatMatrix, ListMatrix, degree_solve

q1, q2, q3, v1, v2, v3 = sp.symbols("q1 q2 q3 v1 v2 v3")
p1, p2, p3 = sp.symbols("p1 p2 p3")
Q, V, P = (q1, q2, q3), (v1, v2, v3), (p1, p2, p3)


def _system():
    """L = v^T G(q) v / 2 + q1 v2 (a magnetic term: M - M^T != 0) and three constraints
    affine in v, with coefficients depending on q."""
    G = sp.Matrix([[2 + q2**2, q1, 0], [q1, 3, q3], [0, q3, 1 + q1**2 + q3**2]])
    L = (sp.Matrix(V).T * G * sp.Matrix(V))[0] / 2 + q1 * v2
    chis = [v1 + q2 * v3 - q1, q3 * v2 + v3, v1 * q1 + q2]
    return L, chis


def _data(L, chis, point):
    """Jq, Jv, W, M at ``point`` (a dict of exact rationals), as rows of sympy Rationals."""
    W = sp.hessian(L, V)
    pmom = [sp.diff(L, v) for v in V]
    M = sp.Matrix(3, 3, lambda a, b: sp.diff(pmom[a], Q[b]))
    Jq = sp.Matrix([[sp.diff(c, q) for q in Q] for c in chis])
    Jv = sp.Matrix([[sp.diff(c, v) for v in V] for c in chis])
    return [X.subs(point) for X in (Jq, Jv, W, M)]


def _poisson_reference(L, chis, point):
    """{chi_a o Leg^-1, chi_b o Leg^-1} by the canonical bracket on T*Q, at Leg(point)."""
    pmom = sp.Matrix([sp.diff(L, v) for v in V])
    vsol = sp.solve(list(pmom - sp.Matrix(P)), V, dict=True)[0]
    chis_H = [sp.simplify(c.subs(vsol)) for c in chis]
    at = {q: point[q] for q in Q}
    at.update({p: pmom[i].subs(point) for i, p in enumerate(P)})
    k = len(chis)
    out = sp.zeros(k, k)
    for a in range(k):
        for b in range(k):
            out[a, b] = sum(sp.diff(chis_H[a], Q[i]) * sp.diff(chis_H[b], P[i])
                            - sp.diff(chis_H[a], P[i]) * sp.diff(chis_H[b], Q[i])
                            for i in range(3)).subs(at)
    return out


def _point(seed):
    rng = random.Random(seed)
    return {s: sp.Rational(rng.randint(-9, 9), rng.randint(1, 5)) for s in Q + V}


def _mpq(x):
    x = sp.Rational(x)
    return MPQ(int(x.p), int(x.q))


def _in_every_arithmetic(data) -> dict:
    """The bracket at one point in each arithmetic, as rows (k x k)."""
    rows = [[[_mpq(x) for x in X.row(i)] for i in range(X.rows)] for X in data]
    Fp = GF(PRIME)
    out = {
        "QQ lists": lagrangian_bracket(*(ListMatrix(r) for r in rows)).to_list(),
        "QQ DomainMatrix": lagrangian_bracket(
            *(DomainMatrix([[QQ(x) for x in row] for row in r], (len(r), len(r[0])), QQ)
              for r in rows)).to_list(),
        "GF(p) lists": lagrangian_bracket(
            *(ListMatrix([[ModP.lift(x) for x in row] for row in r]) for r in rows)).to_list(),
        "GF(p) DomainMatrix": lagrangian_bracket(
            *(DomainMatrix([[Fp(int(x.numerator)) / Fp(int(x.denominator)) for x in row]
                            for row in r], (len(r), len(r[0])), Fp) for r in rows)).to_list(),
        "float64": lagrangian_bracket(
            *(FloatMatrix([[float(x) for x in row] for row in r]) for r in rows)).a.tolist(),
    }
    return out


def mismatches(data) -> list:
    """The arithmetics whose bracket disagrees with the exact rational one."""
    got = _in_every_arithmetic(data)
    exact = got["QQ lists"]
    bad = []
    if got["QQ DomainMatrix"] != exact:
        bad.append("QQ DomainMatrix")
    reduced = [[ModP.lift(x) for x in row] for row in exact]
    if got["GF(p) lists"] != reduced:
        bad.append("GF(p) lists")
    as_ints = [[int(ModP.lift(x).v) for x in row] for row in exact]
    if [[int(x) % PRIME for x in row] for row in got["GF(p) DomainMatrix"]] != as_ints:
        bad.append("GF(p) DomainMatrix")
    ref = np.array([[float(x) for x in row] for row in exact])
    if not np.allclose(np.array(got["float64"]), ref, rtol=1e-10, atol=1e-10 * abs(ref).max()):
        bad.append("float64")
    return bad


def _sympy_bracket(data):
    """The formula on sympy matrices (solve by sympy's LU): the value to compare with."""
    def solve(A, X):
        return ListMatrix(sp.Matrix(A.rows).LUsolve(sp.Matrix(X.rows)).tolist())

    B = lagrangian_bracket(*(ListMatrix(X.tolist()) for X in data), solve=solve)
    return sp.Matrix(B.rows)


@pytest.mark.parametrize("seed", range(4))
def test_bracket_is_the_canonical_bracket_through_leg(seed):
    L, chis = _system()
    point = _point(seed)
    data = _data(L, chis, point)
    if data[2].det() == 0:
        pytest.skip("W singular at this point")
    assert _sympy_bracket(data).applyfunc(sp.simplify) == _poisson_reference(L, chis, point)


@pytest.mark.parametrize("seed", range(6))
def test_every_arithmetic_gives_the_same_bracket(seed):
    L, chis = _system()
    data = _data(L, chis, _point(seed))
    if data[2].det() == 0:
        pytest.skip("W singular at this point")
    assert mismatches(data) == []


def test_degree_bound_bounds_the_true_degree():
    """The formula on Degree values bounds, entry by entry, the numerator degree of B in
    a coordinate left as a variable t."""
    t = sp.Symbol("t")
    L, chis = _system()
    data = _data(L, chis, {**_point(1), q1: t})
    true = _sympy_bracket(data).applyfunc(
        lambda x: sp.degree(sp.fraction(sp.cancel(x))[0], t) if x.has(t) else 0)
    degrees = [ListMatrix([[Degree(int(sp.degree(x, t))) if x.has(t) else Degree(0)
                            for x in X.row(i)] for i in range(X.rows)]) for X in data]
    bound = lagrangian_bracket(*degrees, solve=degree_solve).rows
    assert all(Degree.of(bound[a][b]).num >= true[a, b] for a in range(3) for b in range(3))
    assert max(true) > 0  # the variable reaches B: the bound is tested


def test_a_defect_planted_in_one_arithmetic_is_caught(monkeypatch):
    """A wrong modular solve (one entry off by one) changes the GF(p) bracket only; the
    cross-arithmetic comparison names that arithmetic."""
    L, chis = _system()
    data = _data(L, chis, _point(2))
    assert data[2].det() != 0 and mismatches(data) == []
    right = linalg.exact_solve

    def planted(A, b):
        X = right(A, b)
        if any(isinstance(x, ModP) for row in A for x in row):
            X[0][0] = X[0][0] + ModP(1)
        return X

    monkeypatch.setattr(linalg, "exact_solve", planted)
    assert mismatches(data) == ["GF(p) lists"]


def test_frobenius_terms_are_minus_mu_of_the_lie_bracket():
    """mu = dz - y dx (the contact form): on ker mu, dmu(X, Y) = -mu([X, Y]) computed by
    sympy's Lie bracket of the basis fields, at a point, in every arithmetic."""
    from nhham.lagrangian.formulas import frobenius_terms

    x, y, z = sp.symbols("x y z")
    q = (x, y, z)
    mu = sp.Matrix([[-y, 0, 1]])
    X, Y = sp.Matrix([1, 0, y]), sp.Matrix([0, 1, 0])  # the basis of the formula, dep = z
    lie = Y.jacobian(q) * X - X.jacobian(q) * Y
    expected = -(mu * lie)[0]
    at = {y: sp.Rational(3, 7)}
    D = [[[sp.diff(mu[0, B], q[A]) - sp.diff(mu[0, A], q[B]) for B in range(3)]
          for A in range(3)]]
    exact = frobenius_terms(ListMatrix([[_mpq(v.subs(at)) for v in mu]]),
                            [[[_mpq(v) for v in row] for row in D[0]]], [2])
    assert exact == {(0, 0, 1): expected.subs(at)} == {(0, 0, 1): 1}
    modular = frobenius_terms(ListMatrix([[ModP.lift(_mpq(v.subs(at))) for v in mu]]),
                              [[[ModP.lift(_mpq(v)) for v in row] for row in D[0]]], [2])
    assert modular == {(0, 0, 1): ModP(1)}
    floats = frobenius_terms(FloatMatrix([[float(v.subs(at)) for v in mu]]),
                             [[[float(v) for v in row] for row in D[0]]], [2])
    assert floats[(0, 0, 1)] == pytest.approx(1.0, abs=1e-15)


@pytest.mark.parametrize("seed", range(3))
def test_bordered_matrix_determinant_is_det_W_det_C(seed):
    """det [[W, mu^T], [mu, 0]] = det W det C with C = -mu W^-1 mu^T (Schur complement),
    C from sympy; in rationals (lists and DomainMatrix) and float64."""
    from nhham.lagrangian.formulas import bordered_matrix
    from nhham.lagrangian.linalg import field_det

    L, chis = _system()
    _, Jv, W, _ = _data(L, chis, _point(seed))
    if W.det() == 0:
        pytest.skip("W singular at this point")
    C = -Jv * W.inv() * Jv.T
    expected = W.det() * C.det()
    rows = [[[_mpq(x) for x in X.row(i)] for i in range(X.rows)] for X in (W, Jv)]
    K = bordered_matrix(ListMatrix(rows[0]), ListMatrix(rows[1]), ListMatrix(rows[1]))
    assert K.shape == (6, 6)
    dm = DomainMatrix(K.rows, (6, 6), QQ)
    assert sp.Rational(int(dm.det().numerator), int(dm.det().denominator)) == expected
    Kd = bordered_matrix(*(DomainMatrix([[QQ(x) for x in row] for row in r],
                                        (len(r), 3), QQ) for r in (rows[0], rows[1], rows[1])))
    assert Kd.det() == dm.det()
    Kf = bordered_matrix(*(FloatMatrix([[float(x) for x in row] for row in r])
                           for r in (rows[0], rows[1], rows[1])))
    assert field_det(Kf) == pytest.approx(float(expected), rel=1e-9)


def _saddle_data(seed):
    """W, mu (2 x 3), F, drift at a random rational point of the test system."""
    L, chis = _system()
    point = _point(seed)
    W = sp.hessian(L, V).subs(point)
    mu = sp.Matrix([[sp.diff(c, v) for v in V] for c in chis[:2]]).subs(point)
    F = sp.Matrix([sp.Rational(seed + 1, 3), -2, sp.Rational(5, 7)])
    drift = sp.Matrix([sp.Rational(1, 2), sp.Rational(-seed, 5)])
    return W, mu, F, drift


@pytest.mark.parametrize("seed", range(4))
def test_the_saddle_solve_is_the_bordered_system_solved_whole(seed):
    """constrained_motion (Schur complement) against sympy's LU solve of the whole
    saddle system [[W, mu^T], [mu, 0]] [a; lam] = [F; -drift], in QQ, GF(p) and float64;
    tangency_rows with chi = phi gives A = C and b = drift + mu W^-1 F."""
    from nhham.lagrangian.formulas import constrained_motion, tangency_rows

    W, mu, F, drift = _saddle_data(seed)
    if W.det() == 0 or (mu * W.inv() * mu.T).det() == 0:
        pytest.skip("singular at this point")
    whole = sp.Matrix(sp.BlockMatrix([[W, mu.T], [mu, sp.zeros(2, 2)]])).LUsolve(
        sp.Matrix.vstack(F, -drift))
    a_ref, lam_ref = list(whole[:3]), list(whole[3:])

    def lists(X):
        return ListMatrix([[_mpq(x) for x in X.row(i)] for i in range(X.rows)])

    a, lam, C = constrained_motion(lists(W), lists(mu), lists(F), lists(drift))
    assert [r[0] for r in a.rows] == a_ref and [r[0] for r in lam.rows] == lam_ref
    assert C.rows == [[_mpq(x) for x in (-(mu * W.inv() * mu.T)).row(i)] for i in range(2)]
    A, b = tangency_rows(lists(W), lists(mu), lists(F), lists(drift), lists(mu))
    assert A.rows == C.rows
    assert [r[0] for r in b.rows] == [_mpq(x) for x in drift + mu * W.inv() * F]

    def residues(X):
        return ListMatrix([[ModP.lift(_mpq(x)) for x in X.row(i)] for i in range(X.rows)])

    a_p, lam_p, _ = constrained_motion(*(residues(X) for X in (W, mu, F, drift)))
    assert [r[0] for r in a_p.rows] == [ModP.lift(_mpq(x)) for x in a_ref]
    assert [r[0] for r in lam_p.rows] == [ModP.lift(_mpq(x)) for x in lam_ref]
    a_f, lam_f, _ = constrained_motion(
        *(FloatMatrix(np.array(X.tolist(), dtype=float).ravel() if X.cols == 1
                      else np.array(X.tolist(), dtype=float)) for X in (W, mu, F, drift)),
        solve=lambda A, X: FloatMatrix(np.linalg.solve(A.a, X.a)))
    assert np.allclose(a_f.a, [float(x) for x in a_ref], rtol=1e-12)
    assert np.allclose(lam_f.a, [float(x) for x in lam_ref], rtol=1e-12)
