"""δ W⁻¹ without division, and the constraint algorithm run with the scaled fields.

The inverse-free route multiplies ξ_L and Z_i by δ (δ W⁻¹ = blockwise adjugates, see
``nhham/lagrangian/adjugate.py``); the old route used ξ_L = (v, W⁻¹F) and
Z_i = −W⁻¹μ_iᵀ ∂/∂v in closed form. Where W is regular both give the same tangency
equations up to the factor δ, hence the same ranks, stages, multipliers, and secondary
constraints up to factors that do not vanish there.

Systems with a non-constant W whose answer is known by hand are built by a point
transformation q = f(Q) of a system solved by hand (the paper's Example 3.2, the five-stage
walk-through, ...): L and the constraints are pulled back, W(Q) = Jᵀ W₀ J is no longer
constant nor diagonal, and status, stage count, ranks and the multipliers (functions on
TQ, λ^i multiplies the pulled-back μ_i) are those of the original system.
"""

import pathlib

import pytest
import sympy as sp

from nhham import System
from nhham.lagrangian.adjugate import divide_out, scale_factors, scaled_inverse
from nhham.lagrangian.algorithm import run_algorithm
from nhham.lagrangian.analysis import analyze_constraints
from nhham.lagrangian.geometry import LagrangianGeometry
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.scene import load_scene

from handmade import (curvilinear_3_2, curvilinear_five_stage, curvilinear_free_multiplier,
                      curvilinear_inconsistent)

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"

x, y = sp.symbols("x y")
xd, yd = sp.symbols("x_dot y_dot")
q1, q2, q3, q4 = sp.symbols("q1 q2 q3 q4")
v1, v2, v3, v4 = sp.symbols("q1_dot q2_dot q3_dot q4_dot")
l1, l2 = sp.symbols("lambda_1 lambda_2")


# ====================================================================== δ W⁻¹
@pytest.mark.parametrize("W, scale", [
    (sp.diag(1, 1, -1), 1),                                   # the paper's Lorentzian W
    (sp.Matrix([[2, 1, 0], [1, 1, 0], [0, 0, -3]]), 1),       # constant, not diagonal
    (sp.diag(sp.Symbol("a"), 1, -1), 1),                      # parameters only: inverted
    (sp.diag(1 + x**2, -1 - x**2), 1 + x**2),                 # conformal Lorentzian
    (sp.Matrix([[1, sp.cos(x), 0], [sp.cos(x), -1, 0], [0, 0, 1 + y**2]]), None),
])
def test_scaled_inverse_is_delta_times_the_inverse(W, scale):
    """S W = δ Id with polynomial entries; δ = 1 when W is free of the state."""
    S = scaled_inverse(W, (x, y, xd, yd))
    assert (S.matrix() * W - S.scale * sp.eye(W.rows)).applyfunc(sp.simplify) == \
        sp.zeros(W.rows, W.rows)
    assert all(sp.denom(sp.together(e)).free_symbols.isdisjoint({x, y})
               for e in S.matrix())
    if scale is not None:
        assert sp.expand(S.scale - scale) == 0
    else:
        # Blocks [[1, c], [c, -1]] (det -(1 + c^2)) and [1 + y^2]: δ is their lcm (up
        # to sign, in any form equal modulo sin^2 + cos^2 = 1).
        lcm = (1 + sp.cos(x)**2) * (1 + y**2)
        assert any(sp.simplify(S.scale - sign * lcm) == 0 for sign in (1, -1))
        assert len(S.blocks) == 2


def test_divide_out_removes_every_power_of_the_factors_of_delta():
    delta = (1 + x**2) ** 2
    assert scale_factors(delta) == (1 + x**2,)
    assert sp.expand(divide_out((1 + x**2) ** 3 * y * xd, scale_factors(delta)) - y * xd) == 0
    assert divide_out(y + x, ()) == y + x  # δ = 1: untouched
    assert sp.expand(divide_out(x * y, scale_factors(x**2 + 1)) - x * y) == 0


# =============================================== systems with a non-constant W
def conformal_lorentzian():
    """L = (1 + x^2)(x'^2 - y'^2)/2 - x^2/2, phi = x' - y' (n = 2, W depends on x).

    By hand (DESIGN §2 signs).  W = (1 + x^2) diag(1, -1), mu = (1, -1),
    W^-1 mu^T = (1, 1)/(1 + x^2), so Z = -(d/dx' + d/dy')/(1 + x^2) and
    C = Z(phi) = 0: singular.  F_x = dL/dx - (d2L/dq dx') v = x(x'^2 - y'^2) - x
    - 2x x'^2 = -x(x'^2 + y'^2) - x;  F_y = 0 - (-2x x' y') = 2x x' y'.
    xi^x = F_x/(1 + x^2), xi^y = -F_y/(1 + x^2), so
    xi_L(phi) = (F_x + F_y)/(1 + x^2) = -x((x' - y')^2 + 1)/(1 + x^2):
    stage 1 gives the secondary constraint x (the other factors have no zeros).
    Stage 2: Z(x) = 0, xi_L(x) = x' -> secondary x'.  Stage 3: Z(x') = -1/(1 + x^2) != 0,
    rank 1; lambda = -xi_L(x')/Z(x') = F_x = -x(x'^2 + y'^2) - x = 0 on
    M_3 = {x' - y' = 0, x = 0, x' = 0}; the other conditions vanish there.
    Determined, 3 stages, ranks 0, 0, 1, dim M_3 = 4 - 3 = 1.  δ = 1 + x^2: the scaled
    condition at stage 2 is (1 + x^2) x', from which the factor 1 + x^2 is divided out."""
    return System(["x", "y"], (1 + x**2) * (xd**2 - yd**2) / 2 - x**2 / 2, [xd - yd],
                  name="conformal Lorentzian")


# ------------------------------------------------------------- the two routes
def old_route(system, run):
    """The W^-1 route on the same primary constraints: ξ_L and Z_i in closed form."""
    geo = LagrangianGeometry(system)
    first = run.stages[0]
    return run_algorithm(geo.euler_lagrange_field, geo.vertical_fields, first.constraints,
                         first.labels, lambda eqs: Submanifold(system, eqs),
                         max_stages=2 * system.n, multiplier_symbols=run.multiplier_symbols,
                         variables=system.state)


def up_to_a_nonzero_factor(a, b, state, delta):
    """a / b is free of the state, or made of factors of δ (which do not vanish)."""
    ratio = sp.factor(sp.cancel(sp.sympify(a) / sp.sympify(b)))
    if ratio == 0:
        return False
    allowed = {sp.expand(f) for f in scale_factors(delta)}
    allowed |= {sp.expand(-f) for f in allowed}
    for part in (sp.numer(ratio), sp.denom(ratio)):
        _, factors = sp.factor_list(part)
        for f, _ in factors:
            if f.free_symbols & state and sp.expand(f) not in allowed:
                return False
    return True


def assert_same_answer(system):
    """The inverse-free run (analyze_constraints) agrees with the W^-1 route."""
    a = analyze_constraints(system, decompose=False)
    new = a.blocks[0].run
    old = old_route(system, new)
    state = set(system.state)
    assert new.status == old.status
    assert [s.rank for s in new.stages] == [s.rank for s in old.stages]
    assert [s.augmented_rank for s in new.stages] == [s.augmented_rank for s in old.stages]
    assert [s.new_labels for s in new.stages] == [s.new_labels for s in old.stages]
    for sn, so in zip(new.stages, old.stages):
        for en, eo in zip(sn.new_constraints, so.new_constraints):
            assert up_to_a_nonzero_factor(en, eo, state, new.scale), (en, eo)
    assert new.free_multiplier_symbols == old.free_multiplier_symbols
    assert new.dimension == old.dimension
    assert set(new.multipliers) == set(old.multipliers)
    for s in new.multipliers:
        assert new.manifold.vanishes(new.multipliers[s] - old.multipliers[s]).value
    return a, new, old


def scene(name):
    """The scene's system at its parameter values (as ``nhham classify`` answers)."""
    system = load_scene(EXAMPLES / name, drop_redundant=True).system
    values = {p: sp.Rational(str(v)) for p, v in system.parameter_values.items()}
    if not values:
        return system
    return System([q.name for q in system.coordinates], system.lagrangian.xreplace(values),
                  [c.xreplace(values) for c in system.constraints],
                  holonomic=[h.xreplace(values) for h in system.holonomic], name=system.name)


@pytest.mark.parametrize("name", ["paper_3_1.toml", "paper_3_2.toml",
                                  "parametric_null_constraint.toml"])
def test_example_scenes_with_singular_C_agree(name):
    """The example scenes whose C is singular: δ = 1 (W free of the state), so the
    new constraints are the same expressions, not only the same up to a factor."""
    system = scene(name)
    a, new, old = assert_same_answer(system)
    assert not a.regular and new.scale == 1
    for sn, so in zip(new.stages, old.stages):
        assert sn.new_constraints == so.new_constraints


@pytest.mark.parametrize("make, status, ranks", [
    (curvilinear_3_2, "determined", [0, 0, 1]),
    (curvilinear_five_stage, "determined", [0, 0, 0, 0, 1]),
    (curvilinear_free_multiplier, "underdetermined", [1]),
    (curvilinear_inconsistent, "inconsistent", [1, 1]),
    (conformal_lorentzian, "determined", [0, 0, 1]),
], ids=lambda v: getattr(v, "__name__", None))
def test_non_constant_W_agrees_with_the_inverse_route(make, status, ranks):
    """Point transformations of hand-solved systems: the answers of the originals, and
    both routes agree (constraints up to factors without zeros)."""
    system = make()
    a, new, old = assert_same_answer(system)
    assert new.scale != 1  # W depends on the state: the fields really were scaled
    assert a.status == status and [s.rank for s in a.stages] == ranks


def test_curvilinear_example_3_2_by_hand():
    """See curvilinear_3_2: M_3 = {phi = 0, q1 = 0, v1 = 0}, lambda = q1 (invariant)."""
    a = analyze_constraints(curvilinear_3_2())
    assert [list(s.new_constraints) for s in a.stages] == [[q1], [v1], []]
    assert a.multipliers == {l1: q1} or a.blocks[0].run.manifold.vanishes(
        a.multipliers[l1] - q1).value
    assert a.dimension == 3


def test_hand_derived_conformal_lorentzian():
    """See conformal_lorentzian: secondary x then x' (the factor 1 + x^2 = δ divided
    out of (1 + x^2) x'), lambda = F_x, which vanishes on M_3."""
    a = analyze_constraints(conformal_lorentzian())
    run = a.blocks[0].run
    assert sp.expand(run.scale - (1 + x**2)) == 0
    assert a.status == "determined" and not a.regular and a.rank_C == 0
    new = [list(s.new_constraints) for s in a.stages]
    assert len(new) == 3 and new[2] == []
    assert new[0] in ([x], [-x]) and new[1] in ([xd], [-xd])
    assert a.dimension == 1 and a.free_multipliers == 0
    lam = a.multipliers[l1]
    assert run.manifold.vanishes(lam - (-x * (xd**2 + yd**2) - x)).value
    assert sp.simplify(lam.subs({x: 0, xd: 0, yd: 0})) == 0
    # The recorded stage-1 condition is ψ itself (the scaled one divided by δ).
    (label, psi), = a.stages[0].conditions
    assert label == "constraints[0]"
    assert sp.simplify(psi + x * ((xd - yd)**2 + 1) / (1 + x**2)) == 0
    # Closed forms are still there for whoever asks: xi_L + lambda Z on M_f.
    field = a.dynamics.subs({x: 0, xd: 0, yd: 0})
    assert [sp.simplify(e) for e in field] == [0, 0, 0, 0]


# ============================================ the new route never forms W^-1
def _forbidden(name):
    def boom(self):
        raise AssertionError(f"{name} (W^-1 in closed form) was formed")
    return property(boom)


@pytest.mark.parametrize("make", [curvilinear_3_2, conformal_lorentzian,
                                  lambda: scene("paper_3_2.toml")],
                         ids=["curvilinear_3_2", "conformal", "paper_3_2"])
def test_singular_C_route_never_forms_the_inverse(monkeypatch, make):
    """Stages, multipliers and the projector of a singular-C system with the W^-1
    fields made to raise: nothing on the classify path needs them."""
    system = make()
    for name in ("euler_lagrange_field", "vertical_fields", "accelerations",
                 "_W_inv_mu_T", "constraint_matrix", "multipliers"):
        monkeypatch.setattr(LagrangianGeometry, name, _forbidden(name))

    def no_solve(self, rhs):
        raise AssertionError("a solve with W was made")

    monkeypatch.setattr(LagrangianGeometry, "_solve_W", no_solve)
    a = analyze_constraints(system)
    assert not a.regular and a.status == "determined"
    assert a.multipliers  # determined multipliers, from the scaled rows
    P = a.projector_P
    assert P is not None and (P * P - P).applyfunc(sp.simplify) == sp.zeros(*P.shape)
    with pytest.raises(AssertionError, match="closed form"):
        a.dynamics  # the closed form is what still needs W^-1



def test_curvilinear_pair_reports_what_its_header_says():
    """examples/curvilinear_pair.toml (n = 6, W(q) with sines and cosines, det W = (1 + q5^2)^2).  The
    W^-1 route did not finish in 20 minutes (nhham classify); the scaled one answers in
    about a second."""
    a = analyze_constraints(load_scene(EXAMPLES / "curvilinear_pair.toml").system)
    assert len(a.blocks) == 1 and a.rank_C == 0 and not a.regular
    assert a.status == "determined" and [s.rank for s in a.stages] == [0, 0, 2]
    assert [list(s.new_constraints) for s in a.stages] == [[q1, q4], [v1, v4], []]
    assert dict(a.multipliers) == {l1: q1, l2: q4}
    assert a.dimension == 6 and a.integrable is True
    assert sp.expand(a.blocks[0].run.scale - (1 + sp.Symbol("q5")**2)**2) == 0


def test_a_block_with_decimal_entries_is_scaled():
    """W = [[e^0.25, 1/8], [1/8, pi/q]]: e^0.25 is a float (sympy evaluates exp of a
    decimal), and sympy's division of the lcm by the determinant fails in floating point
    (PolynomialDivisionFailed: an internal error of compare). The quotient is then
    cancelled: by hand delta W^-1 = adj W when delta = det W = e^0.25 pi/q - 1/64."""
    q, v = sp.symbols("q v")
    W = sp.Matrix([[sp.exp(sp.Float(0.25)), sp.Rational(1, 8)], [sp.Rational(1, 8), sp.pi / q]])
    S = scaled_inverse(W, [q, v])
    at = {q: sp.Float(0.7)}
    inverse = (S.apply(sp.eye(2)) / S.scale).xreplace(at).evalf()
    assert (inverse * W.xreplace(at) - sp.eye(2)).norm() < 1e-12
