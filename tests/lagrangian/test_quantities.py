"""Vanishing and Rank asked directly of the decision engine, each step on its own.

On the rolling disk's M_1 the reduction gives x' = R cos(theta) phi' and
y' = R sin(theta) phi' (worked out by hand), so:
- x' - R cos(theta) phi' vanishes (exact), x' does not (it reduces to R cos(theta) phi');
- [[x' - R c phi', 0], [0, y']] has rank 1 (exact), and 1 at the sample points;
- the sampled step alone gives the same answers at float points.
"""

import pytest
import sympy as sp

from nhham import System
from nhham.lagrangian.engine import Policy, answers_by_step, decide
from nhham.lagrangian.quantities import Rank, Vanishing
from nhham.lagrangian.submanifold import Submanifold

th = sp.Symbol("theta")
xd, yd, thd, phd = sp.symbols("x_dot y_dot theta_dot phi_dot")
m, R, I1, I2 = sp.symbols("m R I1 I2")


def _M1():
    s = System(["x", "y", "theta", "phi"],
               m * (xd**2 + yd**2) / 2 + I1 * thd**2 / 2 + I2 * phd**2 / 2,
               [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd],
               parameters={"m": 1.3, "I1": 0.5, "I2": 0.25, "R": 0.7})
    return Submanifold(s, s.phi)


def test_vanishing_exact_and_sampled_agree_with_the_hand_reduction():
    M = _M1()
    yes, no = xd - R * sp.cos(th) * phd, xd
    assert decide(Vanishing(yes), M, M.policy).value is True
    decision = decide(Vanishing(no), M, M.policy)
    assert decision.value is False and decision.method == "exact"
    for expr, expected in ((yes, True), (no, False)):
        answers = answers_by_step(lambda: Vanishing(expr), M, Policy())
        assert {step: a.value for step, a in answers.items()} == {
            step: expected for step in answers}
        assert "sampled" in answers and "reduced" in answers


def test_rank_exact_and_sampled_agree_with_the_hand_reduction():
    M = _M1()
    A = sp.Matrix([[xd - R * sp.cos(th) * phd, 0], [0, yd]])
    # A deficient rank is not decided by the reduction alone nor by a point over F_p:
    # found at exact points (or sampled), then proved by a certificate (a nonzero
    # 1 x 1 minor whose Schur complement vanishes on M).
    answers = answers_by_step(lambda: Rank(A), M, Policy())
    assert {step: a.value for step, a in answers.items()} == {"exact points": 1,
                                                              "sampled": 1}
    decision = decide(Rank(A), M, M.policy)
    assert (decision.value, decision.method) == (1, "exact")
    # Full rank: det = R^2 cos(theta) sin(theta) phi'^2, a nonzero function on M.
    full = sp.Matrix([[xd, 0], [0, yd]])
    answers = answers_by_step(lambda: Rank(full), M, Policy())
    assert {step: a.value for step, a in answers.items()} == {
        "reduced": 2, "proof modulo p": 2, "exact points": 2, "sampled": 2}
    assert decide(Rank(sp.zeros(0, 3)), M, M.policy).value == 0


def test_without_exact_steps_only_the_samples_decide():
    M = _M1().sampled_only()
    decision = decide(Vanishing(xd), M, M.policy)
    assert decision.value is False and decision.method == "sampled"


# ------------------------------------------------- a curved M: points over F_p
P = 2 ** 61 - 1


def _cylinder_Q1():
    """Q_1 = {x^2 + y^2 = 1} in (x, y, z): curved (no coordinate enters linearly)."""
    s = System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2", [],
               holonomic=["x**2 + y**2 - 1"])
    return Submanifold(s, s.holonomic, fibre=())


def test_a_planted_rank_drop_on_a_curved_M_is_found_with_its_bezout_bound():
    """[[y, 1], [(x^2 + y^2) y, 1]] has det y (1 - x^2 - y^2): rank 2 off the circle,
    1 on it. At 6 smooth points over F_p (one of x, y drawn, the other a root of
    x^2 + y^2 - 1): rank 1, with the bound by hand: deg X = 2 (the circle), the 2 x 2
    minor's numerator degree 1 + 3 = 4, 50 draws x (1 + 3 redraws) per point:
    6 * 200 * 2 * 4 / (p - 1)."""
    M = _cylinder_Q1()
    x, y = sp.symbols("x y")
    A = sp.Matrix([[y, 1], [(x**2 + y**2) * y, 1]])
    answers = answers_by_step(lambda: Rank(A), M, Policy())
    assert "proof modulo p" not in answers  # rank 1 at a point proves nothing
    found = answers["exact points"]
    assert (found.value, found.method, found.samples) == (1, "exact at points", 6)
    assert found.error_bound == pytest.approx(6 * 200 * 2 * 4 / (P - 1), rel=1e-12)
    assert "component" in found.scope and found.scope in found.detail
    # Off the circle the same matrix has full rank: the drop is M's, not the matrix's.
    flat = Submanifold(M.system, [], fibre=())
    assert decide(Rank(A), flat, flat.policy).value == 2


def test_vanishing_on_a_curved_M_at_points_and_a_proof_of_the_contrary():
    """y (x^2 + y^2 - 1) vanishes on the circle: decided at 6 points over F_p with the
    bound 6 * 200 * 2 * 3 / (p - 1) (numerator degree 3); y does not: nonzero at the
    first point, a proof on the component through it."""
    M = _cylinder_Q1()
    x, y = sp.symbols("x y")
    zero = answers_by_step(lambda: Vanishing(y * (x**2 + y**2 - 1)), M, Policy())
    at = zero["exact points"]
    assert at.value is True and at.method == "exact at points"
    assert at.error_bound == pytest.approx(6 * 200 * 2 * 3 / (P - 1), rel=1e-12)
    nonzero = answers_by_step(lambda: Vanishing(y), M, Policy())["proof modulo p"]
    assert (nonzero.value, nonzero.method, nonzero.error_bound) == (False, "exact", 0.0)
    assert nonzero.scope.startswith("M is curved")


def test_a_rank_drop_on_the_bicycle_contact_is_found_at_its_points():
    """The bicycle's front contact g(q) = 0 (a sqrt of the lean and steer angles) planted
    in [[g + 1, 1], [1, 1]] (det = g): rank 1 on its Q_1, decided at points over F_p
    (no exact reduction of a sqrt, no float sampling); the bound counts the contact's
    degree and is below 1e-9. With g + 3/2 in place of g + 1 (det = g + 1/2) the rank is full, proved
    at one point."""
    from pathlib import Path

    from nhham.system.scene import load_scene

    scene = Path(__file__).resolve().parents[2] / "examples" / "whipple_bicycle.toml"
    system = load_scene(scene).system
    (g,) = system.holonomic
    Q1 = Submanifold(system, system.holonomic, fibre=())
    drop = decide(Rank(sp.Matrix([[g + 1, 1], [1, 1]])), Q1, Q1.policy)
    assert (drop.value, drop.method) == (1, "exact at points")
    assert 0 < drop.error_bound < 1e-9 and "component" in drop.scope
    full = decide(Rank(sp.Matrix([[g + sp.Rational(3, 2), 1], [1, 1]])), Q1, Q1.policy)
    assert (full.value, full.method, full.error_bound) == (2, "exact", 0.0)


def test_a_rank_deficient_at_random_points_of_F_p_is_not_cancelled():
    """The relativistic particle's kind of matrix: rows proportional through a radical
    (rank 1 of 2 everywhere), its determinant cancels to 0 only after seconds; rank 1
    at random points over F_p says so first. A full-rank matrix of angles, and one with
    a function F_p has no value of (exp), are not called deficient."""
    from nhham.lagrangian.quantities import _deficient_at_random_points

    x, y, v, w = sp.symbols("x y v w")
    root = sp.sqrt(v ** 2 - w ** 2 + x ** 2)
    proportional = sp.Matrix([[v / root, -w / root, x * sp.sin(y)],
                              [v * root, -w * root, x * sp.sin(y) * root ** 2]])
    assert sp.simplify(proportional.row(1) - root ** 2 * proportional.row(0)) == \
        sp.zeros(1, 3)
    assert _deficient_at_random_points(proportional, 2)
    full = sp.Matrix([[sp.cos(y), sp.sin(y), x], [-sp.sin(y), sp.cos(y), v * root]])
    assert not _deficient_at_random_points(full, 2)
    assert not _deficient_at_random_points(sp.Matrix([[sp.exp(x), 0], [0, sp.exp(x)]]), 2)
    # a polynomial matrix of rank 1 whose rows differ by a factor sin^2 + cos^2 - 1 + 2
    trig = sp.Matrix([[x, y], [x * (sp.sin(y) ** 2 + sp.cos(y) ** 2 + 1),
                               2 * y]])
    assert _deficient_at_random_points(trig, 2)
