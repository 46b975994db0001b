"""Points over F_p of curved configuration spaces (nhham.lagrangian.curved).

Every point is checked against the constraints written out by hand in plain modular
integers (not through the evaluator that found it); the verdicts on curved M_1 against
what holds at the parameter values.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import sympy as sp

import nhham
from nhham import Policy
from nhham.lagrangian.curved import curved_chart
from nhham.lagrangian.domains import PRIME, Angle, ModP, NotExact, square_root
from nhham.lagrangian.points import PointSampler, circle_parameters, exact_sampler
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.models import particle_on_sphere
from nhham.system.scene import load_scene

P = PRIME
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _value(x) -> int:
    x = x.r if isinstance(x, Angle) else x
    return x.v if isinstance(x, ModP) else ModP.lift(x).v


def test_points_of_the_sphere_satisfy_the_constraints_exactly():
    """x^2 + y^2 + z^2 = R^2 and x x' + y y' + z z' = 0 in integers mod p, at points
    whose dependent coordinate comes from a root of a polynomial over F_p."""
    system = particle_on_sphere()
    sampler = PointSampler.on_M1(system, seed=3, modular=True)
    assert sampler.chart is not None and sampler.chart.degrees == (2,)
    x, y, z = system.coordinates
    xd, yd, zd = system.velocities
    R = sp.Symbol("R")
    for _ in range(5):
        env = sampler.point().env
        X, Y, Z = (_value(env[s]) for s in (x, y, z))
        assert (X * X + Y * Y + Z * Z - _value(env[R]) ** 2) % P == 0
        assert (X * _value(env[xd]) + Y * _value(env[yd]) + Z * _value(env[zd])) % P == 0


def test_a_rational_sampler_refuses_a_curved_M():
    """Rational points of a curved M are not drawn (no rational parametrisation)."""
    with pytest.raises(NotExact, match="curved"):
        PointSampler.on_M1(particle_on_sphere(), seed=1)


@pytest.fixture(scope="module")
def bicycle():
    return load_scene(EXAMPLES / "whipple_bicycle.toml").system


def test_the_bicycle_contact_holds_exactly_at_points_over_Fp(bicycle):
    """The front contact of the Whipple bicycle (a sqrt of 1 - S^2) at points over F_p:
    with S = sin(delta) cos(phi) cos(h + theta) + sin(phi) cos(delta) and w the square
    root of 1 - S^2 that is a square mod p, the contact condition written by hand
    -lf sin(h + theta) cos(phi) + fo (-sin(delta) sin(phi) + cos(delta) cos(phi)
    cos(h + theta)) + lr cos(phi) cos(h + theta) - rF w + rR cos(phi) = 0 holds in
    integers mod p; the head angle h is drawn on the circle (one angle with a value)."""
    sampler = PointSampler.on_M1(bicycle, seed=5, modular=True)
    names = {s.name: s for s in (*bicycle.coordinates, *bicycle.parameters)}
    assert circle_parameters(bicycle) == (names["htangle"],)
    for _ in range(3):
        env = sampler.point().env

        def cs(name):
            a = env[names[name]]
            assert isinstance(a, Angle)
            return a.c.v, a.s.v

        def par(name):
            return _value(env[names[name]])

        (cp, sp_), (cd, sd), (ch, sh), (ct, st) = (cs(n) for n in ("phi", "delta",
                                                                   "htangle", "pitch"))
        c_ht, s_ht = (ch * ct - sh * st) % P, (sh * ct + ch * st) % P
        S = (sd * cp * c_ht + sp_ * cd) % P
        w = square_root(ModP(1 - S * S)).v
        g = (-par("forklength") * s_ht * cp
             + par("forkoffset") * (-sd * sp_ + cd * cp * c_ht)
             + par("framelength") * cp * c_ht - par("rF") * w + par("rR") * cp)
        assert g % P == 0
        assert (cp * cp + sp_ * sp_ - 1) % P == 0 and (ct * ct + st * st - 1) % P == 0
    assert "over F_p" in sampler.scope and "component" in sampler.scope


def test_the_bicycle_is_classified_by_proofs_at_its_parameter_values(bicycle):
    """Every decision of the bicycle's classification is a proof at a smooth point of
    M_1 over F_p (none sampled), each saying so; the verdict at the values has nothing
    left to check."""
    from nhham.verdict.values import classification_at_values

    at = classification_at_values(bicycle)
    analysis = at.verdict.analysis
    decisions = [ev.decision for st in analysis.stages for ev in st.decisions]
    decisions += [d for _, d in analysis.integrability.decisions]
    assert decisions and all(d.method == "exact" and d.error_bound == 0.0 for d in decisions)
    assert all(d.scope.startswith("M is curved") and d.scope in d.detail for d in decisions)
    assert analysis.rank_C == 5 and analysis.integrable is False
    assert (at.verdict.first_class, at.verdict.second_class) == (0, 6)
    assert at.warnings == ()


def test_exact_points_answer_where_sampling_would_be_wrong():
    """Two velocity constraints z' + x' and z' + (1 + eps) x' on a cylinder over a
    circle, eps = 1e-13: independent at the value, but within float64's tolerance of
    dependent. The exact route (points of the curved M_1 over F_p) says rank C = 3,
    determined; the sampled route alone finds rank 2 and no warning."""
    system = nhham.System(["x", "y", "z", "w"], "(x_dot**2 + y_dot**2 + z_dot**2 + w_dot**2)/2",
                          ["z_dot + x_dot", "z_dot + (1 + eps)*x_dot"],
                          holonomic=["x**2 + y**2 - 1"], parameters={"eps": 1e-13})
    exact = nhham.analyze_constraints(system)
    assert exact.rank_C == 3 and exact.status == "determined"
    assert all(ev.decision.method == "exact" for st in exact.stages for ev in st.decisions)
    sampled = nhham.analyze_constraints(system, policy=Policy(exact=False))
    assert sampled.rank_C == 2 and sampled.status == "underdetermined"


def test_a_rank_drop_on_the_curved_M1_is_not_proved_away():
    """Constraints dependent only on the circle x^2 + y^2 = 1 (z' + w' and
    (x^2 + y^2) z' + w', equal there): no point over F_p proves a full rank, and the
    decision says rank 2 of 3 (C singular on M_1)."""
    system = nhham.System(["x", "y", "z", "w"], "(x_dot**2 + y_dot**2 + z_dot**2 + w_dot**2)/2",
                          ["z_dot + w_dot", "(x**2 + y**2)*z_dot + w_dot"],
                          holonomic=["x**2 + y**2 - 1"])
    analysis = nhham.analyze_constraints(system)
    assert analysis.rank_C == 2 and not analysis.regular


def test_a_chart_refuses_what_it_cannot_make_polynomial():
    """A dependent coordinate both inside and outside sin (q + sin q = 1), or under exp,
    gives NotExact naming the constraint."""
    q, r = sp.symbols("q r")
    with pytest.raises(NotExact, match="cannot be solved over F_p"):
        curved_chart([q + sp.sin(q) - 1], [q])
    with pytest.raises(NotExact, match="cannot be solved over F_p"):
        curved_chart([sp.exp(q) + r ** 2 - 3], [q])


def test_the_submanifold_of_Q_of_a_curved_constraint_has_points():
    """exact_sampler of Q_1 = {g = 0} (fibre ()) is curved too; its points satisfy g."""
    system = particle_on_sphere()
    Q1 = Submanifold(system, system.holonomic, fibre=())
    sampler = exact_sampler(Q1, 7, modular=True)
    env = sampler.point().env
    x, y, z = system.coordinates
    total = sum(_value(env[s]) ** 2 for s in (x, y, z)) - _value(env[sp.Symbol("R")]) ** 2
    assert total % P == 0


def test_a_closed_loop_has_points_over_Fp_and_its_verdict_is_proved():
    """The four-bar linkage on a rolling cart: two loop-closure constraints in three
    angles, two of them dependent (a Groebner basis over F_p). At each point the loop
    closes in integers mod p, a cos t1 + b cos t2 - c cos t3 - d = 0 and
    a sin t1 + b sin t2 - c sin t3 = 0, and the classification is proved there: C of rank
    3, 1 first-class and 4 second-class constraints (an antisymmetric 5 x 5 matrix has
    rank 4 at most)."""
    from nhham.verdict.values import classification_at_values

    system = load_scene(EXAMPLES / "four_bar_cart.toml").system
    sampler = PointSampler.on_M1(system, seed=11, modular=True)
    assert len(sampler.chart.dependent) == 2
    names = {s.name: s for s in (*system.coordinates, *system.parameters)}
    for _ in range(3):
        env = sampler.point().env
        (c1, s1), (c2, s2), (c3, s3) = ((env[names[f"theta{i}"]].c.v, env[names[f"theta{i}"]].s.v)
                                        for i in (1, 2, 3))
        a, b, c, d = (_value(env[names[k]]) for k in "abcd")
        assert (a * c1 + b * c2 - c * c3 - d) % P == 0
        assert (a * s1 + b * s2 - c * s3) % P == 0
    verdict = classification_at_values(system).verdict
    assert (verdict.rank_C, verdict.first_class, verdict.second_class) == (3, 1, 4)
    assert all(ev.decision.method == "exact" and ev.decision.scope
               for st in verdict.analysis.stages for ev in st.decisions)


def test_the_direct_solution_agrees_with_a_groebner_basis(bicycle, monkeypatch):
    """The bicycle's chart (one angle t, one sqrt w) is solved without a Groebner basis
    (the roots of c F0^2 - b F1^2, w = -F0/F1); at 20 draws the solutions are the same
    sets as the lex Groebner route gives."""
    import nhham.lagrangian.curved as curved

    sampler = PointSampler.on_M1(bicycle, seed=5, modular=True)
    chart = sampler.chart
    assert len(chart.unknowns) == 2  # t and w

    def key(solutions):
        return sorted(tuple(sorted((str(k), v) for k, v in s.items())) for s in solutions)

    found = 0
    for _ in range(20):
        env = {k: v for k, v in sampler.point().env.items() if k not in chart.dependent}
        system = chart._instance(env)
        direct = curved._triangular_solutions(system, chart.unknowns)
        with monkeypatch.context() as m:
            m.setattr(curved, "_one_unknown", lambda elements, R: None)
            general = curved._triangular_solutions(system, chart.unknowns)
        assert key(direct) == key(general)
        found += bool(direct)
    assert found == 20


def test_roots_over_Fp_of_a_product_of_known_factors():
    """(x - r1)...(x - rk)(x^2 + b x + c): every r_i is found, and each root returned is
    a root (Horner's rule in plain integers)."""
    import random

    from nhham.lagrangian.curved import _roots

    rng = random.Random(3)
    for _ in range(30):
        rs = [rng.randrange(P) for _ in range(rng.randrange(0, 5))]
        f = [1]
        for r in rs:
            f = [(a - r * b) % P for a, b in zip(f + [0], [0] + f)]
        q = [1, rng.randrange(P), rng.randrange(P)]
        g = [0] * (len(f) + 2)
        for i, a in enumerate(f):
            for j, b in enumerate(q):
                g[i + j] = (g[i + j] + a * b) % P
        got = _roots(g)
        assert set(rs) <= set(got)
        for r in got:
            value = 0
            for c in g:
                value = (value * r + c) % P
            assert value == 0


def test_the_rank_of_C_on_the_bicycles_M1_is_proved_without_a_symbolic_reduction(bicycle):
    """``LagrangianGeometry.constraint_rank`` asks M_1.rank(C): on the bicycle's curved
    M_1 (n = 8 > closed_form_size) the symbolic solve of the velocities (minutes) is
    skipped and a point over F_p proves rank 5 = m."""
    from nhham.lagrangian.geometry import lagrangian_geometry

    G = lagrangian_geometry(bicycle)
    decision = G.constraint_rank
    assert (decision.value, decision.method, decision.error_bound) == (5, "exact", 0.0)
    assert decision.scope.startswith("M is curved") and G.regular


def test_chart_equations_are_read_off_their_terms_as_sympy_s_poly_reads_them():
    """The chart's {exponents: coefficient} (read term by term) against sympy.Poly over
    the expression domain: the same monomials in the same order, equal coefficients, and
    the same refusal of a term that is not a monomial in the unknowns."""
    from nhham.lagrangian.curved import _coefficients

    t, w, a, x = sp.symbols("t w a x")
    cases = [sp.expand((1 + t ** 2) ** 2 * sp.sin(x) * a - 3 * t * w ** 2 + w * sp.cos(x)
                       - a * sp.sin(x) + 7),
             sp.expand((a * t - sp.sqrt(2) * w) ** 3 + x * t),
             a * sp.sin(x), sp.Integer(0)]
    for e in cases:
        got = _coefficients(e, [t, w])
        poly = sp.Poly(e, t, w)
        want = {m: c for m, c in zip(poly.monoms(), poly.coeffs()) if c != 0}
        assert list(got) == list(want), e
        assert all(sp.expand(got[m] - want[m]) == 0 for m in want), e
    # t*x - t*x: the coefficient of t cancels, no zero entry is kept
    assert _coefficients(sp.expand(t * (x + 1) - t * x), [t]) == {(1,): 1}
    for bad in (sp.sin(t) * a + t, a / t + 1, sp.sqrt(t) + 1):
        with pytest.raises(sp.PolynomialError):
            sp.Poly(bad, t, w)
        with pytest.raises(sp.PolynomialError):
            _coefficients(sp.expand(bad), [t, w])
