"""Chaplygin's multiplier (nhham.hamiltonian.hamiltonization) against hand derivations.

On T*S: Omega_nh = dr ^ dp - 1/2 J B dr ^ dr; a factor f(r) with d(f Omega_nh) = 0 exists
exactly when theta ^ Omega_nh = -d Omega_nh has a closed solution theta(r), f = exp of its
potential.
"""

import sympy as sp

from nhham import System, models
from nhham.hamiltonian.hamiltonization import hamiltonize
from nhham.lagrangian.chaplygin import chaplygin_reduction

L3 = "(x_dot**2 + y_dot**2 + z_dot**2)/2"


def symbols_of(expr):
    return {str(s): s for s in sp.sympify(expr).free_symbols}


def test_the_nonholonomic_particle_has_the_factor_of_the_literature():
    """z' = y x': J = y p_x/(1 + y^2), Omega_nh = dx^dp_x + dy^dp_y - J dx^dy,
    d Omega = -dJ/dp_x dp_x^dx^dy; theta = -y/(1 + y^2) dy, f = (1 + y^2)^(-1/2)
    (Garcia-Naranjo & Vermeeren's N(y)); {p_x, p_y} = J, so the Jacobiator of
    (x, p_x, p_y) is {{x, p_x}, p_y} + {{p_x, p_y}, x} + {{p_y, x}, p_x} = {J, x} =
    -dJ/dp_x = -y/(1 + y^2) before, 0 after; div(f X) = 0 (k = 2)."""
    found = hamiltonize(chaplygin_reduction(System(["x", "y", "z"], L3, ["z_dot - y*x_dot"])))
    y = symbols_of(found.conformal_factor)["y"]
    assert found.hamiltonizable
    assert sp.simplify(found.conformal_factor - 1 / sp.sqrt(1 + y**2)) == 0
    assert sp.simplify(found.theta[1] + y / (1 + y**2)) == 0 and found.theta[0] == 0
    (triple, value), = found.jacobiator_before
    assert triple == ("x", "p_x", "p_y") and sp.simplify(value + y / (1 + y**2)) == 0
    assert found.jacobiator_after == ()
    assert found.divergence == 0
    assert sp.simplify(found.invariant_measure_density - found.conformal_factor) == 0


def test_the_sleigh_has_no_factor_theta_is_not_closed():
    """Shape (x, theta), symmetry y. theta ^ Omega = -d Omega solves to
    a m/((I + m a^2) cos th) dx - I tan th/(I + m a^2) d th, whose d is
    -a m sin th/((I + m a^2) cos^2 th) dx^d th != 0 (a != 0): no factor, as the sleigh has
    no invariant measure. (A dth part -tan th is this one at a = 0 only: with a != 0 it leaves
    the residual a^2 m tan th/(I + m a^2) in the equations; the reduced field of this
    Omega_nh is P(xi_L)'s, checked in tests/lagrangian/test_chaplygin.py.)"""
    found = hamiltonize(chaplygin_reduction(models.chaplygin_sleigh(), symmetry=["y"]))
    s = symbols_of(found.two_form)
    th, a, m, I = s["theta"], s["a"], s["m"], s["I"]
    assert not found.hamiltonizable and found.conformal_factor is None
    assert sp.simplify(found.theta[0] - a * m / ((I + m * a**2) * sp.cos(th))) == 0
    assert sp.simplify(found.theta[1] + I * sp.tan(th) / (I + m * a**2)) == 0
    assert found.obstruction.startswith("theta is not closed")
    assert found.jacobiator_before  # the reduced bracket is not Poisson


def test_a_twisted_particle_has_no_factor():
    """z' = x y x' + x y': the one-form theta solving the equations is not closed."""
    found = hamiltonize(chaplygin_reduction(System(["x", "y", "z"], L3,
                                                   ["z_dot - x*y*x_dot - x*y_dot"])))
    assert not found.hamiltonizable and found.obstruction.startswith("theta is not closed")


def test_an_extra_free_coordinate_leaves_the_equations_without_solution():
    """The particle with a free w (k = 3 shape coordinates): d Omega = -dJ ^ dx ^ dy has a
    dp_x ^ dx ^ dy part that theta ^ Omega cannot match together with the zero
    components involving w (on 6 dimensions wedging with Omega is injective)."""
    system = System(["x", "y", "z", "w"], L3 + " + w_dot**2/2", ["z_dot - y*x_dot"])
    found = hamiltonize(chaplygin_reduction(system, symmetry=["z"]))
    assert not found.hamiltonizable and found.theta is None
    assert "no solution" in found.obstruction


def test_a_reduced_lagrangian_that_is_not_quadratic_is_refused():
    """L_c with x'^4: p = dL_c/dx' cannot be inverted by one linear solve; refused, not a
    wrong H."""
    import pytest

    from nhham.errors import InputError

    system = System(["x", "y", "z"], L3 + " + x_dot**4", ["z_dot - y*x_dot"])
    with pytest.raises(InputError, match="not quadratic in the shape velocities"):
        hamiltonize(chaplygin_reduction(system))


def test_the_large_surface_route_gives_the_closed_forms_values(monkeypatch):
    """The k = 2 route for a large Omega_nh (theta from g W^-1, the Jacobiators read off
    theta, no Legendre inverse cancelled), forced on the particle: f = (1 + y^2)^(-1/2) and
    the Jacobiator (x, p_x, p_y) = -y/(1 + y^2) by hand; the sleigh (a != 0): not closed."""
    import nhham.hamiltonian.hamiltonization as H
    from nhham import System
    from nhham.lagrangian.chaplygin import chaplygin_reduction

    monkeypatch.setattr(H, "CLOSED_FORM_OPS", -1)
    particle = System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2", ["z_dot - y*x_dot"])
    found = H.hamiltonize(chaplygin_reduction(particle))
    y = found.reduction.shape[1]
    assert found.hamiltonizable and "theorem" in found.decision.detail
    assert sp.simplify(found.conformal_factor ** 2 * (1 + y ** 2)) == 1
    ((triple, value),) = found.jacobiator_before
    assert triple == ("x", "p_x", "p_y") and sp.simplify(value + y / (1 + y ** 2)) == 0
    found = H.hamiltonize(chaplygin_reduction(models.chaplygin_sleigh(), symmetry=["y"]))
    assert not found.hamiltonizable and found.obstruction.startswith("theta is not closed")
