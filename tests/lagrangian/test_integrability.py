"""Frobenius integrability of D = ker mu (is a 'nonholonomic' constraint set holonomic?).

Expected verdicts are derived by hand from dmu_i ^ mu_1 ^ ... ^ mu_m = 0, and the
reported obstruction is checked against an independent Lie bracket computed here:
for X, Y in ker mu, mu_i([X, Y]) = -dmu_i(X, Y).
"""

import pytest
import sympy as sp

from nhham.lagrangian.engine import Policy
from nhham import System
from nhham.lagrangian.integrability import frobenius, integrability
from nhham.lagrangian.submanifold import Submanifold

q1, q2, q3, q4 = sp.symbols("q1 q2 q3 q4")
v1, v2, v3, v4 = sp.symbols("q1_dot q2_dot q3_dot q4_dot")
T3 = (v1**2 + v2**2 + v3**2) / 2
T4 = T3 + v4**2 / 2


def lie_bracket(X, Y, q):
    """[X, Y]^A = X^B d_B Y^A - Y^B d_B X^A, computed independently of nhham."""
    X, Y = sp.Matrix(X), sp.Matrix(Y)
    return Y.jacobian(q) * X - X.jacobian(q) * Y


def heisenberg(eps=1):
    """phi = v3 - eps q1 v2: mu = dq3 - eps q1 dq2, dmu = -eps dq1 ^ dq2,
    dmu ^ mu = -eps dq1 ^ dq2 ^ dq3 != 0: not integrable."""
    return System(["q1", "q2", "q3"], T3, [v3 - eps * q1 * v2])


def test_heisenberg_is_not_integrable_and_obstruction_is_a_bracket():
    res = integrability(heisenberg())
    assert res.integrable is False and res.method == "exact" and res.rank == 2
    mu = sp.Matrix([[0, -q1, 1]])
    B = res.basis
    assert (mu * B).applyfunc(sp.simplify) == sp.zeros(1, 2)
    assert B.rank() == 2
    label, a, b, value = res.obstructions[0]
    assert label == "constraints[0]"
    bracket = lie_bracket(B[:, a], B[:, b], [q1, q2, q3])
    assert sp.simplify((mu * bracket)[0] + value) == 0
    assert sp.simplify(value) != 0
    assert "not integrable" in res.describe()


def test_rolling_disk_is_not_integrable():
    """D = span{d_theta, d_phi + R c d_x + R s d_y}; [d_theta, X2] = -R s d_x + R c d_y,
    mu_1 of it = -R sin(theta) != 0."""
    xd, yd, phd = sp.symbols("x_dot y_dot phi_dot")
    th, R = sp.symbols("theta R")
    s = System(["x", "y", "theta", "phi"], (xd**2 + yd**2 + phd**2) / 2
               + sp.Symbol("theta_dot")**2 / 2,
               [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd], parameters=["R"])
    res = integrability(s)
    assert res.integrable is False and res.method == "exact"


def test_exact_form_is_integrable_with_first_integral():
    """phi = q2 v1 + q1 v2 = d(q1 q2)/dt: mu = d(q1 q2) is closed."""
    s = System(["q1", "q2", "q3"], T3, [q2 * v1 + q1 * v2])
    res = integrability(s)
    assert res.integrable is True and res.method == "exact" and res.obstructions == ()
    assert res.first_integrals == (("constraints[0]", q1 * q2),)
    assert "integrable (holonomic in disguise)" in res.describe()


def test_integrable_with_integrating_factor():
    """mu1 = q3 d(q1 + q2) (not closed, integrating factor 1/q3), mu2 = d(q1 - q4):
    dmu1 = dq3 ^ d(q1 + q2), and dmu1 ^ mu1 ^ mu2 = 0 because d(q1 + q2) appears twice;
    dmu2 = 0.  Integrable; only mu2 has a potential."""
    s = System(["q1", "q2", "q3", "q4"], T4, [q3 * (v1 + v2), v1 - v4])
    res = integrability(s)
    assert res.integrable is True
    assert res.first_integrals == (("constraints[0]", None), ("constraints[1]", q1 - q4))


def test_affine_constraints_concern_the_linear_part():
    """phi = v1 - 1: linear part dq1 (integrable; motion q1 = t + c).
    phi = v1 + q2 v3 + 1: linear part dq1 + q2 dq3, dmu ^ mu = dq2 ^ dq3 ^ dq1 != 0."""
    assert integrability(System(["q1", "q2", "q3"], T3, [v1 - 1])).integrable is True
    res = integrability(System(["q1", "q2", "q3"], T3, [v1 + q2 * v3 + 1]))
    assert res.integrable is False


def test_decided_on_Q1_where_the_motion_happens():
    """g = q4 (lift v4) and phi = v1 - q4 q2 v3.  On Q: dmu ^ dq4 ^ mu =
    -q4 dq2 ^ dq3 ^ dq4 ^ dq1 != 0 off q4 = 0, but on Q_1 = {q4 = 0} it vanishes, so the
    distribution is integrable where the motion takes place.  Without g it is not."""
    with_g = System(["q1", "q2", "q3", "q4"], T4, [v1 - q4 * q2 * v3], holonomic=[q4])
    res = integrability(with_g)
    assert res.integrable is True
    assert res.labels == ("holonomic[0].lift", "constraints[0]")
    without = System(["q1", "q2", "q3", "q4"], T4, [v1 - q4 * q2 * v3])
    assert integrability(without).integrable is False


def test_low_rank_distributions_are_integrable():
    """n - m <= 1: a line field is always integrable; m = 0: D = TQ."""
    s = System(["q1", "q2"], (v1**2 + v2**2) / 2, [v1 - q1 * q2 * v2])
    assert integrability(s).integrable is True
    free = System(["q1", "q2"], (v1**2 + v2**2) / 2)
    assert integrability(free).integrable is True


def test_generic_frobenius_on_a_submanifold_of_Q():
    system = heisenberg()
    Q = Submanifold(system, (), fibre=())
    res = frobenius(sp.Matrix([[0, -q1, 1]]), [q1, q2, q3], Q, labels=["heis"])
    assert res.integrable is False and res.obstructions[0][0] == "heis"


CASES = [
    (heisenberg, False),
    (lambda: System(["q1", "q2", "q3"], T3, [q2 * v1 + q1 * v2]), True),
    (lambda: System(["q1", "q2", "q3", "q4"], T4, [q3 * (v1 + v2), v1 - v4]), True),
    (lambda: System(["q1", "q2", "q3", "q4"], T4, [v1 - q4 * q2 * v3], holonomic=[q4]), True),
]


@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("precision", [None, 30], ids=["float64", "mp30"])
def test_sampled_agrees_with_exact(case, precision):
    make, expected = CASES[case]
    res = integrability(make(), policy=Policy(exact=False, precision=precision))
    assert res.integrable is expected and res.method == "sampled" and res.warnings == ()


def test_tiny_obstruction_is_undecided_in_float64():
    """eps = 1e-11 hidden in a cancellation: mu = dq3 - q1 (sin^2 q3 + cos^2 q3 - 1 + eps) dq2,
    so dmu ^ mu = -eps dq1 ^ dq2 ^ dq3 is exactly nonzero, but float64 sampling sees a
    value about eps/2 of the size of its terms, below its tolerance but above its zero
    level, and must not choose."""
    eps = sp.Rational(1, 10**11)
    c = sp.sin(q3)**2 + sp.cos(q3)**2 - 1 + eps
    s = System(["q1", "q2", "q3"], T3, [v3 - c * q1 * v2])
    assert integrability(s).integrable is False
    f64 = integrability(s, policy=Policy(exact=False))
    assert f64.integrable is None and f64.warnings
    assert "undecided" in f64.describe()
    assert integrability(s, policy=Policy(exact=False, precision=30)).integrable is False


def test_small_obstruction_is_decided_whatever_the_units():
    """eps = 1e-11 as a coefficient (a choice of units for q2): dmu ^ mu = -eps dq1 ^ dq2 ^ dq3
    is one term, as far from zero as with eps = 1, so sampling decides it too."""
    for eps in (sp.Rational(1, 10**11), sp.Integer(10**11)):
        assert integrability(heisenberg(eps), policy=Policy(exact=False)).integrable is False


def _with_circle(constraints):
    """Six coordinates, a holonomic circle a^2 + b^2 = 1 (no exact points of Q_1)."""
    names = ["x", "y", "theta", "phi", "a", "b"]
    L = " + ".join(f"{n}_dot**2/2" for n in names)
    return System(names, L, constraints, holonomic=["a**2 + b**2 - 1"], parameters={"R": 1.0})


def test_frobenius_on_a_curved_Q1():
    """The rolling disk's distribution beside a circle: not integrable (dmu_1 = R sin(theta)
    dtheta ^ dphi on D, as in the symbolic test above), proved at a point of the curved
    Q_1 over F_p and said so; at sampled points too. x_dot - y_dot beside it: closed,
    integrable, at sampled points (the circle has no rational points for the bound)."""
    from nhham.lagrangian.integrability import frobenius_sampled

    rolling = _with_circle(["x_dot - R*cos(theta)*phi_dot", "y_dot - R*sin(theta)*phi_dot"])
    res = integrability(rolling)
    assert res.integrable is False and res.method == "exact"
    (_, proof), = res.decisions
    assert proof.error_bound == 0.0 and proof.scope.startswith("M is curved")
    assert "on the component of M through it" in proof.detail
    sampled = frobenius_sampled(rolling, ("holonomic[0].lift", "constraints[0]",
                                          "constraints[1]"))
    assert sampled.integrable is False and sampled.method == "sampled"
    closed = _with_circle(["x_dot - y_dot"])
    res = frobenius_sampled(closed, ("holonomic[0].lift", "constraints[0]"))
    assert res.integrable is True and res.method == "sampled"
