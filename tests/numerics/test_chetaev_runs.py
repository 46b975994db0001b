"""Nonlinear (Chetaev) constraints in numbers, against closed forms worked out by hand.

Every system is built here with :class:`nhham.System`; the reference values come from
the closed forms in the docstrings (DESIGN.md §2's signs: m a = F - lambda d phi/d v).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import nhham
from nhham.errors import InputError
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate

G = 9.81


def appell_hamel(m=1.3, a=0.5):
    """z' = a sqrt(x'^2 + y'^2), phi = a s - z', gravity along -z.

    By hand: m x'' = -lambda a x'/s (so the horizontal direction is fixed), m z'' =
    -m g + lambda, and z'' = a s' = -lambda a^2/m give lambda = m g/(1 + a^2),
    s(t) = s0 - a g t/(1 + a^2), z'' = -a^2 g/(1 + a^2); phi is homogeneous of degree 1
    in v, so the reaction's power -lambda (d phi/d v) v = -lambda phi vanishes: E conserved.
    """
    return nhham.System(["x", "y", "z"], "m*(x_dot**2 + y_dot**2 + z_dot**2)/2 - m*g*z",
                        ["a*sqrt(x_dot**2 + y_dot**2) - z_dot"],
                        parameters={"m": m, "g": G, "a": a})


def isokinetic(m=0.7, c=2.0):
    """x'^2 + y'^2 = c^2 in gravity (phi = (x'^2 + y'^2 - c^2)/2, d phi/d v = v).

    By hand, from the origin with velocity (c, 0) and u = g t/c: x = (c^2/g) gd(u),
    y = -(c^2/g) ln cosh(u), x' = c sech(u), y' = -c tanh(u), lambda = -m g y'/c^2; the
    kinetic energy stays m c^2/2, the total changes by m g y (the reaction's work).
    """
    return nhham.System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2 - m*g*y",
                        ["(x_dot**2 + y_dot**2 - c**2)/2"],
                        parameters={"m": m, "g": G, "c": c})


def perpendicular(m1=1.0, m2=2.0, k=3.0):
    """v1 . v2 = 0 for two particles, particle 1 in gravity, particle 2 on a spring.

    By hand (m_k a_k = F_k - lambda d phi/d v_k, d phi/d v_1 = v2, d phi/d v_2 = v1):
    d phi/dt = 0 gives lambda = (F1.v2/m1 + F2.v1/m2)/(|v2|^2/m1 + |v1|^2/m2), the
    opposite sign of the formula written with the reaction +lambda d phi/d v; phi is
    homogeneous of degree 2, so the reaction does no work: E conserved.
    """
    return nhham.System(["x1", "y1", "x2", "y2"],
                        "m1*(x1_dot**2 + y1_dot**2)/2 + m2*(x2_dot**2 + y2_dot**2)/2"
                        " - m1*g*y1 - k*(x2**2 + y2**2)/2",
                        ["x1_dot*x2_dot + y1_dot*y2_dot"],
                        parameters={"m1": m1, "m2": m2, "g": G, "k": k})


TIGHT = dict(rtol=1e-12, atol=1e-12, warn=False)


def test_appell_hamel_closed_form():
    m, a, s0 = 1.3, 0.5, 5.0
    t = np.linspace(0.0, 1.0, 6)
    res = simulate(numeric_model(appell_hamel(m, a), backend="numpy"), (0.0, 1.0),
                   [0, 0, 0, 3.0, 4.0, a * s0], t_eval=t, **TIGHT)
    assert res.success, res.message
    x, y, z, xd, yd, zd = res.y
    s = s0 - a * G * t / (1 + a**2)
    assert np.max(np.abs(np.hypot(xd, yd) - s)) < 1e-10
    assert np.max(np.abs(zd - a * s)) < 1e-10
    # the horizontal direction stays (3, 4)/5, and so does the path's
    assert np.max(np.abs(xd / np.hypot(xd, yd) - 0.6)) < 1e-12
    assert np.max(np.abs(4 * x - 3 * y)) < 1e-10
    # z = a (s0 t - a g t^2 / (2 (1 + a^2)))
    assert np.max(np.abs(z - a * (s0 * t - a * G * t**2 / (2 * (1 + a**2))))) < 1e-10
    assert np.max(np.abs(res.multipliers - m * G / (1 + a**2))) < 1e-9
    assert res.energy_drift < 1e-10


def test_isokinetic_particle_closed_form():
    m, c = 0.7, 2.0
    t = np.linspace(0.0, 1.0, 6)
    res = simulate(numeric_model(isokinetic(m, c), backend="numpy"), (0.0, 1.0),
                   [0, 0, c, 0], t_eval=t, **TIGHT)
    assert res.success, res.message
    u = G * t / c
    gd = 2 * np.arctan(np.tanh(u / 2))
    exact = np.array([c**2 / G * gd, -c**2 / G * np.log(np.cosh(u)), c / np.cosh(u),
                      -c * np.tanh(u)])
    assert np.max(np.abs(res.y - exact)) < 1e-9
    assert np.max(np.abs(res.multipliers[0] - m * G * np.tanh(u) / c)) < 1e-8
    kinetic = m * (res.y[2]**2 + res.y[3]**2) / 2
    assert np.max(np.abs(kinetic - m * c**2 / 2)) < 1e-11
    # the total energy is not conserved: it changes by m g y, the reaction's work
    energy = res.diagnostics.energy
    assert abs(energy[-1] - energy[0] - m * G * exact[1, -1]) < 1e-9
    assert abs(energy[-1] - energy[0]) > 1.0
    assert res.diagnostics.energy_balance_residual < 1e-9


@pytest.mark.skipif(nhham.numerics.codegen.c_compiler() is None, reason="no C compiler")
@pytest.mark.parametrize("projection", [False, True])
def test_the_compiled_loop_takes_a_nonlinear_constraint(projection):
    """The isokinetic particle's closed form by the compiled DOP853 loop (its C projection
    onto M_1 is Newton's method for a nonlinear constraint): x = (c^2/g) gd(u),
    y = -(c^2/g) ln cosh(u), u = g t/c; the kinetic energy constant."""
    m, c = 0.7, 2.0
    res = simulate(numeric_model(isokinetic(m, c), backend="c"), (0.0, 1.0), [0, 0, c, 0],
                   loop="compiled", projection=projection, **TIGHT)
    assert res.success and res.settings["loop"] == "compiled"
    u = G / c
    exact = [c**2 / G * 2 * math.atan(math.tanh(u / 2)), -c**2 / G * math.log(math.cosh(u))]
    assert np.max(np.abs(res.y[:2, -1] - exact)) < 1e-9
    kinetic = (res.y[2]**2 + res.y[3]**2) / 2
    assert np.max(np.abs(kinetic - c**2 / 2)) < (1e-13 if projection else 1e-10)


def test_perpendicular_velocities_multiplier_and_energy():
    m1, m2, k = 1.0, 2.0, 3.0
    res = simulate(numeric_model(perpendicular(m1, m2, k), backend="numpy"), (0.0, 1.0),
                   [0, 0, 1.0, 0, 1.0, 0.5, -0.5, 1.0], t_eval=np.linspace(0, 1, 5), **TIGHT)
    assert res.success, res.message
    x1, y1, x2, y2, u1, w1, u2, w2 = res.y
    assert np.max(np.abs(u1 * u2 + w1 * w2)) < 1e-10
    F1 = np.array([0 * x1, -m1 * G * np.ones_like(x1)])
    F2 = np.array([-k * x2, -k * y2])
    v1, v2 = np.array([u1, w1]), np.array([u2, w2])
    lam = ((np.sum(F1 * v2, axis=0) / m1 + np.sum(F2 * v1, axis=0) / m2)
           / (np.sum(v2 * v2, axis=0) / m1 + np.sum(v1 * v1, axis=0) / m2))
    assert np.max(np.abs(res.multipliers[0] - lam)) < 1e-8
    assert res.energy_drift < 1e-9


def test_projection_onto_m1_is_newton_for_a_nonlinear_constraint():
    # (2, 0.3) onto x'^2 + y'^2 = 4 in W = m I: the kinetic-metric projection keeps the
    # direction of v (d phi/d v = v), so it ends at 2 (2, 0.3)/|(2, 0.3)|.
    model = numeric_model(isokinetic(0.7, 2.0), backend="numpy")
    out = model.project(np.array([0.0, 0.0, 2.0, 0.3]))
    assert np.allclose(out.y[2:], 2 * np.array([2.0, 0.3]) / math.hypot(2.0, 0.3),
                       atol=1e-14, rtol=0)


@pytest.mark.parametrize("method, order", [("rattle", 2), ("rattle4", 4)])
def test_rattle_takes_a_nonlinear_constraint_symmetric_and_of_its_order(method, order):
    """Chetaev's rule in RATTLE (the reaction along d phi/d v at each grid point, phi at
    the midpoint inside the step): the isokinetic closed form x = (c^2/g) gd(u),
    y = -(c^2/g) ln cosh(u) at t = 1, the error falling by 2^order when h halves, |v| = c
    to round-off at every grid point, and a step undone by the step with -h."""
    from nhham.numerics.integrators import rattle_step

    m, c = 0.7, 2.0
    model = numeric_model(isokinetic(m, c), backend="numpy")
    u = G / c
    exact = [c**2 / G * 2 * math.atan(math.tanh(u / 2)), -c**2 / G * math.log(math.cosh(u))]
    errors = []
    for h in (0.02, 0.01):
        res = simulate(model, (0.0, 1.0), [0, 0, c, 0], method=method, step=h, warn=False)
        assert res.success, res.message
        assert np.max(np.abs(res.y[2]**2 + res.y[3]**2 - c**2)) < 1e-12
        errors.append(np.max(np.abs(res.y[:2, -1] - exact)))
    assert abs(math.log2(errors[0] / errors[1]) - order) < 0.2
    y1 = rattle_step(model, [0, 0, c, 0], 0.1)
    assert np.allclose(rattle_step(model, y1, -0.1), [0, 0, c, 0], atol=1e-14, rtol=0)


def test_work_precision_shows_the_energy_balance_with_a_working_reaction():
    # the isokinetic reaction does work (E changes by m g y): the table's energy column is
    # the balance |E(t) - E(0) - W(t)|, small, not the drift of order 1
    from nhham.numerics.workprecision import work_precision

    model = numeric_model(isokinetic(0.7, 2.0), backend="numpy")
    result = work_precision(model, [0, 0, 2.0, 0], (0.0, 1.0), methods=["DOP853"],
                            tolerances=(1e-8,), projection_variants=False, quick=True)
    assert result.forced
    rows = [r for r in result.rows if r.method == "DOP853"]
    assert rows and all(r.energy_balance_residual < 1e-6 and r.energy_drift > 1.0
                        for r in rows)


def test_reference_method_keeps_the_isokinetic_closed_form():
    # the mpmath extrapolation on phi(q, v) = 0 (Chetaev's rule in the mp kernels)
    c = 2.0
    res = simulate(numeric_model(isokinetic(0.7, c), backend="numpy"), (0.0, 0.2),
                   [0, 0, c, 0], method="reference", warn=False)
    u = G * 0.2 / c
    exact = [c**2 / G * 2 * math.atan(math.tanh(u / 2)), -c**2 / G * math.log(math.cosh(u)),
             c / math.cosh(u), -c * math.tanh(u)]
    assert np.max(np.abs(res.y[:, -1] - exact)) < 1e-13


def test_every_method_record_says_whether_it_takes_a_nonlinear_constraint():
    from nhham.numerics.methods import METHODS

    model = numeric_model(isokinetic(0.7, 2.0), backend="numpy")
    for name, method in METHODS.items():
        options = dict(step=0.01) if method.fixed_step else {}
        if method.takes_nonlinear:
            res = simulate(model, (0.0, 0.05), [0, 0, 2.0, 0], method=name, warn=False,
                           **options)
            assert res.success and abs(np.hypot(*res.y[2:, -1]) - 2.0) < 1e-6, name
        else:
            with pytest.raises(InputError, match=method.nonlinear_refused[:30]):
                simulate(model, (0.0, 0.05), [0, 0, 2.0, 0], method=name, warn=False,
                         **options)


def test_a_speed_prescribed_in_time_is_both_kinds_at_once():
    """phi = sqrt(x'^2 + y'^2) - (1 + t) (nonlinear and time-dependent), L = |v|^2/2.

    By hand, from the origin with velocity (1, 0): the reaction -lambda v/|v| is along v,
    so the motion stays on the x axis with x' = 1 + t, x = t + t^2/2; x'' = 1 = -lambda, so
    lambda = -1; E = (1 + t)^2/2 grows by the reaction's power -lambda |v| = 1 + t."""
    system = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2",
                          ["sqrt(x_dot**2 + y_dot**2) - (1 + t)"])
    assert system.constraint_kinds == ("nonlinear (Chetaev)",) and system.time is not None
    t = np.linspace(0.0, 2.0, 5)
    res = simulate(numeric_model(system, backend="numpy"), (0.0, 2.0), [0, 0, 1.0, 0],
                   t_eval=t, **TIGHT)
    assert res.success, res.message
    exact = np.array([t + t**2 / 2, 0 * t, 1 + t, 0 * t])
    assert np.max(np.abs(res.y - exact)) < 1e-9
    assert np.max(np.abs(res.multipliers[0] + 1.0)) < 1e-8
    assert np.max(np.abs(res.diagnostics.energy - (1 + t)**2 / 2)) < 1e-9
    assert res.diagnostics.energy_balance_residual < 1e-9
