"""Bracket algebra: canonical bracket identities (hypothesis), Hamiltonian fields,
lazy cached bracket matrices, the Dirac bracket on the particle on a sphere."""

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import nhham
from nhham.hamiltonian.brackets import (
    BivectorBracket,
    BracketAlgebra,
    canonical_bracket,
    connected_blocks,
    hamiltonian_vector_field,
    jacobiator,
    numeric_bracket_matrix,
)
from nhham.hamiltonian.classification import classify_constraints
from nhham.hamiltonian.dirac import dirac_bracket
from nhham.hamiltonian.legendre import canonical_form_matrix

q1, q2, p1, p2 = sp.symbols("q1 q2 p_q1 p_q2")
Q, P = (q1, q2), (p1, p2)
VARS = (q1, q2, p1, p2)

SETTINGS = settings(max_examples=25, deadline=None)


def S(name):
    return sp.Symbol(name)


@st.composite
def functions(draw):
    """Random sums of (integer) x (monomial of degree <= 2 per variable) x (optional sin/cos)."""
    terms = []
    for _ in range(draw(st.integers(1, 3))):
        c = draw(st.integers(-3, 3).filter(bool))
        mono = sp.Mul(*[v ** draw(st.integers(0, 2)) for v in VARS])
        trig = draw(st.sampled_from([None, sp.sin, sp.cos]))
        if trig is not None:
            mono *= trig(draw(st.sampled_from(VARS)))
        terms.append(c * mono)
    return sp.Add(*terms)


def br(f, g):
    return canonical_bracket(f, g, Q, P)


@SETTINGS
@given(functions(), functions())
def test_antisymmetry(f, g):
    assert sp.expand(br(f, g) + br(g, f)) == 0


@SETTINGS
@given(functions(), functions(), functions())
def test_leibniz(f, g, h):
    assert sp.expand(br(f, g * h) - br(f, g) * h - g * br(f, h)) == 0


@settings(max_examples=15, deadline=None)
@given(functions(), functions(), functions())
def test_jacobi(f, g, h):
    assert sp.expand(jacobiator(br, f, g, h, simplify=sp.expand)) == 0


def test_canonical_relations_and_hamiltonian_field():
    for i, (qa, pa) in enumerate(zip(Q, P)):
        for j, (qb, pb) in enumerate(zip(Q, P)):
            assert br(qa, pb) == (1 if i == j else 0)
            assert br(qa, qb) == 0 and br(pa, pb) == 0
    f = q1**2 * p2 + sp.sin(q2) * p1
    g = p1 * p2 + q1
    Xf = hamiltonian_vector_field(f, Q, P)
    Xg = hamiltonian_vector_field(g, Q, P)
    grad = lambda h: sp.Matrix([sp.diff(h, v) for v in VARS])  # noqa: E731
    Omega = canonical_form_matrix(2)
    # i_{X_f} omega_Q = df:  (i_X omega)(Y) = X^T Omega Y, so Omega^T X_f = df.
    assert (Omega.T * Xf - grad(f)).applyfunc(sp.expand) == sp.zeros(4, 1)
    # X_f(g) = {g, f} and {f, g} = omega(X_f, X_g).
    assert sp.expand((grad(g).T * Xf)[0] - br(g, f)) == 0
    assert sp.expand((Xf.T * Omega * Xg)[0] - br(f, g)) == 0


def test_algebra_caches_and_serves_antisymmetry():
    alg = BracketAlgebra(Q, P)
    f, g = q1 * p2, sp.cos(q2) * p1
    b = alg.bracket(f, g)
    assert (f, g) in alg._brackets
    assert alg.bracket(g, f) == -b
    assert (g, f) not in alg._brackets  # served from the cached (f, g)
    assert alg.bracket(f, f) == 0
    assert sp.expand(b - br(f, g)) == 0
    assert (alg.hamiltonian_field(f) - hamiltonian_vector_field(f, Q, P)) == sp.zeros(4, 1)


def test_bracket_matrix_is_lazy():
    alg = BracketAlgebra(Q, P)
    fs = [q1, p1, q2 * p2]
    B = alg.bracket_matrix(fs)
    assert alg._brackets == {}
    assert B[0, 1] == 1
    assert len(alg._brackets) == 1
    M = B.matrix
    assert M == sp.Matrix([[0, 1, 0], [-1, 0, 0], [0, 0, 0]])
    # Only the upper triangle was computed.
    assert len(alg._brackets) == 3
    rect = alg.bracket_matrix([q1], [p1, p2])
    assert rect.matrix == sp.Matrix([[1, 0]])


def test_numeric_bracket_matrix_matches_symbolic():
    fs = [q1 * p2, sp.sin(q2) * p1 + q1]
    alg = BracketAlgebra(Q, P)
    pt = {q1: 0.3, q2: -0.7, p1: 1.1, p2: 0.4}
    Gq = np.array([[float(sp.diff(f, v).subs(pt)) for v in Q] for f in fs])
    Gp = np.array([[float(sp.diff(f, v).subs(pt)) for v in P] for f in fs])
    sym = np.array(alg.bracket_matrix(fs).matrix.subs(pt), dtype=float)
    assert np.allclose(numeric_bracket_matrix(Gq, Gp), sym)
    # {f_a, g_b} against other functions g = (q2, p1): Gq Hp^T - Gp Hq^T by hand
    Hq, Hp = np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0, 0.0], [1.0, 0.0]])
    other = np.array(sp.Matrix([[alg.bracket(f, g) for g in (q2, p1)] for f in fs]).subs(pt),
                     dtype=float)
    assert np.allclose(numeric_bracket_matrix(Gq, Gp, Hq, Hp), other)
    with pytest.raises(TypeError, match="both Hq and Hp"):
        numeric_bracket_matrix(Gq, Gp, Hq)


def test_connected_blocks():
    nz = np.zeros((5, 5), dtype=bool)
    nz[0, 3] = nz[3, 0] = True
    nz[1, 2] = nz[2, 1] = True
    assert connected_blocks(nz) == [[0, 3], [1, 2], [4]]


def test_bivector_bracket_of_the_canonical_tensor_is_poisson():
    bb = BivectorBracket(canonical_form_matrix(2), VARS)
    assert bb.jacobiator_tensor() == {}
    f, g = q1 * p2**2, sp.sin(p1) * q2
    assert sp.expand(bb(f, g) - br(f, g)) == 0


# -------------------------------------------------------------- Dirac bracket
def sphere():
    """Particle of mass m on the sphere x^2 + y^2 + z^2 = R^2 (no gravity: g = 0 would be
    the same bracket)."""
    x, y, z = sp.symbols("x y z")
    xd, yd, zd = sp.symbols("x_dot y_dot z_dot")
    m, g, R = sp.symbols("m g R")
    L = m * (xd**2 + yd**2 + zd**2) / 2 - m * g * z
    return nhham.System(["x", "y", "z"], L, holonomic=[(x**2 + y**2 + z**2 - R**2) / 2],
                        parameters={"m": 1.3, "g": 9.81, "R": 0.9})


@pytest.fixture(scope="module")
def sphere_dirac():
    """The Dirac bracket of the particle on a sphere, and its variables x, y, z, p_x, p_y, p_z."""
    s = sphere()
    D = dirac_bracket(s)
    return D, (*s.coordinates, *D.algebra.momenta)


def test_sphere_dirac_bracket_hand_values(sphere_dirac):
    # chi_1 = (r^2 - R^2)/2, chi_2 = (x p_x + y p_y + z p_z)/m (the lift, transported).
    # B_12 = {chi_1, chi_2} = grad(chi_1) . d chi_2/dp = r^2/m, so B^{-1} = [[0, -m/r^2], [m/r^2, 0]]
    # {q_i, p_j}_D = delta_ij - {q_i, chi_1}B^{12}{chi_2, p_j} - {q_i, chi_2}B^{21}{chi_1, p_j}
    #             = delta_ij - (x_i/m)(m/r^2) x_j = delta_ij - x_i x_j / r^2,
    # {q_i, q_j}_D = 0 and {p_i, p_j}_D = (x_i p_j - x_j p_i)/r^2 ... checked below.
    D, (x, y, z, px, py, pz) = sphere_dirac
    r2 = x**2 + y**2 + z**2
    X, Pm = (x, y, z), (px, py, pz)
    assert D.blocks == [[0, 1]]
    assert sp.simplify(D.matrix[0, 1] - r2 / S("m")) == 0
    for i in range(3):
        for j in range(3):
            assert sp.simplify(D(X[i], Pm[j]) - ((1 if i == j else 0) - X[i] * X[j] / r2)) == 0
            assert D(X[i], X[j]) == 0
    # {p_x, p_y}_D: -{p_x, chi_1}B^{12}{chi_2, p_y} - {p_x, chi_2}B^{21}{chi_1, p_y}
    # with {p_x, chi_1} = -x, {chi_2, p_y} = p_y/m, {p_x, chi_2} = -p_x/m, {chi_1, p_y} = y:
    # = -(-x)(-m/r^2)(p_y/m) - (-p_x/m)(m/r^2)(y) = (y p_x - x p_y)/r^2.
    assert sp.simplify(D(px, py) - (y * px - x * py) / r2) == 0


@settings(max_examples=8, deadline=None)
@given(st.data())
def test_sphere_dirac_second_class_constraints_are_casimirs(sphere_dirac, data):
    D, (x, y, z, px, py, pz) = sphere_dirac
    pool = [x, y, z, px, py, pz, sp.sin(x), x * pz - z * px, px**2 + py * z]
    f = data.draw(st.sampled_from(pool)) * data.draw(st.sampled_from(pool)) + \
        data.draw(st.sampled_from(pool))
    for chi in D.constraints:
        assert sp.simplify(D(chi, f)) == 0


def test_sphere_dirac_jacobi_identity(sphere_dirac):
    D, (x, y, z, px, py, pz) = sphere_dirac
    triples = [(x, y, px), (x, px, py), (px, py, pz), (x * py, z, px), (x * px + y, py, pz**2),
               (sp.sin(x), py, z * pz)]
    for f, g, h in triples:
        assert sp.simplify(D.jacobiator(f, g, h)) == 0, (f, g, h)


def test_dirac_bracket_antisymmetric_and_block_decomposed():
    """Two independent particles on circles: B has two 2x2 blocks, inverted separately;
    the result equals the bracket with the full inverse of B."""
    x1, y1, x2, y2 = sp.symbols("x1 y1 x2 y2")
    v = sp.symbols("x1_dot y1_dot x2_dot y2_dot")
    L = sum(w**2 for w in v) / 2
    s = nhham.System(["x1", "y1", "x2", "y2"], L,
                     holonomic=[x1**2 + y1**2 - 1, x2**2 + y2**2 - 4])
    classes = classify_constraints(s, method="exact")
    D = dirac_bracket(classes)
    assert classes.second_class == 4 and classes.first_class == 0
    assert [len(b) for b in D.blocks] == [2, 2]
    full = D.matrix.inv()
    ps = D.algebra.momenta
    f, g = x1 * ps[1] + ps[2], y2 * ps[0] * ps[3]
    alg = D.algebra
    ref = alg.bracket(f, g) - sum(
        alg.bracket(f, D.constraints[a]) * full[a, b] * alg.bracket(D.constraints[b], g)
        for a in range(4) for b in range(4))
    assert sp.simplify(D(f, g) - ref) == 0
    assert sp.simplify(D(f, g) + D(g, f)) == 0


@settings(max_examples=6, deadline=None)
@given(st.data())
def test_sphere_dirac_jacobi_random_triples(sphere_dirac, data):
    D, (x, y, z, px, py, pz) = sphere_dirac
    pool = [x, y, z, px, py, pz, x * py - y * px, pz**2, sp.cos(y)]
    f, g, h = (data.draw(st.sampled_from(pool)) * data.draw(st.sampled_from(pool))
               for _ in range(3))
    assert sp.simplify(D.jacobiator(f, g, h)) == 0
