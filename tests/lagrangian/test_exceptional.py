"""The data of the generic decisions and their exceptional sets
(nhham.lagrangian.exceptional): the components found against those derived by hand, and the
200-bit floating-point determinants and solves against exact arithmetic."""

from __future__ import annotations

import sympy as sp

from nhham.lagrangian.analysis import analyze_constraints
from nhham.lagrangian.exceptional import exceptional_conditions
from parametric_systems import two_bodies


def test_exceptional_conditions_of_one_analysis():
    conds = exceptional_conditions(analyze_constraints(two_bodies()))
    eqs = {tuple(str(e) for e in c.equations) for c in conds}
    assert ("I1 - I2",) in eqs
    rank = next(c for c in conds if c.equations == (sp.Symbol("I1") - sp.Symbol("I2"),))
    assert any("C singular" in r for r in rank.reasons)


def test_floating_point_determinants_pivot():
    """The nearness estimate evaluates data in 200-bit floating point: determinants and
    solves there pivot (sympy's fraction-free elimination divides by the rounded zero
    pivots of an antisymmetric bracket matrix). Checked against exact arithmetic."""
    from sympy.polys.matrices import DomainMatrix

    from nhham.lagrangian.exceptional import SHIFT_FIELD
    from nhham.lagrangian.linalg import field_det, field_solve

    rows = [[0, 3, -1, 2], [-3, 0, 5, 1], [1, -5, 0, 7], [-2, -1, -7, 0]]
    exact = DomainMatrix([[sp.QQ(x) for x in r] for r in rows], (4, 4), sp.QQ)
    F = SHIFT_FIELD
    approx = exact.convert_to(F)
    pf = 3 * 7 - (-1) * 1 + 2 * 5  # Pfaffian b01 b23 - b02 b13 + b03 b12 = 32
    assert exact.det() == pf ** 2
    assert abs(float(field_det(approx)) - pf ** 2) < 1e-40
    rhs = DomainMatrix([[sp.QQ(1)], [sp.QQ(0)], [sp.QQ(2)], [sp.QQ(-1)]], (4, 1), sp.QQ)
    x = exact.lu_solve(rhs).to_list()
    y = field_solve(approx, rhs.convert_to(F)).to_list()
    assert all(abs(float(a[0]) - float(b[0])) < 1e-40 for a, b in zip(x, y))


def test_without_points_over_the_parameter_field_the_note_says_what_the_verdict_rests_on():
    """M_1 curved (a circle x^2 + y^2 = l^2): no points over Q(params), but every
    decision is proved at points of M_1 over F_p with the parameters at their values, so
    nothing is left unchecked and nothing is said. Decisions taken at float points are
    also at the values; one taken for generic parameters (an exact rank by reduction)
    is named."""
    from types import SimpleNamespace

    from nhham.lagrangian.decision import Decision
    from nhham.lagrangian.exceptional import ExceptionalData
    from nhham.lagrangian.records import Evidence
    from nhham.system.models import pendulum_cartesian
    from nhham.verdict.values import classification_at_values

    at = classification_at_values(pendulum_cartesian())
    assert at.warnings == ()
    assert all(ev.decision.scope.startswith("M is curved")
               for st in at.verdict.analysis.stages for ev in st.decisions
               if ev.decision.method == "exact")

    def note(*evidence, integrable=True, terms=()):
        stage = SimpleNamespace(decisions=evidence)
        analysis = SimpleNamespace(stages=(stage,), integrable=integrable,
                                   integrability=SimpleNamespace(decisions=terms))
        return ExceptionalData._unchecked_note(SimpleNamespace(
            analysis=analysis, system=pendulum_cartesian(), seed=1))

    sampled = Evidence("rank of (Z_i(chi_j)) on M_1", Decision(1, "sampled", "at points"))
    exact_zero = Evidence("condition from g", Decision(True, "exact", "vanishes"))
    exact_rank = Evidence("rank of (Z_i(chi_j)) on M_2", Decision(2, "exact", "minor"))
    at_values = Evidence("rank of (Z_i(chi_j)) on M_1",
                         Decision(2, "exact", "proof", scope="M is curved (...)"))
    frobenius = (("dmu(X_1, X_2)", Decision(False, "exact", "reduced")),)
    assert note(sampled, exact_zero).startswith("no exact points of M_1: every decision")
    assert note(at_values, exact_zero) == ""
    text = note(sampled, exact_rank, integrable=False, terms=frobenius)
    assert text.startswith("the parameter values were not checked")
    assert "rank of (Z_i(chi_j)) on M_2" in text and "integrability" in text
    assert "(Z_i(chi_j)) on M_1" not in text  # the sampled decision is not named


def test_non_integrability_by_reduction_is_proved_again_at_the_values():
    """The two-particle rod: Q_1 = {|r2 - r1| = l} is curved; non-integrability is
    decided by reduction for generic l, and proved again at a point of Q_1 over F_p with
    l at its value, so the verdict at the values names nothing unchecked. A system that
    is integrable (the Cartesian pendulum: no nonzero term) gets no such proof."""
    from nhham.lagrangian.engine import Policy
    from nhham.lagrangian.integrability import integrability_proved_at_values
    from nhham.system.models import pendulum_cartesian, two_particle_rod
    from nhham.verdict.values import classification_at_values

    at = classification_at_values(two_particle_rod())
    assert at.verdict.analysis.integrable is False
    assert at.warnings == ()
    proved = integrability_proved_at_values(two_particle_rod(), Policy())
    assert proved.integrable is False and proved.method == "exact"
    assert integrability_proved_at_values(pendulum_cartesian(), Policy()) is None



def test_exceptional_data_are_built_once_and_frozen():
    """The second-class set is given when the data are built, never set afterwards.

    Two particles on a line, q = (x, y), L = m (x_dot^2 + y_dot^2) / 2 with the
    holonomic constraint g = x - y: M_f = {g = 0, g^c = 0} and the bracket
    {g, g^c} = dg W^-1 dg^T = 2/m, so B = [[0, 2/m], [-2/m, 0]] and det B = 4/m^2 = 4
    at m = 1, at every point. With no set given the block is the generic choice (both
    constraints, B regular); with an empty set there is no minor to evaluate."""
    from dataclasses import FrozenInstanceError

    import pytest
    from sympy import QQ

    from nhham import System
    from nhham.lagrangian.exceptional import ExceptionalData

    system = System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2", holonomic=["x - y"],
                    parameters={"m": 1.0})
    analysis = analyze_constraints(system)
    generic = ExceptionalData(system, analysis, 7, 2)
    assert generic._bracket_minor(generic.env(), QQ) == [4, 4]
    given = ExceptionalData(system, analysis, 7, 2, second_class=(0, 1))
    assert given._bracket_minor(given.env(), QQ) == [4, 4]
    empty = ExceptionalData(system, analysis, 7, 2, second_class=())
    assert empty._bracket_minor(empty.env(), QQ) == []
    with pytest.raises(FrozenInstanceError):
        generic.points = 1
    assert not hasattr(ExceptionalData, "use_second_class_set")
    with generic._first_point_only():  # one point, without changing the object
        assert generic.points == 2 and generic._bracket_minor(generic.env(), QQ) == [4]
    assert len(generic._bracket_minor(generic.env(), QQ)) == 2


def test_bracket_minor_with_symbolic_parameters_is_the_hand_numerator():
    """The bracket datum in Q(m, a, b), formed without division (W⁻¹ by a fraction-free
    solve: in Q(p) the gcds of the field arithmetic made the roller racer's 2 x 2 B run
    past 300 s).

    By hand: L = (m x'^2 + y'^2 + z'^2)/2, chi_1 = x' + a y, chi_2 = y' + b x; on T*Q
    chi_1 = p_x/m + a y, chi_2 = p_y + b x, so {chi_1, chi_2} = a - b/m at every point and
    det B = (a - b/m)^2 = (m a - b)^2 / m^2: the numerator is (m a - b)^2, without the
    factor m of det W that the division-free form carries (d^2 B, d a divisor of m)."""
    from sympy import QQ

    from nhham import System
    from nhham.lagrangian.exceptional import ExceptionalData
    from nhham.lagrangian.linalg import field_det

    system = System(["x", "y", "z"], "(m*x_dot**2 + y_dot**2 + z_dot**2)/2",
                    ["x_dot + a*y", "y_dot + b*x"], parameters={"m": 1.0, "a": 1.0, "b": 2.0})
    analysis = analyze_constraints(system)
    data = ExceptionalData(system, analysis, 7, 3)
    m, a, b = sp.symbols("m a b")
    K = QQ.frac_field(m, a, b)
    env0 = data.env(gens=dict(zip((m, a, b), K.gens)))
    values = data._bracket_minor(env0, K)
    assert len(values) == 3
    for v in values:
        assert sp.simplify(K.to_sympy(v) / (m * a - b) ** 2).is_number
    # the field route, the formula with W⁻¹ in Q(p): (a - b/m)^2 itself
    fields = [field_det(B.extract([0, 1], [0, 1])) for B in data._brackets(env0, K)]
    assert all(sp.simplify(K.to_sympy(v) - (a - b / m) ** 2) == 0 for v in fields)



def test_the_bracket_modulo_p_on_residues_is_the_bracket_in_gf_p():
    """_brackets over GF(p) (formed on residues, ListMatrix of ModP) against the same
    formula on sympy's GF(p) matrices, at the datum's own points; and by hand: with
    L = (m x'^2 + y'^2 + z'^2)/2, chi_1 = x' + a y, chi_2 = y' + b x, {chi_1, chi_2} = a - b/m."""
    from sympy.polys.matrices import DomainMatrix

    from nhham import System
    from nhham.lagrangian.exceptional import MODULAR, ExceptionalData
    from nhham.lagrangian.domains import evaluate
    from nhham.lagrangian.formulas import lagrangian_bracket

    system = System(["x", "y", "z"], "(m*x_dot**2 + y_dot**2 + z_dot**2)/2",
                    ["x_dot + a*y", "y_dot + b*x"], parameters={"m": 3.0, "a": 1.0, "b": 2.0})
    data = ExceptionalData(system, analyze_constraints(system), 7, 3)
    env0 = data.env(generic=True)
    got = data._brackets(env0, MODULAR)
    pts = data._pts(list(data.analysis.final_constraints), env0, MODULAR, "f")
    assert len(got) == len(pts) == 3
    for B, env in zip(got, pts):
        cache = {}
        want = lagrangian_bracket(*(DomainMatrix(
            [[data._val(MODULAR, x) for x in evaluate(row, env, cache)] for row in r],
            (len(r), len(r[0])), MODULAR) for r in data._bracket_rows))
        assert B == want
        m, a, b = (MODULAR(data._val(MODULAR, env[s])) for s in sp.symbols("m a b"))
        assert B[0, 1].element == a - b / m
