"""The Dirac flow against the projected field at exact points of a curved M_f
(nhham.hamiltonian.dirac_points), and what `nhham compare` reports there.

Expected values: by hand for the pendulum-set disc integrator (X_D - X in closed form, see
the scene's header); for the bead on a sphere with a rotor, the true p_phi' from the
Euler-Lagrange equations with multipliers solved by sympy in the test (the Dirac flow has
p_phi' = 0: H, g and g^c do not depend on phi); holonomic constraints give X_D = X.
"""

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from sympy.external.gmpy import MPQ

import nhham
from nhham import models
from nhham.hamiltonian.classification import classify_constraints
from nhham.hamiltonian.dirac import dirac_vs_projected
from nhham.hamiltonian.dirac_points import DiracDifference
from nhham.hamiltonian.side import hamiltonian_side
from nhham.lagrangian.engine import Policy, decide
from nhham.lagrangian.formulas import dirac_difference
from nhham.lagrangian.linalg import FloatMatrix
from nhham.lagrangian.submanifold import Submanifold
from nhham.system.evaluation import Backend

SCENES = Path(__file__).parent / "scenes"
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def scene(name, folder=SCENES):
    return nhham.load_scene(folder / name, check_initial=False).system


def difference_at(system, point):
    """X_D - X at a rational point of M_f (symbol name -> Fraction-like), as Rationals."""
    classes = classify_constraints(system)
    q = DiracDifference(hamiltonian_side(system), classes.constraints_TQ,
                        classes.second_class_indices)
    env = {s: MPQ(sp.Rational(point[s.name]).p, sp.Rational(point[s.name]).q)
           for s in (*system.coordinates, *system.velocities)}
    env.update({p: MPQ(sp.Rational(str(v)).p, sp.Rational(str(v)).q)
                for p, v in system.parameter_values.items()})
    return classes, [sp.Rational(int(x.numerator), int(x.denominator)) for x in q.value(env)]


def test_integrator_difference_is_the_hand_closed_form():
    """At (x, y) = (3/5, 4/5), x' = 4, y' = -3, phi' = 1, s' = x phi': lambda =
    -J M x' phi'/(J + M x^2) = -200/61, so X_D - X = (0, .., 0, -lambda x, lambda)."""
    system = scene("pendulum_integrator.toml")
    point = {"x": "3/5", "y": "4/5", "phi": "1/3", "s": "2", "x_dot": "4", "y_dot": "-3",
             "phi_dot": "1", "s_dot": "3/5"}
    classes, got = difference_at(system, point)
    assert classes.second_class_set == ("holonomic[0]", "holonomic[0].lift")
    J, M, x, xd, phid = sp.Rational(1, 2), 2, sp.Rational(3, 5), 4, 1
    lam = -J * M * xd * phid / (J + M * x**2)
    assert got == [0, 0, 0, 0, 0, 0, -lam * x, lam]


def _true_p_phi_rate(point):
    """d/dt (J (phi' + x')) on the bead with a rotor, from the Euler-Lagrange equations
    with multipliers of g^c and the rotor constraint, solved by sympy at the point."""
    t = sp.Symbol("t")
    m, J, g = 1, sp.Rational(1, 2), sp.Rational(981, 100)
    x, y, z, phi = (sp.Function(n)(t) for n in ("x", "y", "z", "phi"))
    qs = [x, y, z, phi]
    L = (m * (x.diff(t)**2 + y.diff(t)**2 + z.diff(t)**2) / 2
         + J * (phi.diff(t) + x.diff(t))**2 / 2 - m * g * z)
    cons = [x * x.diff(t) + y * y.diff(t) + z * z.diff(t),
            phi.diff(t) - z * x.diff(t) - x * y.diff(t)]
    l1, l2 = sp.symbols("l1 l2")
    eqs = [sp.diff(L.diff(qd), t) - L.diff(q) + l1 * c1 + l2 * c2
           for q, qd, c1, c2 in zip(qs, [q.diff(t) for q in qs],
                                    [cons[0].diff(q.diff(t)) for q in qs],
                                    [cons[1].diff(q.diff(t)) for q in qs])]
    eqs += [c.diff(t) for c in cons]
    acc = sp.symbols("ax ay az aphi")
    vel = sp.symbols("vx vy vz vphi")
    sub = {q.diff(t, 2): a for q, a in zip(qs, acc)}
    sub.update({q.diff(t): v for q, v in zip(qs, vel)})
    eqs = [e.subs(sub) for e in eqs]
    values = {**{q: sp.Rational(point[n]) for q, n in zip(qs, ("x", "y", "z", "phi"))},
              **{v: sp.Rational(point[n + "_dot"]) for v, n in zip(vel, ("x", "y", "z",
                                                                        "phi"))}}
    sol = sp.solve([e.subs(values) for e in eqs], [*acc, l1, l2], dict=True)[0]
    return J * (sol[acc[3]] + sol[acc[0]])


def test_rotor_on_sphere_differs_in_p_phi_by_the_true_torque():
    """At (2/3, 1/3, 2/3) on the unit sphere with x' = 1, y' = 2 (z' = -2, phi' = 2 from the
    constraints): the Dirac flow has p_phi' = 0, so (X_D - X)(p_phi) = -(true p_phi'), and
    the q-components agree."""
    system = scene("rotor_on_sphere.toml")
    point = {"x": "2/3", "y": "1/3", "z": "2/3", "phi": "0", "x_dot": "1", "y_dot": "2",
             "z_dot": "-2", "phi_dot": "2"}
    classes, got = difference_at(system, point)
    assert classes.second_class_set == ("holonomic[0]", "holonomic[0].lift")
    rate = _true_p_phi_rate(point)
    assert rate != 0
    assert got[:4] == [0, 0, 0, 0]
    assert got[7] == -rate


def _compare(path):
    from nhham.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(["compare", str(path), "--json", "--budget", "60"])
    return rc, json.loads(out.getvalue())


@pytest.mark.parametrize("name, equal, components", [
    ("rotor_on_sphere.toml", False, {"p_phi"}),
    ("pendulum_integrator.toml", False, {"p_phi", "p_s"}),
    ("rotor_on_sphere_geared.toml", True, set()),
])
def test_compare_decides_the_dirac_flow_at_points_of_a_curved_Mf(name, equal, components):
    """n = 4 on a curved M_f: the Dirac verdict is given (a proof where the flows differ,
    in the components derived by hand; agreement with its error bound where the
    constraints are holonomic), not 'not available'."""
    rc, env = _compare(SCENES / name)
    assert rc == 0 and not any("Dirac" in w for w in env["warnings"])
    d = env["result"]["dirac_vs_projected"]
    assert d["equal"] is equal and d["difference"] is None
    if equal:
        assert d["components"] == [] and d["method"] == "exact at points"
        assert 0 < d["error_bound"] < 1e-9
    else:
        assert components <= set(d["components"]) and d["method"] == "exact"
        assert d["error_bound"] == 0
        assert not set(d["components"]) & {"x", "y", "z", "phi", "s"}
    if name == "pendulum_integrator.toml":
        assert set(d["components"]) == components


@pytest.mark.parametrize("example", ["pendulum_cartesian.toml", "particle_on_sphere.toml"])
def test_holonomic_curved_examples_agree_at_points(example):
    """Holonomic constraints: X_D - X is 0 at every point over F_p of the curved M_f."""
    system = scene(example, EXAMPLES)
    classes = classify_constraints(system)
    M = Submanifold(system, tuple(classes.constraints_TQ))
    assert M.curved
    verdict = decide(DiracDifference(hamiltonian_side(system), classes.constraints_TQ,
                                     classes.second_class_indices), M, Policy())
    d = verdict.decision
    assert d.value is True and d.method == "exact at points" and verdict.components == ()
    assert 0 < d.error_bound < 1e-9 and "curved" in d.detail
    # The symbolic route (n <= 3) agrees.
    assert dirac_vs_projected(system).equal


def test_curved_M1_classification_is_decided_at_points(monkeypatch):
    """A q-dependent, non-diagonal W on a curved M_1 with an odd number of constraints:
    the rank of B is proved at a point over F_p (the combination's coefficients at float
    points, M_1 having no rational points) instead of falling back to sampling. (Its
    W^-1 is small, 11 operations times n = 4: the route at points is forced by a bound
    of 0.)"""
    monkeypatch.setattr("nhham.lagrangian.geometry.CLOSED_FORM_WORK", 0)
    system = nhham.loads_scene(
        (SCENES / "rotor_on_sphere.toml").read_text().replace(
            "J*(phi_dot + x_dot)**2/2", "J*(phi_dot + z*x_dot)**2/2"), check_initial=False
    ).system
    classes = classify_constraints(system)
    assert classes.method == "exact at points"
    assert classes.decisions["rank"].method == "exact" and classes.rank == 2
    report = dirac_vs_projected(system)
    assert not report.equal and "p_phi" in report.components


def _hamiltonian_route(side, chis, x):
    """X_D - X at a float point of M_f from the T*Q numeric layer (v = Leg^-1(q, p) at the
    point, canonical gradients of chi o Leg^-1): X_D = X_H - X_chi B^-1 {chi, H}, X from
    its multipliers."""
    be = Backend(None)
    num = side.numeric
    hp = num.point_from_tq(be, x)
    X, _ = num.projected_field(be, hp)
    XD = hp.X_H.copy()
    if chis:
        _, Gq, Gp = num.gradients(be, hp, chis)
        y = np.linalg.solve(Gq @ Gp.T - Gp @ Gq.T, Gq @ hp.Hp - Gp @ hp.Hq)
        XD = XD - np.concatenate([Gp.T @ y, -(Gq.T @ y)])
    return XD - X


@pytest.mark.parametrize("make", [lambda: models.snake(3),
                                  lambda: scene("rotor_on_sphere.toml")])
def test_the_formula_against_the_hamiltonian_numeric_layer(make):
    """The one formula of X_D - X (Lagrangian data, no Leg^-1), in float64, equals the
    T*Q route at seeded points of M_f (the snake: second-class constraints in p, so the
    q-components differ too)."""
    system = make()
    side = hamiltonian_side(system)
    # R and M_f only: the first-class combinations are not formed
    classes = classify_constraints(side, policy=Policy(combination_size=0))
    q = DiracDifference(side, classes.constraints_TQ, classes.second_class_indices)
    args = [*system.coordinates, *system.velocities, *system.parameters]
    n = system.n
    rows = [sp.lambdify(args, sp.Matrix(r), "numpy") for r in q.data]
    points, _ = Submanifold(system, tuple(classes.constraints_TQ), exact=False).points()
    chis = [classes.constraints_TQ[a] for a in classes.second_class_indices]
    for x in points[:3]:
        vals = [float(x[s]) for s in args]
        W, M, mu, F, drift, v, Jq, Jv, Jt = (FloatMatrix(np.array(f(*vals), dtype=float)
                                                     .reshape(len(r), -1) if r else
                                                     np.zeros((0, n))) for f, r in
                                          zip(rows, q.data))
        got = dirac_difference(W, M, mu, F, drift, v, Jq, Jv, Jt=Jt).a.ravel()
        want = _hamiltonian_route(side, chis, x)
        assert np.allclose(got, want, rtol=1e-9, atol=1e-12)
        assert np.max(np.abs(got)) > 1e-6
