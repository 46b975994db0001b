"""System description: construction, affine extraction, validation messages."""

import dataclasses

import pytest
import sympy as sp

import nhham
from nhham.errors import (
    NonAffineConstraintError,
    RedundantConstraintError,
    SingularLagrangianError,
    ValidationError,
)

x, y, z, th, ph = sp.symbols("x y z theta phi")
xd, yd, zd, thd, phd = sp.symbols("x_dot y_dot z_dot theta_dot phi_dot")
m, R, k = sp.symbols("m R k")
L_free = m * (xd**2 + yd**2 + zd**2) / 2


def make(**kw):
    args = dict(coordinates=["x", "y", "z"], lagrangian=L_free, parameters={"m": 1.0})
    args.update(kw)
    return nhham.System(**args)


def test_velocity_symbols_and_affine_parts():
    s = make(constraints=[zd - y * xd + 3 * x], parameters={"m": 1.0})
    assert s.velocities == (xd, yd, zd)
    assert s.mu == sp.Matrix([[-y, 0, 1]])
    assert s.h == sp.Matrix([3 * x])
    assert s.n == 3 and s.m == 1
    assert not s.is_linear


def test_coordinates_accept_symbols_with_assumptions():
    xr = sp.Symbol("x", real=True)
    s = nhham.System([xr, "y"], (sp.Symbol("x_dot", real=True) ** 2 + yd**2) / 2)
    assert s.coordinates == (x, y)
    assert s.lagrangian == (xd**2 + yd**2) / 2


def test_holonomic_constraint_complete_lift_comes_first():
    s = make(constraints=[zd], holonomic=[x**2 + y**2 - 1])
    assert s.phi[0] == 2 * x * xd + 2 * y * yd
    assert s.phi[1] == zd
    assert s.constraint_labels == ("holonomic[0]", "constraints[0]")


def test_system_is_frozen():
    s = make()
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.lagrangian = 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.anything = 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        del s.name


def test_system_is_a_dataclass_of_its_normalised_fields():
    s = make(constraints=[zd, "2*z_dot"], drop_redundant=True, name="n")
    names = [f.name for f in dataclasses.fields(nhham.System)]
    assert names == ["name", "coordinates", "velocities", "parameters", "parameter_values",
                     "lagrangian", "holonomic", "constraints", "dropped", "constraint_labels",
                     "forces", "dissipation", "inputs", "speeds"]
    assert s.constraints == (zd,) and s.constraint_labels == ("constraints[0]",)
    assert [d.label for d in s.dropped] == ["constraints[1]"]
    # identity equality and hash: a system is a key of caches
    assert s == s and s != make(constraints=[zd], name="n") and hash(s) == object.__hash__(s)
    # the constructor takes raw inputs, not fields: replace is refused, never silently wrong
    with pytest.raises(ValueError, match="init=False"):
        dataclasses.replace(s, name="other")


def test_nonlinear_constraints_are_accepted_with_their_kind_and_mu():
    # Chetaev's rule: mu = d phi/d v, by hand for phi = x'y' + z and phi = sin(x') - y'.
    s = make(constraints=[zd - y * xd, xd * yd + z])
    assert s.constraint_kinds == ("affine", "nonlinear (Chetaev)") and not s.is_affine
    assert s.mu == sp.Matrix([[-y, 0, 1], [yd, xd, 0]])
    t = make(constraints=[sp.sin(xd) - yd])
    assert t.mu == sp.Matrix([[sp.cos(xd), -1, 0]]) and t.constraint_kinds == ("nonlinear (Chetaev)",)
    assert make(constraints=[zd - y * xd]).is_affine


@pytest.mark.parametrize("phi, grad", [
    ((xd - yd)**2, "(2*x_dot - 2*y_dot, -2*x_dot + 2*y_dot, 0)"),   # M_1: x' = y'
    (xd**2 + yd**2, "(2*x_dot, 2*y_dot, 0)"),                         # M_1: x' = y' = 0
    ((xd**2 + yd**2 - 1)**2, None),                                   # M_1: the unit circle
])
def test_degenerate_chetaev_reaction_is_refused_naming_it(phi, grad):
    # d phi/d v vanishes at every point of M_1: Chetaev's rule gives no reaction.
    with pytest.raises(NonAffineConstraintError) as err:
        make(constraints=[zd - y * xd, phi])
    msg = str(err.value)
    assert msg.startswith("constraints[1]: d phi/d v = ") and "vanishes on M_1" in msg
    assert err.value.key == "constraints[1]" and "constraints[0]" not in msg
    if grad:
        assert grad in msg


def test_reaction_vanishing_at_points_of_m1_only_is_accepted():
    # d phi/d v = (2x', 2y', -2z') vanishes at v = 0 only, a point of M_1 (the cone), and
    # x'y' at x' = y' = 0: singular points of C, not a refusal.
    assert make(constraints=[xd**2 + yd**2 - zd**2]).m == 1
    assert make(constraints=[xd * yd]).m == 1


def test_singular_hessian_is_accepted_and_refused_where_w_inverse_is_needed():
    s = nhham.System(["x", "y"], (xd + yd) ** 2 / 2)
    assert s.regular_lagrangian is False
    for build in (nhham.lagrangian_geometry, nhham.legendre_map):
        with pytest.raises(SingularLagrangianError) as err:
            build(s)
        msg = str(err.value)
        assert "rank 1 of 2" in msg and "null direction [-1, 1]" in msg and "lagrangian" in msg
        assert "needs W invertible" in msg and "classify" in msg
    # a 2-D kernel: both directions, by hand (d2L/dv dv = diag(1, 0, 0))
    with pytest.raises(SingularLagrangianError,
                       match=r"rank 1 of 3; null directions \[0, 1, 0\], \[0, 0, 1\]"):
        nhham.System(["x", "y", "z"], "x_dot**2/2 + y*z").require_regular_lagrangian("it")
    assert nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2").regular_lagrangian


def test_singular_hessian_depending_on_q():
    # W = [[y^2, x y], [x y, x^2]] has rank 1 everywhere.
    with pytest.raises(SingularLagrangianError, match="rank 1 of 2"):
        nhham.System(["x", "y"], (y * xd + x * yd) ** 2 / 2).require_regular_lagrangian("it")


def test_m_not_less_than_n():
    with pytest.raises(ValidationError, match="m = 3.*n = 3"):
        make(constraints=[xd, yd, zd - x])


def test_unknown_symbol_named():
    with pytest.raises(ValidationError, match=r"lagrangian: unknown symbol\(s\) k"):
        make(lagrangian=L_free + k * x)


def test_holonomic_with_velocity_named():
    with pytest.raises(ValidationError, match=r"holonomic\[0\].*x_dot"):
        make(holonomic=[x * xd])


def test_all_problems_reported_at_once():
    with pytest.raises(ValidationError) as err:
        make(lagrangian=L_free + k, holonomic=[x * xd])
    assert len(err.value.problems) == 2


def test_duplicate_coordinates_and_clashing_parameters():
    with pytest.raises(ValidationError) as err:
        nhham.System(["x", "x"], xd**2 / 2, parameters={"x_dot": 1.0})
    text = str(err.value)
    assert "duplicate names x" in text and "x_dot" in text


def test_parameter_values_must_be_finite_numbers():
    with pytest.raises(ValidationError, match=r"parameters.m: value must be finite"):
        make(parameters={"m": float("nan")})
    with pytest.raises(ValidationError, match=r"parameters.m: value must be a real number"):
        make(parameters={"m": "heavy"})


def _disk(third, drop=False):
    I1, I2 = sp.symbols("I1 I2")
    L = m * (xd**2 + yd**2) / 2 + I1 * thd**2 / 2 + I2 * phd**2 / 2
    cons = [xd - R * sp.cos(th) * phd, yd - R * sp.sin(th) * phd, third]
    return nhham.System(["x", "y", "theta", "phi"], L, cons,
                        parameters=["m", "I1", "I2", "R"], drop_redundant=drop)


def test_redundant_constraint_reports_combination():
    third = 2 * xd + sp.cos(th) * yd - R * (2 * sp.cos(th) + sp.cos(th) * sp.sin(th)) * phd
    with pytest.raises(RedundantConstraintError) as err:
        _disk(third)
    msg = str(err.value)
    assert "constraints[2]" in msg and "(2)*constraints[0]" in msg
    assert "(cos(theta))*constraints[1]" in msg and "drop_redundant=True" in msg


def test_redundant_constraint_dropped_on_request():
    third = 2 * xd + sp.cos(th) * yd - R * (2 * sp.cos(th) + sp.cos(th) * sp.sin(th)) * phd
    s = _disk(third, drop=True)
    assert s.m == 2
    assert [d.label for d in s.dropped] == ["constraints[2]"]
    combo = s.dropped[0].combination
    assert combo["constraints[0]"] == 2 and sp.simplify(combo["constraints[1]"] - sp.cos(th)) == 0


def test_dependent_one_forms_with_different_h_imply_position_constraint():
    with pytest.raises(RedundantConstraintError, match="position constraint"):
        make(constraints=[xd, 2 * xd + y])


def test_numeric_parameters_missing_value():
    s = make(parameters=["m"])
    with pytest.raises(nhham.MissingParameterValueError, match="no numeric value for m"):
        s.numeric_parameters()


def test_sample_points_outside_the_domain_of_L_are_left_out():
    """W = diag(sqrt(x), 1): at the random points with x < 0 its entry is not real (its
    real part, 0, was taken: a singular W there); those points are left out, and W is
    regular at the others."""
    system = nhham.System(["x", "y"], "sqrt(x)*x_dot**2/2 + y_dot**2/2", ["y_dot - x_dot"])
    assert system.n == 2 and system.m == 1


@pytest.mark.parametrize("lagrangian, constraint, key, part", [
    # sqrt(-1 - x^2) is real nowhere: W was "singular" (its real part 0), misleadingly
    ("sqrt(-1 - x**2)*x_dot**2/2 + y_dot**2/2", "y_dot", "lagrangian", "sqrt(-x**2 - 1)"),
    # log(-1 - y^2) = log(1 + y^2) + i pi: its real part was used, silently
    ("(x_dot**2 + y_dot**2)/2", "x_dot + log(-1 - y**2)*y_dot", "constraints[0]",
     "log(-y**2 - 1)"),
])
def test_an_expression_defined_nowhere_on_the_state_is_refused_by_name(lagrangian, constraint,
                                                                      key, part):
    with pytest.raises(ValidationError) as info:
        nhham.System(["x", "y"], lagrangian, [constraint])
    assert str(info.value).startswith(f"{key}: ") and part in str(info.value)
    assert "is not finite at any of 16 random points of the state" in str(info.value)
    assert info.value.key == key
