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


def _exact_brackets_with(system, gamma, points):
    """{gamma, chi_b o Leg^-1} at exact points of M_f, for every final constraint chi_b,
    from L alone: the canonical bracket with d(chi o Leg^-1)/dp = W^-1 mu^T and
    d(chi o Leg^-1)/dq = d chi/dq - mu W^-1 d^2 L/dv dq (v = Leg^-1(q, p) moves with q),
    all at the point in exact rationals (angles at rational points of the circle)."""
    q, v = list(system.coordinates), list(system.velocities)
    p = [momentum_symbol(s) for s in q]
    values = {s: sp.nsimplify(x, rational=True) for s, x in system.parameter_values.items()}
    L = system.lagrangian.xreplace(values)
    chis = [c.xreplace(values) for c in system.phi]
    g = gamma.xreplace(values)
    dg_q, dg_p = [sp.diff(g, s) for s in q], [sp.diff(g, s) for s in p]
    W = sp.hessian(L, v)
    Mqv = sp.Matrix(len(v), len(q), lambda a, b: sp.diff(L, v[a], q[b]))
    out = []
    for angles, rest, free in points:
        trig = {}
        for name, t in angles.items():   # sin, cos rational: (2t, 1 - t^2) / (1 + t^2)
            trig[sp.sin(sp.Symbol(name))] = 2 * t / (1 + t ** 2)
            trig[sp.cos(sp.Symbol(name))] = (1 - t ** 2) / (1 + t ** 2)
        at = {sp.Symbol(k): x for k, x in rest.items()}
        at.update({sp.Symbol(k): x for k, x in free.items()})
        # the dependent velocities from the constraints at this point (exactly)
        dep = [s for s in v if s.name not in free]
        eqs = [c.xreplace(trig).xreplace(at) for c in chis]
        at.update(sp.solve(eqs, dep, dict=True)[0])
        assert all(e.xreplace(at) == 0 for e in eqs)
        Wp = W.xreplace(trig).xreplace(at)
        Mp = Mqv.xreplace(trig).xreplace(at)
        momenta = {ps: sp.diff(L, s).xreplace(trig).xreplace(at) for ps, s in zip(p, v)}
        full = {**at, **momenta}
        gq = sp.Matrix([e.xreplace(trig).xreplace(full) for e in dg_q])
        gp = sp.Matrix([e.xreplace(trig).xreplace(full) for e in dg_p])
        assert g.xreplace(trig).xreplace(full) == 0            # gamma vanishes on M_f
        row = []
        for c in chis:
            mu = sp.Matrix([[sp.diff(c, s).xreplace(trig).xreplace(at) for s in v]])
            cq = sp.Matrix([[sp.diff(c, s).xreplace(trig).xreplace(at) for s in q]])
            Winv_mu = Wp.LUsolve(mu.T)
            dq = cq - (Winv_mu.T * Mp)
            row.append(sp.nsimplify((gq.T * Winv_mu)[0] - (dq * gp)[0]))
        out.append(row)
    return out


def test_segway_combination_is_short_and_first_class_at_exact_points():
    """The coefficients are formed reduced on M_f: a few hundred characters each (they had
    56,000 and 30,000), the combination a few thousand; its brackets with all three final
    constraints vanish exactly at random exact points of M_f, while the bracket of the
    third constraint alone with the first does not (so the check can fail)."""
    system = nhham.load_scene(SEGWAY).system
    classes = classify_constraints(system)
    (gamma,) = classes.first_class_combinations
    coeffs = classes.combination_coefficients[0]
    assert max(len(str(c)) for c in coeffs.values()) < 1000
    assert len(str(gamma)) < 4000
    R = sp.Rational
    points = [({"psi": R(1, 3), "theta": R(2, 7)}, {"x": R(1, 2), "y": R(-3, 4)},
               {"theta_dot": R(3, 5), "phiL_dot": R(7, 4), "phiR_dot": R(-2, 3)}),
              ({"psi": R(-5, 2), "theta": R(1, 9)}, {"x": R(2), "y": R(1, 7)},
               {"theta_dot": R(-1, 3), "phiL_dot": R(1, 5), "phiR_dot": R(9, 4)})]
    for row in _exact_brackets_with(system, gamma, points):
        assert row == [0, 0, 0]
    third = _exact_brackets_with(system, sp.Add(*[
        c * nhham.legendre_map(system).transport(phi) for c, phi in
        zip([0, 0, 1], system.phi)]), points[:1])
    assert third[0][0] != 0
