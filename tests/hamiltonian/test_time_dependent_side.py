"""T*Q with a time-dependent constraint: Ψ(q, p, t) = φ ∘ Leg⁻¹ and ∂Ψ/∂t in the
consistency condition; the cross-check through Leg agrees at a generic instant."""

import pytest
import sympy as sp

from nhham import System, cross_check, hamiltonian_side

x, y, px, py, t, m, W = sp.symbols("x y p_x p_y t m Omega")


def bead():
    return System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2",
                  holonomic=["y*cos(Omega*t) - x*sin(Omega*t)"],
                  parameters={"m": 1.0, "Omega": 2.0})


def test_the_consistency_condition_carries_the_time_derivative_of_psi():
    # Ψ = (−sin Ωt p_x + cos Ωt p_y)/m − Ω(x cos Ωt + y sin Ωt); {Ψ, H} = −Ω(cos p_x +
    # sin p_y)/m (H = |p|²/2m) and ∂Ψ/∂t = −Ω(cos p_x + sin p_y)/m + Ω²(x sin − y cos)
    side = hamiltonian_side(bead())
    c, s = sp.cos(W * t), sp.sin(W * t)
    expected = -2 * W * (c * px + s * py) / m + W**2 * (x * s - y * c)
    assert sp.simplify(side.constraint_derivatives[0] - expected) == 0


def test_the_cross_check_agrees_for_a_moving_constraint():
    report = cross_check(bead())
    assert report.agree


def damped_particle():
    """L = e^{γt}(|v|²/2 − z) (Caldirola–Kanai in gravity) with z' = y x'."""
    return System(["x", "y", "z"], "exp(g*t)*((x_dot**2 + y_dot**2 + z_dot**2)/2 - z)",
                  constraints=["z_dot - y*x_dot"], parameters={"g": 0.3})


def test_the_legendre_map_of_a_lagrangian_in_t_moves_at_its_hand_rate():
    """p = e^{γt} v, so ∂Leg/∂t at fixed (q, v) = (0, γ e^{γt} v)."""
    leg = hamiltonian_side(damped_particle()).legendre
    g = next(p for p in leg.system.parameters if p.name == "g")
    time = leg.system.time
    expected = sp.zeros(3, 1).col_join(g * sp.exp(g * time) * sp.Matrix(leg.velocities))
    assert sp.simplify(leg.time_derivative - expected) == sp.zeros(6, 1)


@pytest.mark.parametrize("method", ["exact", "sampled"])
def test_the_cross_check_of_a_lagrangian_in_t_agrees_through_the_moving_legendre_map(method):
    """H = e^{−γt}|p|²/2 + e^{γt} z; X_H(t) o Leg_t = Leg_* ξ_L + ∂Leg/∂t (Leg moves with t):
    every check agrees, by the exact route and at sampled points (without the map's rate,
    the field check fails by (0, γ p))."""
    report = cross_check(damped_particle(), method=method)
    assert report.agree and {c.name for c in report.checks} >= {"field", "multipliers"}


def wall(a=0.7):
    """A particle pushed by a wall moving as x = a t²/2 (holonomic, linear in x): the true
    motion has x'' = a, the wall's push m a, y free in gravity."""
    return System(["x", "y"], "m*(x_dot**2 + y_dot**2)/2 - m*g*y",
                  holonomic=["x - a*t**2/2"], parameters={"m": 2.0, "g": 9.81, "a": a})


@pytest.mark.parametrize("system", [bead(), wall()], ids=["bead", "wall"])
@pytest.mark.parametrize("method", ["auto", "sampled"])
def test_the_dirac_flow_of_a_moving_holonomic_constraint_is_the_true_motion(system, method):
    """Second-class constraints χ(q, p, t) stay satisfied along X_D = {z, H}_D − {z, χ_a}
    C^ab ∂χ_b/∂t only with the ∂χ/∂t term, and a holonomic constraint's Dirac flow is then
    the true motion (Dirac 1950). The wall by hand: χ = (x − a t²/2, p_x/m − a t),
    {χ, H} = (p_x/m, 0), ∂χ/∂t = (−a t, −a): the correction cancels q-motion's error on
    M_f and p_x' = m a; without ∂χ/∂t the flow left p_x constant and the report said the
    flows differ."""
    from nhham import dirac_vs_projected

    report = dirac_vs_projected(system, method=method)
    assert report.equal, report.components


def test_the_dirac_flow_at_exact_points_carries_the_time_derivative():
    """The route at exact points of M_f (the wall's M_f is flat: points over Q) decides
    X_D − X = 0 with ∂χ/∂t in (without it, the points proved X_D − X ≠ 0)."""
    from nhham.hamiltonian.classification import classify_constraints
    from nhham.hamiltonian.dirac import _dirac_vs_projected_at_points
    from nhham.lagrangian.engine import Policy

    side = hamiltonian_side(wall())
    classes = classify_constraints(side, policy=Policy(combination_size=0))
    report = _dirac_vs_projected_at_points(side, classes, Policy())
    assert report is not None and report.equal
