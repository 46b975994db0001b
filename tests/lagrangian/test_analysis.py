"""The constraint algorithm's Lagrangian entry point (analyze_constraints): the system
split into independent blocks and merged back, and the integrability of the constraint
distribution it reports. Expected values are derived by hand in the docstrings."""

import sympy as sp

from handmade import rolling_disk, same_vector, two_blocks, zero
from nhham import System
from nhham.lagrangian.analysis import analyze_constraints

q1, q2, q3 = sp.symbols("q1 q2 q3")
v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
l1, l3 = sp.symbols("lambda_1 lambda_3")


def test_integrable_nonholonomic_constraint_is_recognised():
    """phi = q2 v1 + q1 v2 = d(q1 q2)/dt: the distribution is integrable (holonomic)."""
    s = System(["q1", "q2", "q3"], (v1**2 + v2**2 + v3**2) / 2, [q2 * v1 + q1 * v2])
    a = analyze_constraints(s)
    assert a.integrable is True
    assert a.integrability.first_integrals == (("constraints[0]", q1 * q2),)
    assert a.status == "determined"
    assert analyze_constraints(rolling_disk()[0]).integrable is False


def test_two_decoupled_subsystems_are_separate_blocks():
    """Rolling disk (x, y, theta, phi) + Example 3.2 (q1, q2, q3), L the sum.
    Blocks: disk [x, y, theta, phi] with phi_1, phi_2 (lambda_1, lambda_2 as in 2.1);
    [q1, q3] with v1 + v3 (lambda_3 = q1, three stages); q2 is free and joins a free
    block."""
    s = two_blocks()
    m, R = sp.symbols("m R")
    a = analyze_constraints(s)
    names = [[q.name for q in b.coordinates] for b in a.blocks]
    assert names == [["x", "y", "theta", "phi"], ["q1", "q3"], ["q2"]]
    assert [b.run.status for b in a.blocks] == ["determined"] * 3
    assert len(a.blocks[0].run.stages) == 1 and len(a.blocks[1].run.stages) == 3
    assert a.status == "determined" and len(a.stages) == 3
    assert [st.rank for st in a.stages] == [2, 2, 3]
    th, thd, phd = sp.symbols("theta theta_dot phi_dot")
    assert a.multipliers[l3] == q1
    assert zero(a.multipliers[l1] - m * R * thd * phd * sp.sin(th))
    xd, yd = sp.symbols("x_dot y_dot")
    expected = [xd, yd, thd, phd, v1, v2, v3,
                -R * thd * phd * sp.sin(th), R * thd * phd * sp.cos(th), 0, 0, 0, 0, q1]
    assert same_vector(a.dynamics, expected)
    whole = analyze_constraints(s, decompose=False)
    assert len(whole.blocks) == 1 and whole.status == "determined"
    assert same_vector(whole.dynamics, expected)
    assert [st.rank for st in whole.stages] == [2, 2, 3]
