"""Vanishing and Rank asked directly of the decision engine, each step on its own.

On the rolling disk's M_1 the reduction gives x' = R cos(theta) phi' and
y' = R sin(theta) phi' (worked out by hand), so:
- x' - R cos(theta) phi' vanishes (exact), x' does not (it reduces to R cos(theta) phi');
- [[x' - R c phi', 0], [0, y']] has rank 1 (exact), and 1 at the sample points;
- the sampled step alone gives the same answers at float points.
"""

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
    # A deficient rank is not decided by the reduction alone: sampled, then proved by a
    # certificate (a nonzero 1 x 1 minor whose Schur complement vanishes on M).
    answers = answers_by_step(lambda: Rank(A), M, Policy())
    assert {step: a.value for step, a in answers.items()} == {"sampled": 1}
    decision = decide(Rank(A), M, M.policy)
    assert (decision.value, decision.method) == (1, "exact")
    # Full rank: det = R^2 cos(theta) sin(theta) phi'^2, a nonzero function on M.
    full = sp.Matrix([[xd, 0], [0, yd]])
    answers = answers_by_step(lambda: Rank(full), M, Policy())
    assert {step: a.value for step, a in answers.items()} == {"reduced": 2, "sampled": 2}
    assert decide(Rank(sp.zeros(0, 3)), M, M.policy).value == 0


def test_without_exact_steps_only_the_samples_decide():
    M = _M1().sampled_only()
    decision = decide(Vanishing(xd), M, M.policy)
    assert decision.value is False and decision.method == "sampled"
