"""Simulations of time-dependent L and constraints against closed forms worked out by hand
(the examples' headers): the generated code reads t from its time slot, the states are
projected onto M_1(t), and dE/dt = −∂L/∂t + λ·h + Q·v is the energy balance reported."""

import math
from pathlib import Path

import numpy as np
import pytest

from nhham import System, simulate
from nhham.errors import InputError
from nhham.numerics.codegen import numeric_model
from nhham.numerics.linearization import linearize
from nhham.system.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def ball():
    return load_scene(EXAMPLES / "ball_on_turntable_spun_up.toml")


@pytest.fixture(scope="module")
def bead():
    return load_scene(EXAMPLES / "bead_on_turning_wire.toml")


def test_ball_on_a_turntable_spun_up_reaches_the_closed_form(ball):
    # ζ'' = i k d/dt(Ω ζ), Ω = t, k = 2/7, ζ(0) = 1, ζ'(0) = i (solved by hand with an
    # independent high-precision ODE solve of the complex equation)
    result = simulate(ball.system, **ball.simulate_options())
    assert result.success
    x, y = result.y[0, -1], result.y[1, -1]
    assert abs(x - -1.8357633850033281069) < 1e-10
    assert abs(y - 2.7697346008192437249) < 1e-10
    assert result.constraint_residual_max < 1e-10   # on M_1(t), read at each state's time
    assert result.energy_balance_residual < 1e-8    # dE/dt = λ·h: the motor works


def test_bead_on_a_turning_wire_moves_as_r0_cosh_omega_t_pushed_by_the_coriolis_force(bead):
    result = simulate(bead.system, **bead.simulate_options())
    assert result.success
    t = result.t
    r = np.hypot(result.y[0], result.y[1])
    assert np.max(np.abs(r - np.cosh(t))) < 1e-10
    assert abs(result.y[0, -1] - math.cosh(2) * math.cos(2)) < 1e-10
    assert abs(result.y[1, -1] - math.cosh(2) * math.sin(2)) < 1e-10
    # the wire's push N = 2 m Ω r' = 2 sinh t along e_θ; the reaction −μᵀλ with
    # μ = (−sin t, cos t) gives λ = −N
    assert np.max(np.abs(result.multipliers[0] + 2 * np.sinh(t))) < 1e-9
    # E = m r'²/2 + m Ω² r²/2 grows by the motor's work ∫ N Ω r dt
    assert result.energy_balance_residual < 1e-9 and result.energy_drift > 1


def test_a_lagrangian_in_t_is_integrated_with_its_energy_balance():
    # Caldirola-Kanai, L = e^{γt}(x'² − x²)/2: x'' + γ x' + x = 0; from x = 1 at rest,
    # x = e^{−γt/2}(cos ωt + γ/(2ω) sin ωt) with ω² = 1 − γ²/4; dE_L/dt = −∂L/∂t.
    system = System(["x"], "exp(gamma*t)*(x_dot**2 - x**2)/2", parameters={"gamma": 0.5})
    result = simulate(system, (0.0, 4.0), {"x": 1.0, "x_dot": 0.0}, rtol=1e-12, atol=1e-12)
    w = math.sqrt(1 - 0.5**2 / 4)
    exact = math.exp(-1.0) * (math.cos(4 * w) + 0.25 / w * math.sin(4 * w))
    assert abs(result.y[0, -1] - exact) < 1e-10
    assert result.energy_balance_residual < 1e-9 < result.energy_drift


def test_the_mpmath_reference_takes_the_time(bead):
    import mpmath

    from nhham.numerics.reference import reference_solution

    model = numeric_model(bead.system)
    ref = reference_solution(model, model.state(bead.initial), (0.0, 2.0), digits=25,
                             t_eval=[2.0])
    with mpmath.workdps(30):
        r = mpmath.cosh(2)
        assert abs(ref.y_mp[-1][0] - r * mpmath.cos(2)) < mpmath.mpf(10) ** -20
        assert abs(ref.y_mp[-1][1] - r * mpmath.sin(2)) < mpmath.mpf(10) ** -20


@pytest.mark.parametrize("method, order", [("rattle", 2), ("rattle4", 4)])
def test_rattle_takes_time_in_the_constraints_and_keeps_its_order(bead, method, order):
    """The bead on the wire turning at Omega = 1, by hand: r'' = r, so (x, y) =
    cosh t (cos t, sin t) from r = 1 at rest; each half kick and the midpoint constraint
    read at their own time, the error falls by 2^order when h halves and the wire's
    constraint holds at every grid point's own t."""
    exact = np.array([math.cosh(2) * math.cos(2), math.cosh(2) * math.sin(2)])
    errors = []
    for h in (0.02, 0.01):
        res = simulate(bead.system, **bead.simulate_options(method=method, step=h))
        assert res.success, res.message
        errors.append(np.max(np.abs(res.y[:2, -1] - exact)))
        x, y = res.y[0], res.y[1]
        assert np.max(np.abs(y * np.cos(res.t) - x * np.sin(res.t))) < 1e-12
    assert abs(math.log2(errors[0] / errors[1]) - order) < 0.2


@pytest.mark.filterwarnings("ignore:constraint residual")  # unprojected at h = 0.04: honest
@pytest.mark.parametrize("projection", [False, True])
def test_rk4_sets_each_stage_s_time_and_keeps_its_order(bead, projection):
    """The bead at t = 2, (x, y) = cosh 2 (cos 2, sin 2) by hand: the error falls by 2⁴
    when the step halves (a stage read at the wrong time would leave an O(h) error),
    and with projection the states lie on M_1(t) at their own t."""
    exact = np.array([math.cosh(2) * math.cos(2), math.cosh(2) * math.sin(2)])
    errors = []
    for h in (0.04, 0.02):
        result = simulate(bead.system, **bead.simulate_options(method="rk4", step=h,
                                                               projection=projection))
        assert result.success
        errors.append(float(np.hypot(*(result.y[:2, -1] - exact))))
    assert errors[1] < 1e-6 and 12 < errors[0] / errors[1] < 20
    if projection:
        assert result.constraint_residual_max < 1e-12
    # the energy balance dE/dt = λ·h (the motor's work) to the method's accuracy
    assert result.energy_balance_residual < 1e-6 < result.energy_drift


def test_linearize_refuses_a_time_dependent_constraint_naming_it(bead):
    model = numeric_model(bead.system)
    with pytest.raises(InputError, match="holonomic.0.: depends on time t") as e:
        linearize(model, model.state(bead.initial))
    assert e.value.key == "holonomic[0]"


def test_a_study_reads_the_ends_of_a_run_at_their_times(bead):
    # the residual at the end is on M_1(t_end), and E(t_end) − E(0) is the motor's work:
    # E = m (r'² + Ω² r²)/2 with r = cosh t, E(0) = 1/2, E(2) = (sinh² 2 + cosh² 2)/2
    from nhham.study.ensemble import _ends

    model = numeric_model(bead.system)
    y0 = model.state(bead.initial)
    result = simulate(model, (0.0, 2.0), y0, rtol=1e-12, atol=1e-12)
    E0, E1, residual = _ends(model, None, y0[None], result.y[:, -1][None], np.array([2.0]))
    assert residual[0] < 1e-10
    assert abs(E0[0] - 0.5) < 1e-12
    assert abs(E1[0] - (math.sinh(2) ** 2 + math.cosh(2) ** 2) / 2) < 1e-9
