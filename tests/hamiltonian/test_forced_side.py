"""Forces on T*Q: X_H + F^V with F^V = Q_A(q, Leg⁻¹(q, p)) ∂/∂p_A is the image of the
Lagrangian side's ξ_L + F^v through Leg (DESIGN.md §2), at random forces (hypothesis)."""

import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import nhham
from nhham.hamiltonian.crosscheck import cross_check
from nhham.hamiltonian.side import hamiltonian_side
from nhham.lagrangian.geometry import lagrangian_geometry

x, y, z, xd, yd, zd = sp.symbols("x y z x_dot y_dot z_dot")
px, py, pz = sp.symbols("p_x p_y p_z")
MONOMIALS = [sp.S.One, x, y, xd, yd, zd, x * yd, y**2, sp.sin(z), xd * zd]

coefficients = st.lists(st.integers(-3, 3), min_size=len(MONOMIALS), max_size=len(MONOMIALS))


def force(coeffs):
    return sum((c * mono for c, mono in zip(coeffs, MONOMIALS)), sp.S.Zero)


def particle(forces, mass=2):
    """The nonholonomic particle z' = y x' with mass ``mass`` (Leg: p = mass v)."""
    return nhham.System(["x", "y", "z"], mass * (xd**2 + yd**2 + zd**2) / 2,
                        constraints=[zd - y * xd], forces=forces)


@settings(max_examples=12, deadline=None)
@given(coefficients, coefficients)
def test_the_forced_fields_agree_through_leg(cx, cz):
    """Leg_*(P(ξ_L + F^v)) = X ∘ Leg, with Leg(q, v) = (q, 2v) done by hand here."""
    system = particle({"x": force(cx), "z": force(cz)})
    lag = lagrangian_geometry(system).projected_field
    ham = hamiltonian_side(system).projected_field
    to_p = {px: 2 * xd, py: 2 * yd, pz: 2 * zd}
    pushed = list(lag[:3]) + [2 * a for a in lag[3:]]      # d(2v)/dt = 2 a
    for a, b in zip(pushed, ham):
        assert sp.simplify(a - sp.sympify(b).xreplace(to_p)) == 0


@settings(max_examples=6, deadline=None)
@given(coefficients)
def test_the_cross_check_agrees_with_forces_on_both_of_its_routes(cx):
    system = particle({"x": force(cx), "y": "x_dot - y"})
    for method in ("exact", "sampled"):
        report = cross_check(system, method=method)
        assert report.agree, report.describe()


def test_a_hamiltonian_side_without_the_force_is_caught():
    """The check is not vacuous: the unforced T*Q field differs from the forced TQ one."""
    forced = lagrangian_geometry(particle({"x": "1"})).projected_field
    free = hamiltonian_side(particle({})).projected_field
    to_p = {px: 2 * xd, py: 2 * yd, pz: 2 * zd}
    assert sp.simplify(2 * forced[3] - free[3].xreplace(to_p)) != 0
    # and the hand value of the force's share: a_x gains 1 / (2 (1 + y^2))
    unforced = lagrangian_geometry(particle({})).projected_field
    assert sp.simplify(forced[3] - unforced[3] - 1 / (2 * (1 + y**2))) == 0
