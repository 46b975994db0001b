"""Forces and inputs in the numeric layer, against closed forms and independent integrations.

* The bicycle's B against the benchmark's M⁻¹ (Meijaard et al. 2007: M q'' + v C1 q' +
  (g K0 + v² K2) q = f with f = (T_phi, T_delta)), and its steer-torque controller.
* The differential drive under constant wheel torques with viscous friction: straight
  driving with M φ'' = 2τ - 2cφ', M = (mc + 2 mw) r² + 2 Iw (only the forward kinetic energy
  changes), so φ'(t) = (τ/c)(1 - exp(-2ct/M)); B = M_red⁻¹ with M_red the wheel-rate mass
  matrix of the kinetic energy on M_1 (derived in the test).
* The snakeboard under a torque gait against tests/snakeboard_reference.py (the KKT form
  solved by numpy and scipy, no nhham).
* A time-dependent force against scipy's solve_ivp on the same ODE.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import signal
from scipy.integrate import solve_ivp
from scipy.linalg import expm

import nhham
from nhham.errors import InputError
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate
from nhham.numerics.linearization import linearize
from nhham.numerics.steady_sweep import with_steady_inputs
from nhham.numerics.workprecision import work_precision
from nhham.system.scene import load_scene

import snakeboard_reference as reference  # tests/ is on sys.path (conftest)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
M0 = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])


def steady_linearization(scene, model):
    model, state = with_steady_inputs(model, scene.steady.values(model.parameters))
    return linearize(model, state, family=scene.steady.family(model.parameters))


# ------------------------------------------------------------------ bicycle
@pytest.fixture(scope="module")
def bicycle():
    scene = load_scene(EXAMPLES / "bicycle_steer_control.toml")
    return scene, numeric_model(scene.system)


def test_bicycle_input_matrix_is_the_benchmark_inverse_mass_matrix(bicycle):
    scene, model = bicycle
    for v in np.linspace(0.0, 10.0, 11):
        lin = steady_linearization(scene, model.with_parameters(v=v))
        assert lin.coordinates == ("phi", "delta", "phi_dot", "delta_dot")
        assert lin.inputs == ("T_phi", "T_delta")
        assert np.all(lin.input_matrix[:2] == 0)
        np.testing.assert_allclose(lin.input_matrix[2:], np.linalg.inv(M0), rtol=1e-10,
                                   atol=1e-10)
    ss = lin.state_space()
    assert ss.B.shape == (4, 2) and np.array_equal(ss.A, lin.matrix)


def test_the_steer_controller_places_its_poles_and_returns_upright(bicycle):
    scene, _ = bicycle
    closed = scene.system.closed_loop(scene.control)
    assert closed.inputs == ()
    model = numeric_model(closed)
    lin = linearize(model, {k: x for k, x in scene.steady.values(model.parameters).items()
                            if k not in ("T_phi", "T_delta")},
                    family=scene.steady.family(model.parameters))
    np.testing.assert_allclose(np.sort(lin.eigenvalues.real), [-5, -4, -3, -2], atol=1e-8)
    np.testing.assert_allclose(lin.eigenvalues.imag, 0, atol=1e-8)
    # the closed loop has no input: B and D have no column (none is made up), and
    # scipy's free response is exp(A t) x0
    ss = lin.state_space()
    assert ss.B.shape == (4, 0) and ss.D.shape == (4, 0) and np.array_equal(ss.A, lin.matrix)
    x0 = np.array([0.1, 0.0, 0.0, 0.0])
    _, y, _ = signal.lsim(ss, None, [0.0, 0.5, 1.0], X0=x0)
    np.testing.assert_allclose(y[-1], expm(lin.matrix) @ x0, rtol=1e-6, atol=1e-9)
    run = simulate(closed, (0.0, 10.0), dict(scene.initial), rtol=1e-10)
    assert run.success and scene.initial["phi"] == 0.1
    assert abs(run["phi"][-1]) < 1e-6 and abs(run["delta"][-1]) < 1e-6
    assert run.energy_balance_residual < 1e-8


# --------------------------------------------------------- differential drive
@pytest.fixture(scope="module")
def drive():
    scene = load_scene(EXAMPLES / "differential_drive_motors.toml")
    return scene, {p.name: v for p, v in scene.system.parameter_values.items()}


def test_driven_differential_drive_against_the_closed_form(drive):
    scene, p = drive
    run = nhham.simulate(scene.system.closed_loop(scene.control),
                         **scene.simulate_options(rtol=1e-12, atol=1e-14))
    M = (p["mc"] + 2 * p["mw"]) * p["r"] ** 2 + 2 * p["Iw"]
    rate = p["tau"] / p["c"]
    exact = rate * (1 - np.exp(-2 * p["c"] * run.t / M))
    assert np.max(np.abs(run["phiL_dot"] - exact)) < 1e-10
    assert np.max(np.abs(run["phiR_dot"] - exact)) < 1e-10
    assert abs(run["x_dot"][-1] - p["r"] * rate) < 1e-10      # the steady speed r tau / c
    assert np.max(np.abs(run["theta"])) < 1e-12
    assert run.energy_balance_residual < 1e-10
    # the balance is not vacuous: the energy itself changes by the motors' net work
    assert run.energy[-1] - run.energy[0] > 1e-4


def test_driven_differential_drive_linearisation_by_hand(drive):
    scene, p = drive
    lin = steady_linearization(scene, numeric_model(scene.system))
    assert lin.coordinates == ("phiL_dot", "phiR_dot") and lin.inputs == ("tauL", "tauR")
    # kinetic energy on M_1 at theta = 0 in the wheel rates: x' = r (wL + wR)/2,
    # theta' = r (wR - wL)/(2b), so M_red = a [[1, 1], [1, 1]] + e [[1, -1], [-1, 1]] + Iw I
    J = p["Ic"] + 2 * p["Id"] + 2 * p["b"] ** 2 * p["mw"] + p["d"] ** 2 * p["mc"]
    a = (p["mc"] + 2 * p["mw"]) * p["r"] ** 2 / 4
    e = J * p["r"] ** 2 / (4 * p["b"] ** 2)
    M_red = a * np.ones((2, 2)) + e * np.array([[1, -1], [-1, 1]]) + p["Iw"] * np.eye(2)
    np.testing.assert_allclose(lin.input_matrix, np.linalg.inv(M_red), rtol=1e-10)
    M = (p["mc"] + 2 * p["mw"]) * p["r"] ** 2 + 2 * p["Iw"]
    assert np.isclose(lin.eigenvalues.real.max(), -2 * p["c"] / M, rtol=1e-10)


@pytest.mark.filterwarnings("ignore:the reference error estimate")
def test_work_precision_of_a_dissipative_system_reports_the_energy_balance(drive):
    scene, _ = drive
    wp = work_precision(scene.system.closed_loop(scene.control), dict(scene.initial),
                        (0.0, 2.0), quick=True)
    assert wp.forced and "energy balance" in wp.table()
    assert not {"rattle", "rattle4"} & set(wp.methods())
    good = [r for r in wp.rows if r.status == 0 and r.error < 1e-8]
    assert good and all(r.energy_balance_residual < 1e-6 for r in good)


# ---------------------------------------------------------------- snakeboard
def test_snakeboard_gait_against_an_independent_kkt_integration():
    scene = load_scene(EXAMPLES / "snakeboard_gait.toml")
    run = nhham.simulate(scene.system.closed_loop(scene.control),
                         **scene.simulate_options(rtol=1e-12, atol=1e-13))
    moved = np.array([run["x"][-1], run["y"][-1], run["theta"][-1]])
    np.testing.assert_allclose(moved, reference.net_displacement(), rtol=0, atol=1e-8)
    assert run.energy_balance_residual < 1e-10


# -------------------------------------------------------------- time and inputs
def driven_oscillator():
    return nhham.System(["x"], "m*x_dot**2/2 - k*x**2/2",
                        parameters={"m": 1.0, "k": 2.0, "c": 0.1},
                        forces={"x": "-c*x_dot + u*sin(t)"}, inputs=["u"])


@pytest.mark.parametrize("backend,loop,method", [("auto", "auto", "DOP853"),
                                                 ("numpy", "auto", "DOP853"),
                                                 ("auto", "scipy", "RK45"),
                                                 ("auto", "auto", "Radau")])
def test_a_time_dependent_force_against_solve_ivp(backend, loop, method):
    system = driven_oscillator().closed_loop({"u": "1/2"})
    model = numeric_model(system, backend=backend)
    assert model.time_slot is not None and system.time is not None
    run = simulate(model, (0.0, 10.0), {"x": 1.0, "x_dot": 0.0}, rtol=1e-11, atol=1e-12,
                   method=method, loop=loop)
    ref = solve_ivp(lambda t, y: [y[1], -2 * y[0] - 0.1 * y[1] + 0.5 * math.sin(t)],
                    (0.0, 10.0), [1.0, 0.0], rtol=1e-12, atol=1e-13, method="DOP853")
    np.testing.assert_allclose(run.y[:, -1], ref.y[:, -1], atol=1e-8)
    assert run.energy_balance_residual < 1e-8
    y = np.array([0.3, 0.2])
    assert math.isclose(model.rhs(1.0, y)[1], -0.6 - 0.02 + 0.5 * math.sin(1.0), rel_tol=1e-14)


def test_inputs_are_parameters_of_the_model_set_at_run_time():
    model = numeric_model(driven_oscillator())
    assert model.input_names == ("u",) and model.unset_inputs() == ("u",)
    with pytest.raises(InputError, match="no value for u"):
        simulate(model, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0})
    set_ = model.with_parameters(u=0.5)
    assert set_.unset_inputs() == ()
    assert np.allclose(set_.at_time(1.0).rhs(1.0, np.array([0.3, 0.2])),
                       model.with_parameters(u=0.5).rhs(1.0, np.array([0.3, 0.2])))


def test_what_does_not_take_forces_refuses_them():
    forced = nhham.System(["x"], "x_dot**2/2 - x**2/2", dissipation="x_dot**2/4")
    with pytest.raises(InputError, match="conservative systems"):
        simulate(forced, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, method="rattle", step=0.1)
    timed = driven_oscillator().closed_loop({"u": "1"})
    # the mpmath reference and rk4 take the time (t is a state entry of the reference's
    # steps; each rk4 stage sets its own): they agree with DOP853 at tight tolerances
    start = {"x": 1.0, "x_dot": 0.0}
    ref = simulate(timed, (0.0, 1.0), start, method="reference", reference_digits=20)
    dop = simulate(timed, (0.0, 1.0), start, rtol=1e-13, atol=1e-13)
    rk4 = simulate(timed, (0.0, 1.0), start, method="rk4", step=0.01)
    assert abs(ref.y[0, -1] - dop.y[0, -1]) < 1e-11
    assert abs(rk4.y[0, -1] - dop.y[0, -1]) < 1e-8
    with pytest.raises(InputError, match="depend on time"):
        linearize(numeric_model(timed), {"x": 0.0, "x_dot": 0.0})
    with pytest.raises(InputError, match="steady value for the input"):
        linearize(numeric_model(driven_oscillator()), {"x": 0.0, "x_dot": 0.0})


def test_a_dissipative_free_fall_matches_its_closed_form():
    """x'' = -g - c x' from rest: x'(t) = -(g/c)(1 - exp(-ct)); energy balance E - E0 = W."""
    s = nhham.System(["x"], "x_dot**2/2 - g*x", parameters={"g": 9.81, "c": 0.5},
                     dissipation="c*x_dot**2/2")
    run = simulate(s, (0.0, 3.0), {"x": 0.0, "x_dot": 0.0}, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(run["x_dot"], -(9.81 / 0.5) * (1 - np.exp(-0.5 * run.t)),
                               atol=1e-10)
    assert run.energy_balance_residual < 1e-10 and run.energy[-1] < run.energy[0]


def test_linearize_an_unconstrained_forced_oscillator_by_hand():
    """x'' = -k x - c x' + u about x = u/k: A = [[0, 1], [-k, -c]], B = [[0], [1]] (m = 0)."""
    s = nhham.System(["x"], "x_dot**2/2 - k*x**2/2", parameters={"k": 2.0, "c": 0.1},
                     forces={"x": "-c*x_dot + u"}, inputs=["u"])
    model = numeric_model(s).with_parameters(u=0.5)
    lin = linearize(model, {"x": 0.25, "x_dot": 0.0}, neutral=False)
    np.testing.assert_allclose(lin.matrix, [[0, 1], [-2.0, -0.1]], atol=1e-14)
    np.testing.assert_allclose(lin.input_matrix, [[0], [1]], atol=1e-14)


def test_inputs_from_a_python_callable_or_an_expression():
    """u = 1/2 - x/5 as a callable (the scipy loop sets it at every evaluation) and as an
    expression (compiled with the field): both the ODE x'' = -2x - x'/10 + u sin t."""
    ref = solve_ivp(lambda t, y: [y[1], -2 * y[0] - 0.1 * y[1] + (0.5 - 0.2 * y[0]) * math.sin(t)],
                    (0.0, 10.0), [1.0, 0.0], rtol=1e-12, atol=1e-13, method="DOP853")
    system = driven_oscillator()
    for law, method in ((lambda t, y: 0.5 - 0.2 * y[0], "DOP853"),
                        (lambda t, y: 0.5 - 0.2 * y[0], "Radau"), ("1/2 - x/5", "DOP853")):
        run = simulate(system, (0.0, 10.0), {"x": 1.0, "x_dot": 0.0}, rtol=1e-11, atol=1e-12,
                       method=method, controls={"u": law})
        np.testing.assert_allclose(run.y[:, -1], ref.y[:, -1], atol=1e-8)
    with pytest.raises(InputError, match="scipy methods"):
        simulate(system, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, method="rk4", step=0.1,
                 controls={"u": lambda t, y: 0.0})
    with pytest.raises(InputError, match="not an input"):
        simulate(system, (0.0, 1.0), {"x": 1.0, "x_dot": 0.0}, controls={"v": lambda t, y: 0})


def test_multipliers_along_a_run_use_each_state_s_time_and_inputs():
    """A particle in the plane with x' = y' (one constraint, λ = (Q_x - Q_y)/2 for unit
    masses): with Q_x = sin t, or a callable input u(t, y) = t as Q_x, λ(t) = sin(t)/2 or
    t/2 at every stored state."""
    base = dict(coordinates=["x", "y"], lagrangian="(x_dot**2 + y_dot**2)/2",
                constraints=["x_dot - y_dot"])
    timed = nhham.System(**base, forces={"x": "sin(t)"})
    run = simulate(timed, (0.0, 2.0), {"x": 0, "y": 0, "x_dot": 0, "y_dot": 0}, rtol=1e-10)
    np.testing.assert_allclose(run.multipliers[0], np.sin(run.t) / 2, atol=1e-12)
    driven = nhham.System(**base, forces={"x": "u"}, inputs=["u"])
    run = simulate(driven, (0.0, 2.0), {"x": 0, "y": 0, "x_dot": 0, "y_dot": 0}, rtol=1e-10,
                   controls={"u": lambda t, y: t})
    np.testing.assert_allclose(run.multipliers[0], run.t / 2, atol=1e-12)


def test_a_failing_control_callable_is_named():
    with pytest.raises(InputError, match=r"controls.u: f\(t, y\).*TypeError"):
        simulate(driven_oscillator(), (0.0, 1.0), {"x": 1.0, "x_dot": 0.0},
                 controls={"u": lambda t: t})
