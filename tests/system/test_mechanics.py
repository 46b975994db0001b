"""nhham against sympy.physics.mechanics.LagrangesMethod on the same systems.

The core check: at random points of M_1 the constrained accelerations and
multipliers from nhham (its saddle-point ingredients, and for the small
systems its symbolic projected field P(xi_L)) equal LagrangesMethod's
(``mass_matrix_full`` x = ``forcing_full``) to 1e-12, and nhham's
(q'', lambda) make ``lm.eom`` vanish.

Signs: ``lm.eom`` is d/dt(dL/dq') - dL/dq + mu^T lam (lam_coeffs = -mu and
eom = ... - lam_coeffs^T lam), nhham's convention; but sympy 1.14's
``mass_matrix`` appends ``lam_coeffs.T`` = -mu^T, so the lam solved from
``mass_matrix_full``/``rhs()`` is minus the lam of ``lm.eom``. The constraint
order (holonomic lifts first) is the same on both sides.
"""

import math
import zlib

import numpy as np
import pytest
import sympy as sp
from sympy.matrices.exceptions import NonInvertibleMatrixError
from sympy.physics import mechanics as me

from nhham import InputError, RedundantConstraintError, System, ValidationError
from nhham.lagrangian.geometry import lagrangian_geometry
from nhham.system.mechanics import from_lagranges_method, from_mechanics, to_lagranges_method
from nhham.system.models import (
    chaplygin_sleigh,
    knife_edge_inclined,
    nonholonomic_particle,
    rolling_disk,
    snake,
    two_particle_rod,
)
from test_models import constrained_accelerations, point_on_M1

t = me.dynamicsymbols._t
S = sp.Symbol


# ------------------------------------------------------------- helpers
def lagranges_solution(system, form, point):
    """(q'', lambda) from LagrangesMethod's full mass matrix at a numeric point."""
    lm, _, maps = form
    M = lm.mass_matrix_full.xreplace(maps.from_mechanics)
    F = lm.forcing_full.xreplace(maps.from_mechanics)
    leftover = (M.atoms(sp.Function) | F.atoms(sp.Function)) - M.atoms(sp.sin, sp.cos) \
        - F.atoms(sp.sin, sp.cos)
    assert not [f for f in leftover if isinstance(f, sp.core.function.AppliedUndef)]
    sub = {k: v for k, v in point.items()}
    x = np.linalg.solve(np.array(M.xreplace(sub).evalf(), float),
                        np.array(F.xreplace(sub).evalf(), float).ravel())
    n = system.n
    # minus: the mass matrix carries lam_coeffs.T = -mu^T (see the module docstring)
    return x[n:2 * n], -x[2 * n:]


def eom_residual(system, form, point, acc, lam):
    """lm.eom evaluated at nhham's accelerations and multipliers."""
    lm, qs, maps = form
    sub = dict(point)
    sub.update({maps.from_mechanics[f.diff(t, 2)]: a for f, a in zip(qs, acc)})
    sub.update({maps.from_mechanics[lv]: v for lv, v in zip(lm.lam_vec, lam)})
    eom = lm.eom.xreplace(maps.from_mechanics).xreplace(sub)
    return np.array(eom.evalf(), float).ravel()


def projected_accelerations(system, point):
    """The v-components of nhham's symbolic P(xi_L) and its multipliers at a point."""
    geo = lagrangian_geometry(system)
    field = np.array(geo.projected_field.xreplace(point).evalf(), float).ravel()
    lam = np.array(geo.multipliers.xreplace(point).evalf(), float).ravel()
    return field[system.n:], lam


def assert_close(a, b, tol=1e-12):
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(1.0, np.abs(b).max(initial=0.0))
    assert np.abs(a - b).max(initial=0.0) <= tol * scale, (a, b)


# ------------------------------------------------- agreement with sympy
SYSTEMS = {
    "rolling_disk": (rolling_disk, True),
    "knife_edge_inclined": (knife_edge_inclined, True),
    "chaplygin_sleigh": (chaplygin_sleigh, True),
    "nonholonomic_particle": (lambda: nonholonomic_particle(
        potential="k*(x**2 + y**2 + z**2)/2 + x*y", potential_parameters={"k": 0.7}), True),
    "two_particle_rod": (two_particle_rod, True),
    "snake2": (lambda: snake(2, m=1.3, l=0.8), False),
}


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_accelerations_agree_with_lagranges_method(name):
    build, symbolic_field = SYSTEMS[name]
    system = build()
    form = to_lagranges_method(system)
    form.lm.form_lagranges_equations()
    rng = np.random.default_rng(zlib.crc32(name.encode()))  # stable across runs
    for _ in range(5):
        point = point_on_M1(system, rng)
        a_lm, lam_lm = lagranges_solution(system, form, point)
        a_nh, lam_nh = constrained_accelerations(system, point)
        assert_close(a_nh, a_lm)
        assert_close(lam_nh, lam_lm)
        scale = max(1.0, np.abs(a_nh).max(), np.abs(lam_nh).max(initial=0.0))
        assert np.abs(eom_residual(system, form, point, a_nh, lam_nh)).max() < 1e-12 * scale
        if symbolic_field:
            a_p, lam_p = projected_accelerations(system, point)
            assert_close(a_p, a_lm)
            assert_close(lam_p, lam_lm)


def _disk_with(extra, drop_redundant):
    disk = rolling_disk()
    return System(disk.coordinates, disk.lagrangian, list(disk.constraints) + [extra],
                  parameters={p.name: v for p, v in disk.parameter_values.items()},
                  drop_redundant=drop_redundant)


def _lagranges_method_as_written(system_like, constraints):
    qs = [sp.Function(q.name)(t) for q in system_like.coordinates]
    to_m = {**dict(zip(system_like.coordinates, qs)),
            **{v: f.diff(t) for v, f in zip(system_like.velocities, qs)}}
    lm = me.LagrangesMethod(system_like.lagrangian.xreplace(to_m), qs,
                            nonhol_coneqs=[c.xreplace(to_m) for c in constraints])
    lm.form_lagranges_equations()
    return lm


def test_redundant_constraint_breaks_lagranges_method_not_nhham():
    """A third constraint phi_1 + 2 phi_2: LagrangesMethod's saddle-point matrix is
    singular; nhham reports it, or drops it and keeps the 2-constraint dynamics."""
    disk = rolling_disk()
    extra = disk.constraints[0] + 2 * disk.constraints[1]
    with pytest.raises(RedundantConstraintError, match=r"constraints\[2\].*redundant"):
        _disk_with(extra, drop_redundant=False)
    redundant = _disk_with(extra, drop_redundant=True)
    assert [d.label for d in redundant.dropped] == ["constraints[2]"]
    assert redundant.constraints == disk.constraints

    lm3 = _lagranges_method_as_written(disk, list(disk.constraints) + [extra])
    with pytest.raises(NonInvertibleMatrixError):
        lm3.rhs()

    form = to_lagranges_method(disk)
    form.lm.form_lagranges_equations()
    rng = np.random.default_rng(11)
    for _ in range(3):
        point = point_on_M1(disk, rng)
        a_lm, lam_lm = lagranges_solution(disk, form, point)
        a_red, lam_red = constrained_accelerations(redundant, point)
        assert_close(a_red, a_lm)
        assert_close(lam_red, lam_lm)


def test_heading_combination_breaks_lagranges_method():
    """cos(theta) phi_1 + sin(theta) phi_2 (rolling along the heading) is redundant too."""
    disk = rolling_disk()
    th = disk.coordinates[2]
    x_dot, y_dot, _, phi_dot = disk.velocities
    # cos(th) phi_1 + sin(th) phi_2, simplified as a user writes it
    extra = sp.cos(th) * x_dot + sp.sin(th) * y_dot - S("R") * phi_dot
    lm3 = _lagranges_method_as_written(disk, list(disk.constraints) + [extra])
    maps = to_lagranges_method(disk).maps
    point = point_on_M1(disk, np.random.default_rng(12))
    M = np.array(lm3.mass_matrix_full.xreplace(maps.from_mechanics).xreplace(point).evalf(),
                 float)
    assert np.linalg.matrix_rank(M) == M.shape[0] - 1
    # Written this way sympy's symbolic LU does not see the zero pivot: rhs()
    # returns 0/0 (a denominator that vanishes identically) instead of raising.
    try:
        rhs = lm3.rhs()
    except NonInvertibleMatrixError:
        return
    denominator = sp.denom(sp.together(rhs[disk.n]))
    assert sp.simplify(denominator) == 0


def test_heading_combination_is_dropped_by_nhham():
    disk = rolling_disk()
    th = disk.coordinates[2]
    x_dot, y_dot, _, phi_dot = disk.velocities
    # cos(th) phi_1 + sin(th) phi_2, simplified as a user writes it
    extra = sp.cos(th) * x_dot + sp.sin(th) * y_dot - S("R") * phi_dot
    with pytest.raises(RedundantConstraintError, match=r"constraints\[2\].*redundant"):
        _disk_with(extra, drop_redundant=False)
    redundant = _disk_with(extra, drop_redundant=True)
    assert redundant.constraints == disk.constraints
    combination = redundant.dropped[0].combination
    assert sp.simplify(combination["constraints[0]"] - sp.cos(th)) == 0
    assert sp.simplify(combination["constraints[1]"] - sp.sin(th)) == 0


# ------------------------------------------------------------ adapters
def test_round_trip_through_lagranges_method():
    for system in (two_particle_rod(symbolic=True), rolling_disk(symbolic=True), snake(2)):
        lm, qs, maps = to_lagranges_method(system)
        assert [f.func.__name__ for f in qs] == [q.name for q in system.coordinates]
        assert qs[0] == me.dynamicsymbols(system.coordinates[0].name)
        back = from_lagranges_method(lm, parameters=dict(
            (p.name, system.parameter_values.get(p)) for p in system.parameters))
        assert back.coordinates == system.coordinates
        assert back.velocities == system.velocities
        assert sp.expand(back.lagrangian - system.lagrangian) == 0
        assert len(back.constraints) == len(system.constraints)
        for a, b in zip(back.phi, system.phi):
            assert sp.expand(a - b) == 0
        for a, b in zip(back.holonomic, system.holonomic):
            assert sp.expand(a - b) == 0
        assert dict(back.parameter_values) == dict(system.parameter_values)


def test_from_mechanics_names_and_default_parameters():
    q1, q2 = me.dynamicsymbols("q1 q2")
    k, m = sp.symbols("k m", positive=True)
    L = m * (q1.diff(t)**2 + q2.diff(t)**2) / 2 - k * q1**2 / 2
    system = from_mechanics(L, [q1, q2], nonhol_coneqs=[sp.Eq(q2.diff(t), q1 * q1.diff(t))],
                            name="test")
    assert [s.name for s in system.state] == ["q1", "q2", "q1_dot", "q2_dot"]
    assert [p.name for p in system.parameters] == ["k", "m"]
    assert not system.parameter_values
    assert sp.expand(system.constraints[0] - (S("q2_dot") - S("q1") * S("q1_dot"))) == 0
    assert system.name == "test"


def test_from_lagranges_method_reads_both_constraint_kinds():
    x1, x2, y1, y2 = me.dynamicsymbols("x1 x2 y1 y2")
    g, l = sp.symbols("g l")
    X, Y = x2 - x1, y2 - y1
    L = sum(f.diff(t)**2 for f in (x1, x2, y1, y2)) / 2 - g * (y1 + y2)
    lm = me.LagrangesMethod(
        L, [x1, x2, y1, y2], hol_coneqs=[(X**2 + Y**2 - l**2) / 2],
        nonhol_coneqs=[X * (y2.diff(t) + y1.diff(t)) - (x2.diff(t) + x1.diff(t)) * Y])
    system = from_lagranges_method(lm, parameters={"g": 9.81, "l": 1.0})
    rod = two_particle_rod()
    assert len(system.holonomic) == 1 and len(system.constraints) == 1
    for a, b in zip(system.phi + system.holonomic, rod.phi + rod.holonomic):
        assert sp.expand(a - b) == 0


@pytest.mark.parametrize("lagrangian, fragment", [
    (lambda x: x.diff(t)**2 / 2 + x.diff(t, 2), "first derivatives"),
    (lambda x: x.diff(t)**2 / 2 + me.dynamicsymbols("u")**2, "not one of the coordinates"),
    (lambda x: x.diff(t)**2 / 2 + S("x_dot"), "name of a coordinate or velocity"),
])
def test_from_mechanics_rejects_what_it_cannot_express(lagrangian, fragment):
    x = me.dynamicsymbols("x")
    with pytest.raises(InputError, match=fragment):
        from_mechanics(lagrangian(x), [x])


def test_from_mechanics_names_the_offending_term():
    x, y = me.dynamicsymbols("x y")
    with pytest.raises(ValidationError) as info:
        from_mechanics(x.diff(t)**2 / 2 + y.diff(t)**2 / 2, [x, y],
                       nonhol_coneqs=[x.diff(t) - x.diff(t, 2)])
    assert "nonhol_coneqs[0]" in str(info.value) and "first derivatives" in str(info.value)


def test_from_mechanics_reads_an_explicit_time_as_the_time():
    # L = (x'² + y'²)/2 − cos(t) x with y' = t x': t is System.time (the last parameter);
    # the drift of φ = y' − t x' is ∂φ/∂t = −x' (worked out by hand)
    x, y = me.dynamicsymbols("x y")
    system = from_mechanics((x.diff(t)**2 + y.diff(t)**2) / 2 - sp.cos(t) * x, [x, y],
                            nonhol_coneqs=[y.diff(t) - t * x.diff(t)])
    assert system.time == sp.Symbol("t") and system.parameters == (sp.Symbol("t"),)
    assert system.lagrangian_depends_on_time and system.time_dependent == (True,)
    assert lagrangian_geometry(system).drift[0] == -S("x_dot")


def test_from_mechanics_rejects_non_coordinates():
    x = me.dynamicsymbols("x")
    with pytest.raises(InputError, match="not a dynamicsymbol"):
        from_mechanics(x.diff(t)**2, [x.diff(t)])


def test_multipliers_are_minus_those_of_lagranges_method():
    """The multipliers sympy's LagrangesMethod solves in ``rhs()`` (from
    ``mass_matrix_full``, which appends lam_coeffs.T = -mu^T while ``eom`` has
    -lam_coeffs^T lam: sympy issue 30215) are minus nhham's, whose W a + mu^T lambda = F
    (DESIGN.md) makes -mu^T lambda the generalized constraint force. On the vertical
    rolling disk through from_lagranges_method: the accelerations agree,
    lambda_nhham = -lambda_rhs, and m x'' = -lambda_1 (the force along x) by hand."""
    from nhham.numerics.codegen import numeric_model

    x, y, th, ph = me.dynamicsymbols("x y theta phi")
    t = me.dynamicsymbols._t
    m, I, J, R = sp.symbols("m I J R")
    L = (m * (x.diff(t) ** 2 + y.diff(t) ** 2) + I * th.diff(t) ** 2 + J * ph.diff(t) ** 2) / 2
    lm = me.LagrangesMethod(L, [x, y, th, ph], nonhol_coneqs=[
        x.diff(t) - R * sp.cos(th) * ph.diff(t), y.diff(t) - R * sp.sin(th) * ph.diff(t)])
    lm.form_lagranges_equations()
    values = {m: 2.0, I: 0.3, J: 0.5, R: 0.4}
    system = from_lagranges_method(lm, parameters={k.name: v for k, v in values.items()})
    q0, thd, phd = [0.1, -0.2, 0.7, 0.3], 1.3, 2.1
    v0 = [0.4 * math.cos(0.7) * phd, 0.4 * math.sin(0.7) * phd, thd, phd]
    subs = {**dict(zip([c.diff(t) for c in (x, y, th, ph)], v0)),
            **dict(zip((x, y, th, ph), q0))}
    reference = np.array(lm.rhs().xreplace(subs).xreplace(values), dtype=float).ravel()
    model = numeric_model(system, backend="numpy")
    state = np.array(q0 + v0)
    lam = model.multipliers(state)
    assert np.allclose(model.rhs(0.0, state)[4:], reference[4:8], atol=1e-12)
    assert np.allclose(lam, -reference[8:], atol=1e-12)
    assert np.isclose(values[m] * reference[4], -lam[0], atol=1e-12)


def test_from_mechanics_brings_nonlinear_velocity_constraints():
    # x'^2 + y'^2 = c^2 (the isokinetic particle) in q'(t) and in a speed u = x'.
    x, y = me.dynamicsymbols("x y")
    u = me.dynamicsymbols("u")
    c = sp.Symbol("c")
    L = (x.diff(t)**2 + y.diff(t)**2) / 2
    system = from_mechanics(L, [x, y], nonhol_coneqs=[x.diff(t)**2 + y.diff(t)**2 - c**2])
    xd, yd = S("x_dot"), S("y_dot")
    assert system.constraint_kinds == ("nonlinear (Chetaev)",)
    assert system.mu == sp.Matrix([[2 * xd, 2 * yd]])
    kane = from_mechanics(L, [x, y], u=[u], kd_eqs=[u - x.diff(t)],
                          velocity_constraints=[u**2 + y.diff(t)**2 - c**2])
    assert sp.expand(kane.constraints[0] - (xd**2 + yd**2 - S("c")**2)) == 0
