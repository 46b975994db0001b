"""The records of a run of the constraint algorithm (nhham.lagrangian.records): the
tangency matrix, the multipliers, dynamics and projectors an AlgorithmRun derives from
its stages, and what an inconsistent run has none of. The fields are written out by hand
(W = Id or diag(1, 1, -1), Z_i = -W^-1 mu_i d/dv) and every expected value is derived in
the docstrings."""

import pytest
import sympy as sp

from nhham import System
from nhham.errors import ComputationError
from nhham.lagrangian.algorithm import run_algorithm
from nhham.lagrangian.records import tangency_matrix
from nhham.lagrangian.submanifold import Submanifold

q1, q2, q3 = sp.symbols("q1 q2 q3")
v1, v2, v3 = sp.symbols("q1_dot q2_dot q3_dot")
l1, a, b = sp.symbols("lambda_1 a b")


def _run(system, xi, Z, primary):
    labels = [f"constraints[{i}]" for i in range(len(primary))]
    return run_algorithm(sp.Matrix(xi), sp.Matrix(Z), primary, labels,
                         lambda eqs: Submanifold(system, eqs), variables=system.state)


def test_tangency_matrix_is_Z_i_of_chi_j():
    """chi_1 = q1 v2, chi_2 = v1 + q3; Z_1 = d/dv1, Z_2 = q2 d/dv2:
    A = [[Z_1(chi_1), Z_2(chi_1)], [Z_1(chi_2), Z_2(chi_2)]] = [[0, q1 q2], [1, 0]]."""
    variables = (q1, q2, q3, v1, v2, v3)
    Z = sp.Matrix([[0, 0, 0, 1, 0, 0], [0, 0, 0, 0, q2, 0]])
    A = tangency_matrix([q1 * v2, v1 + q3], Z, variables)
    assert A == sp.Matrix([[0, q1 * q2], [1, 0]])
    assert tangency_matrix([], Z, variables).shape == (0, 2)


def test_a_regular_run_and_its_projectors():
    """L = |v|^2/2 + q1, phi = v1 + v2 (W = Id): xi = (v, 1, 0, 0), Z = -(d/dv1 + d/dv2).
    A = Z(phi) = -2, b = xi(phi) = 1, so lambda = -b/A = 1/2 and the dynamics is
    xi + Z/2 = (v, 1/2, -1/2, 0). Q = Z B^-1 dphi = (e4 + e5)(e4 + e5)^T / 2 (in the
    order q, v), P = id - Q, and P(xi + s Z) is the dynamics for every s."""
    system = System(["q1", "q2", "q3"], (v1**2 + v2**2 + v3**2) / 2 + q1, [v1 + v2])
    xi = [v1, v2, v3, 1, 0, 0]
    Z = [[0, 0, 0, -1, -1, 0]]
    run = _run(system, xi, Z, [v1 + v2])
    assert run.status == "determined" and len(run.stages) == 1 and run.stages[0].consistent
    assert run.tangency_matrix == sp.Matrix([[-2]]) and run.tangency_rhs == sp.Matrix([[1]])
    assert dict(run.multipliers) == {l1: sp.Rational(1, 2)} and run.free_multipliers == 0
    expected = sp.Matrix([v1, v2, v3, sp.Rational(1, 2), -sp.Rational(1, 2), 0])
    assert run.dynamics == expected
    e = sp.Matrix([0, 0, 0, 1, 1, 0])
    assert run.projector_Q == e * e.T / 2
    assert run.projector_P == sp.eye(6) - e * e.T / 2
    s = sp.Symbol("s")
    assert run.project(sp.Matrix(xi) + s * sp.Matrix(Z).T) == expected
    assert "determined" in repr(run) and "1 stage(s)" in repr(run)


def test_a_free_multiplier_stays_a_symbol():
    """L = LOR (W = diag(1, 1, -1)), phi = v2 + v3: Z = -W^-1 (0, 1, 1) = (0, -1, 1) on v,
    Z(phi) = 0 and xi(phi) = 0 (xi = (v, 0, 0, 0)): nothing new, lambda_1 free, the
    dynamics is xi + lambda_1 Z and P = id (Q = 0: no block)."""
    system = System(["q1", "q2", "q3"], (v1**2 + v2**2 - v3**2) / 2, [v2 + v3])
    run = _run(system, [v1, v2, v3, 0, 0, 0], [[0, 0, 0, 0, -1, 1]], [v2 + v3])
    assert run.status == "underdetermined" and run.free_multiplier_symbols == (l1,)
    assert dict(run.multipliers) == {} and run.free_multipliers == 1
    assert run.dynamics == sp.Matrix([v1, v2, v3, 0, -l1, l1])
    assert run.projector_P == sp.eye(6)


def test_an_inconsistent_run_has_no_dynamics_and_no_projector():
    """L = LOR + q2 + q2^3/3, phi = v2 + v3: xi = (v, 0, 1 + q2^2, 0), Z = (0, -1, 1) on v;
    Z(phi) = 0 and xi(phi) = 1 + q2^2 never vanishes: no solution."""
    system = System(["q1", "q2", "q3"], (v1**2 + v2**2 - v3**2) / 2 + q2 + q2**3 / 3,
                    [v2 + v3])
    run = _run(system, [v1, v2, v3, 0, 1 + q2**2, 0], [[0, 0, 0, 0, -1, 1]], [v2 + v3])
    assert run.status == "inconsistent" and not run.stages[-1].consistent
    assert run.dynamics is None and dict(run.multipliers) == {}
    assert run.projector_Q is None and run.projector_P is None
    with pytest.raises(ComputationError, match="inconsistent"):
        run.project([a, b, 0, 0, 0, 0])
