"""Linearisation about steady motions against independent values.

- The Whipple bicycle (examples/whipple_bicycle.toml, built with
  sympy.physics.mechanics): eigenvalues of the upright steady motion for
  v = 0..10 m/s against the benchmark's own linearised equations
  M q'' + v C1 q' + (g K0 + v^2 K2) q = 0 with the matrices printed in
  Meijaard, Papadopoulos, Ruina & Schwab, Proc. R. Soc. A 463 (2007) 1955,
  eq. (A 23) ff. (the reference is computed here from those published
  numbers, not from nhham); weave and capsize speeds as published there
  (v_w = 4.292 382 5, v_c = 6.024 262 0) to 1e-6.
- Small systems against hand-derived closed forms: the Chaplygin sleigh
  (w' = -m a u w / (I + m a^2)), the Cartesian pendulum (+-i sqrt(g/l)); the
  exact path against the complex-step path.
- Refusals: states off M_1 or not steady, with the residual in the message.
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from nhham import InconsistentInitialDataError
from nhham.numerics.codegen import numeric_model
from nhham.numerics.chart import BATCH_STATES
from nhham.numerics.codegen.build import complex_kernels
from nhham.numerics.linearization import BUILD_COMPLEX_FROM, linearize, linearize_many
from nhham.numerics.steady_sweep import sweep_steady
from nhham.system.models import chaplygin_sleigh, pendulum_cartesian

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# Meijaard et al. (2007), the benchmark's coefficient matrices (lean phi, steer delta).
M0 = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
C1 = np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
K0 = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
K2 = np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]])
G = 9.81
V_WEAVE, V_CAPSIZE = 4.2923825, 6.0242620   # the paper's values (section 6)


def benchmark_eigenvalues(v):
    Minv = np.linalg.inv(M0)
    A = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-Minv @ (G * K0 + v ** 2 * K2), -Minv @ (v * C1)]])
    return np.linalg.eigvals(A)


def matched(a, b):
    """max distance between two eigenvalue multisets (greedy nearest matching)."""
    b = list(b)
    worst = 0.0
    for z in a:
        j = int(np.argmin([abs(z - w) for w in b]))
        worst = max(worst, abs(z - b.pop(j)))
    return worst


def test_bicycle_eigenvalues_match_the_benchmark(bicycle):
    scene, model = bicycle
    for v in range(11):
        m = model.with_parameters(v=float(v))
        lin = linearize(m, scene.steady.values(m.parameters))
        assert lin.coordinates == ("phi", "delta", "phi_dot", "delta_dot")
        assert set(lin.neutral) >= {"x", "y", "psi", "thetaR", "thetaF"}
        ref = benchmark_eigenvalues(v)
        assert matched(lin.eigenvalues, ref) < 1e-8, (v, lin.eigenvalues, ref)
        assert lin.method == "complex-step"
    assert linearize(model.with_parameters(v=5.0),
                     scene.steady.values({**model.parameters, "v": 5.0})).stable is True


def test_many_speeds_in_one_batch_are_the_single_linearisations(bicycle):
    """linearize_many over more speeds than one batch holds: the benchmark's eigenvalues
    at each (Meijaard et al. 2007), and the single linearize's to rounding."""
    scene, model = bicycle
    speeds = np.linspace(0.0, 10.0, BATCH_STATES + 3)
    models = [model.with_parameters(v=float(v)) for v in speeds]
    states = [scene.steady.values(m.parameters) for m in models]
    first = linearize(models[0], states[0])
    many = linearize_many(models, states, first.chart,
                          families=[scene.steady.family(m.parameters) for m in models])
    # over BUILD_COMPLEX_FROM states the complex-step kernels were compiled for them
    assert len(speeds) >= BUILD_COMPLEX_FROM and model.compiled is not None
    assert complex_kernels(model, build_now=False) is not None
    for v, lin in zip(speeds, many):
        assert matched(lin.eigenvalues, benchmark_eigenvalues(v)) < 1e-8, v
    for i in (0, BATCH_STATES - 1, BATCH_STATES, len(speeds) - 1):
        one = linearize(models[i], states[i], independent=first.chart,
                        family=scene.steady.family(models[i].parameters))
        assert many[i].coordinates == one.coordinates and many[i].neutral == one.neutral
        assert np.allclose(many[i].matrix, one.matrix, rtol=1e-13, atol=1e-13)


def test_bicycle_weave_and_capsize_speeds(bicycle):
    scene, model = bicycle
    # the reference speeds from the benchmark matrices, and the paper's printed values
    weave = brentq(lambda v: max(z.real for z in benchmark_eigenvalues(v) if z.imag), 3, 5,
                   xtol=1e-13)
    capsize = brentq(lambda v: max(z.real for z in benchmark_eigenvalues(v) if not z.imag), 5.5,
                     6.5, xtol=1e-13)
    assert abs(weave - V_WEAVE) < 1e-6 and abs(capsize - V_CAPSIZE) < 1e-6
    swept = sweep_steady(model, scene.steady.values, "v", np.linspace(0, 10, 21))
    kinds = [(c.kind, c.direction) for c in swept.crossings]
    assert kinds == [("complex", -1), ("real", 1)]
    assert abs(swept.crossings[0].value - weave) < 1e-6
    assert abs(swept.crossings[1].value - capsize) < 1e-6
    stable = [v for v, s in zip(swept.values, swept.stable) if s]
    assert stable and min(stable) > weave and max(stable) < capsize


def test_sleigh_steady_motion_closed_form():
    # forward at speed u: w' = -m a u w / (I + m a^2) (see models.chaplygin_sleigh)
    m_, I, a, u = 1.0, 0.25, 0.5, 2.0
    model = numeric_model(chaplygin_sleigh(m=m_, I=I, a=a), backend="numpy")
    state = dict(x=0.3, y=-1.0, theta=0.0, x_dot=u, y_dot=0.0, theta_dot=0.0)
    lin = linearize(model, state)
    assert lin.coordinates == ("theta_dot",)
    assert abs(lin.eigenvalues[0] - (-m_ * a * u / (I + m_ * a * a))) < 1e-12
    assert lin.stable is True
    back = linearize(model, {**state, "x_dot": -u})
    assert back.stable is False


def test_pendulum_equilibria_and_exact_path():
    from nhham.lagrangian.jacobian import exact_jacobian

    system = pendulum_cartesian(g=9.81, l=2.0)
    model = numeric_model(system, backend="numpy")
    bottom = linearize(model, dict(x=0.0, y=-2.0, x_dot=0.0, y_dot=0.0))
    w = np.sqrt(9.81 / 2.0)
    assert matched(bottom.eigenvalues, [1j * w, -1j * w]) < 1e-12
    assert bottom.stable is None and bottom.spectrally_stable
    top = linearize(model, dict(x=0.0, y=2.0, x_dot=0.0, y_dot=0.0))
    assert top.stable is False and matched(top.eigenvalues, [w, -w]) < 1e-12
    ej = exact_jacobian(system, dict(x=0, y=-2, x_dot=0, y_dot=0),
                        {p.name: v for p, v in system.parameter_values.items()}, bottom.chart)
    assert ej.chart == bottom.chart
    assert str(ej.matrix[1, 0]) == "-981/200"   # -g/l exactly
    assert np.allclose(np.array(ej.matrix, dtype=float), bottom.full_matrix, atol=1e-13)


@pytest.mark.parametrize("lagrangian, constraints, why", [
    # W = diag(x, 1) at x = 0
    ("x*x_dot**2/2 + y_dot**2/2", [], "the Hessian W = d2L/dv dv of the lagrangian is "
                                       "singular there"),
    # mu = (x, 0): C = mu W^-1 mu^T = x^2 vanishes at x = 0
    ("(x_dot**2 + y_dot**2)/2", ["x*x_dot"], "C = mu W^-1 mu^T is singular there"),
    # F = -dV/dx = -1/(2 sqrt(x)) at x = 0: 1/0
    ("(x_dot**2 + y_dot**2)/2 - sqrt(x)", [], "the field is not finite there"),
])
def test_a_state_where_the_motion_is_not_defined_is_refused_saying_why(lagrangian,
                                                                       constraints, why):
    """The right-hand side's NumericalFailure at the user's [steady] state was an internal
    failure (exit 1): it is bad input, saying which part is singular or not finite."""
    import nhham

    model = numeric_model(nhham.System(["x", "y"], lagrangian, constraints), backend="numpy")
    with pytest.raises(InconsistentInitialDataError) as info:
        linearize(model, dict(x=0.0, y=0.0, x_dot=0.0, y_dot=0.0))
    assert str(info.value).startswith("steady: the equations of motion are not defined at "
                                      f"the state: {why}")
    assert info.value.key == "steady"


def test_a_state_where_the_constraints_have_no_chart_is_refused_saying_why():
    """g = x^2 + y^2 at the origin: g = 0 and dg = 0, so no coordinate solves g = 0
    there (a ComputationError: exit 1, then 3 with nothing to do). The user's state:
    bad input, naming [steady] and what to change."""
    import nhham

    model = numeric_model(nhham.System(["x", "y", "z"], "(x_dot**2 + y_dot**2 + z_dot**2)/2",
                                       holonomic=["x**2 + y**2"]), backend="numpy")
    from nhham.numerics.steady_sweep import steady_state

    with pytest.raises(InconsistentInitialDataError) as info:  # the [steady] table's lift
        steady_state(model, dict(x=0.0, y=0.0, z=0.0, x_dot=0.0, y_dot=0.0, z_dot=0.0))
    assert str(info.value).startswith("steady: the holonomic constraints are singular at the "
                                      "state") and "choose another [steady] state" in str(info.value)
    assert info.value.key == "steady"


def test_a_state_where_the_state_matrix_is_not_finite_is_refused():
    """W = exp(atan2(asin z, asin z)): its derivative is 0/0 at z = 0 (sympy's is 0,
    the complex step's NaN), and LAPACK refused the NaN matrix ("Array must not contain
    infs or NaNs": an internal error)."""
    import nhham

    model = numeric_model(nhham.System(["z"], "exp(atan2(asin(z), asin(z)))*z_dot**2/2"),
                          backend="numpy")
    with pytest.raises(InconsistentInitialDataError, match="steady: the state matrix is not "
                                                           "finite at the state"):
        linearize(model, dict(z=0.0, z_dot=0.0))


def test_a_lagrangian_not_quadratic_in_v_linearises():
    """L = x'^4/12 + (x'^2 + y'^2)/2 - x^2/2 with y' = x x': W depends on v, and the
    chart's geometry kernel read q alone ("name 'v0' is not defined"). By hand:
    x'' (1 + x'^2 + x^2) = -x - x x'^2, so at rest at 0 x'' = -x: eigenvalues +-i."""
    import nhham

    system = nhham.System(["x", "y"], "x_dot**4/12 + (x_dot**2 + y_dot**2)/2 - x**2/2",
                          ["y_dot - x*x_dot"])
    lin = linearize(numeric_model(system, backend="numpy"),
                    dict(x=0.0, y=0.0, x_dot=0.0, y_dot=0.0))
    assert np.allclose(sorted(lin.eigenvalues, key=lambda z: z.imag), [-1j, 1j], atol=1e-9)


def test_state_off_the_manifold_or_not_steady_is_refused():
    model = numeric_model(pendulum_cartesian(), backend="numpy")
    with pytest.raises(InconsistentInitialDataError, match=r"not on M_1: holonomic\[0\]"):
        linearize(model, dict(x=0.0, y=-1.5, x_dot=0.0, y_dot=0.0))
    with pytest.raises(InconsistentInitialDataError, match=r"not steady: accelerations x_dot'"):
        linearize(model, dict(x=np.sin(0.3), y=-np.cos(0.3), x_dot=0.0, y_dot=0.0))
    sleigh = numeric_model(chaplygin_sleigh(), backend="numpy")
    with pytest.raises(InconsistentInitialDataError, match="not steady"):
        # turning on the spot at constant rate: theta moves but the field depends on it
        linearize(sleigh, dict(x=0.0, y=0.0, theta=0.0, x_dot=0.0, y_dot=0.0, theta_dot=0.0)
                  | {"x_dot": 1.0, "theta_dot": 1.0, "y_dot": 0.5})
