"""The segway's first-class combination in closed form (examples/segway.toml).

n = 6, m = 3, one first-class combination: it used to be given up (the bracket entries
multiplied by the transported constraints' denominators F_a^2 F_b^2 ran past the size and
time bounds). Expected values: B c = 0 at points of M_1 with B = {chi_a, chi_b} computed in
the test from L by numpy (the Lagrangian bracket f_q W^-1 g_v - (W^-1 f_v) g_q -
(W^-1 f_v)^T (M - M^T) W^-1 g_v, M_AB = d^2 L / dv^A dq^B) and c the closed-form
coefficients evaluated at p = W v.
"""

from pathlib import Path

import numpy as np
import sympy as sp

import nhham
from nhham.hamiltonian.classification import classify_constraints
from nhham.system.naming import momentum_symbol

SEGWAY = Path(__file__).resolve().parents[2] / "examples" / "segway.toml"


def _brackets_and_momenta(system):
    """A function of a point of TQ giving (B, p = dL/dv) there, by numpy from L,
    independently of nhham."""
    q, v = list(system.coordinates), list(system.velocities)
    values = {p: sp.Float(x) for p, x in system.parameter_values.items()}
    L = system.lagrangian.subs(values)
    phi = sp.Matrix(system.phi).subs(values)
    parts = [sp.hessian(L, v), sp.Matrix(len(v), len(q), lambda a, b: sp.diff(L, v[a], q[b])),
             phi.jacobian(q), phi.jacobian(v), sp.Matrix([sp.diff(L, s) for s in v])]
    f = sp.lambdify(q + v, parts, "numpy")

    def at(point):
        W, M, Jq, Jv, p = (np.array(x, dtype=float) for x in f(*point))
        U = np.linalg.solve(W, Jv.T)
        JU = Jq @ U
        return JU - JU.T - U.T @ (M - M.T) @ U, p.ravel()
    return at


def test_segway_first_class_combination_in_closed_form():
    system = nhham.load_scene(SEGWAY).system
    classes = classify_constraints(system)
    assert (classes.first_class, classes.second_class) == (1, 2)
    assert classes.second_class_set == ("constraints[0]", "constraints[1]")
    assert classes.first_class_combinations is not None
    assert classes.decisions["combinations"].value is True
    coeffs = classes.combination_coefficients[0]
    assert set(coeffs) == {"constraints[0]", "constraints[1]", "constraints[2]"}
    assert coeffs["constraints[2]"] == 1
    rng = np.random.default_rng(3)
    r, d = system.parameter_values[sp.Symbol("r")], system.parameter_values[sp.Symbol("d")]
    q = list(system.coordinates)
    params = list(system.parameter_values)
    c_of = sp.lambdify(q + [momentum_symbol(s) for s in q] + params,
                       [coeffs[f"constraints[{a}]"] for a in range(3)], "numpy")
    values = [float(system.parameter_values[s]) for s in params]
    brackets = _brackets_and_momenta(system)
    for _ in range(3):
        x, y, psi, theta, pl, pr = rng.uniform(-1, 1, 6)
        thd, wl, wr = rng.uniform(-2, 2, 3)
        # on M_1: the axle midpoint moves along the heading at r (wl + wr)/2, and
        # psi' = r (wr - wl)/(2 d)
        vf = r * (wl + wr) / 2
        point = [x, y, psi, theta, pl, pr, vf * np.cos(psi), vf * np.sin(psi),
                 r * (wr - wl) / (2 * d), thd, wl, wr]
        B, p = brackets(point)
        c = np.array(c_of(*point[:6], *p, *values), dtype=float)
        assert np.abs(B @ c).max() <= 1e-9 * np.abs(B).max() * np.abs(c).max()
        assert np.abs(B).max() > 1e-3
