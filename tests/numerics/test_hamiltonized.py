"""Integration in Hamiltonized time (nhham.numerics.hamiltonized, the field from
nhham.journeys.hamiltonized_motion): the nonholonomic particle against its closed form,
order 2, symmetry, the constraints exact on the output grid, the energy bounded, the
rubber ball through two reduction steps against DOP853, and the refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import nhham
from nhham.errors import InputError
from nhham.journeys.hamiltonized_motion import hamiltonized_field
from nhham.journeys.simulation import simulate as simulate_scene
from nhham.numerics.hamiltonized import _midpoint, hamiltonized

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def particle():
    scene = nhham.load_scene(str(EXAMPLES / "nonholonomic_particle.toml"))
    field, found = hamiltonized_field(scene.system)
    model = nhham.numeric_model(scene.system, backend="numpy")
    return field, found, model, model.state(scene.checked_initial())


def _closed_form(t):
    """From x = z = 0, y = 1, x' = 1, y' = 1/2 (z' = y x' = 1): y' and x' sqrt(1 + y^2) =
    sqrt(2) are constant (by hand), so y = 1 + t/2, x = 2 sqrt(2) (asinh y - asinh 1),
    z = 2 sqrt(2) (sqrt(1 + y^2) - sqrt(2))."""
    c = math.sqrt(2.0)
    y = 1.0 + 0.5 * t
    return (2 * c * (np.arcsinh(y) - np.arcsinh(1.0)), y,
            2 * c * (np.sqrt(1 + y ** 2) - math.sqrt(2.0)))


def test_the_factor_and_the_canonical_momenta(particle):
    """f = (1 + y^2)^(-1/2) (the scene's header) and H~ = (P_x^2 + (1 + y^2) P_y^2)/2 with
    P = f p (by hand): P_x = x' sqrt(1 + y^2) is the conserved quantity."""
    field, found, model, y0 = particle
    assert str(found.conformal_factor) == "1/sqrt(y**2 + 1)"
    r, P = np.array([0.3, 1.0]), np.array([0.7, -0.4])
    assert field.hamiltonian(r, P) == pytest.approx((0.7 ** 2 + 2.0 * 0.4 ** 2) / 2, rel=1e-14)
    gr, gP = field.gradient(r, P)
    assert np.allclose(gr, [0.0, 1.0 * 0.4 ** 2], rtol=1e-14)
    assert np.allclose(gP, [0.7, 2.0 * -0.4], rtol=1e-14)


def test_order_two_against_the_closed_form_and_the_constraint_exact(particle):
    field, _, model, y0 = particle
    errors = []
    for h in (0.1, 0.05, 0.025):
        run = hamiltonized(model, y0, 0.0, 10.0, h, reduced=field)
        assert run.status == 0 and run.t[-1] == 10.0 and len(run.t) == round(10 / h) + 1
        x, y, z = _closed_form(run.t)
        errors.append(max(np.max(np.abs(run.y[0] - x)), np.max(np.abs(run.y[1] - y)),
                          np.max(np.abs(run.y[2] - z))))
        assert np.max(np.abs(model.residuals(run.y.T))) < 1e-15   # z' = y x' on the grid
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(3.8 < q < 4.2 for q in ratios), (errors, ratios)


def test_the_midpoint_step_is_symmetric(particle):
    field = particle[0]
    r0, P0 = np.array([0.0, 1.0]), np.array([math.sqrt(2), 0.5 / math.sqrt(2)])
    r1, P1, _ = _midpoint(field, r0, P0, 0.1)
    rb, Pb, _ = _midpoint(field, r1, P1, -0.1)
    assert np.max(np.abs(np.concatenate([rb - r0, Pb - P0]))) < 1e-15


def test_the_energy_stays_bounded_over_20000_steps(particle):
    """Symplectic in tau: the energy error of the first and of the last quarter of the run
    are alike (no drift), and small at h = 0.05."""
    field, _, model, y0 = particle
    y_start = model.state(dict(x=0.0, y=0.0, z=0.0, x_dot=1.0, y_dot=0.0, z_dot=0.0))
    y_start[4] = 0.3   # y' = 0.3 with y = 0: z' = y x' = 0 still
    run = hamiltonized(model, y_start, 0.0, 1000.0, 0.05, reduced=field, save_every=10)
    E = model.energy(run.y.T)
    err = np.abs(E - E[0])
    quarter = len(err) // 4
    assert run.status == 0 and np.max(err) < 1e-3
    assert np.max(err[-quarter:]) < 2.0 * np.max(err[:quarter]) + 1e-14


def test_the_rubber_ball_through_two_steps_against_dop853():
    """--symmetry x,y --then yaw: the state at t = 2 within the method's order of DOP853's
    at rtol 1e-13, the errors falling four-fold per halving; no twist and rolling exact."""
    scene = nhham.load_scene(str(EXAMPLES / "rubber_ball.toml"))
    start = dict(yaw=0.0, pitch=0.2, roll=0.1, x=0.0, y=0.0, pitch_dot=0.3, roll_dot=2.0)
    ref = simulate_scene(scene, t_end=2.0, initial=start, options={
        "method": "DOP853", "rtol": 1e-13, "atol": 1e-14}).payload["result"].y[:, -1]
    field, _ = hamiltonized_field(scene.system, symmetry=["x", "y"], then=["yaw"])
    model = nhham.numeric_model(scene.system, backend="numpy")
    y0 = simulate_scene(scene, t_end=0.01, initial=start, options={
        "method": "DOP853"}).payload["result"].y[:, 0]
    errors = []
    for h in (0.02, 0.01):
        run = hamiltonized(model, y0, 0.0, 2.0, h, reduced=field)
        errors.append(np.max(np.abs(run.y[:, -1] - ref)))
        assert np.max(np.abs(model.residuals(run.y.T))) < 1e-14
    assert 3.8 < errors[0] / errors[1] < 4.2 and errors[1] < 1e-4, errors


def test_the_command_runs_it_and_refuses_where_there_is_no_factor():
    particle = simulate_scene(str(EXAMPLES / "nonholonomic_particle.toml"), t_end=5.0,
                              options={"method": "hamiltonized", "step": 0.05})
    result = particle.payload["result"]
    assert result.method == "hamiltonized" and result.success
    assert abs(result["y"][-1] - 3.5) < 3e-4   # y = 1 + t/2 (the clock's error: order 2)
    with pytest.raises(InputError, match="no conformal factor"):
        simulate_scene(str(EXAMPLES / "chaplygin_sleigh.toml"), t_end=1.0,
                       options={"method": "hamiltonized", "step": 0.05})
    with pytest.raises(InputError, match="read by method hamiltonized only"):
        simulate_scene(str(EXAMPLES / "chaplygin_sleigh.toml"), t_end=1.0,
                       options={"method": "rk4", "step": 0.05, "symmetry": ["x"]})


def test_a_scene_names_the_reduction_in_its_simulate_table(tmp_path):
    """``[simulate]`` with method = "hamiltonized", symmetry and then: the command runs the
    rubber ball's two steps from the table; another method leaves the table's reduction
    out, and ``--symmetry`` given with it is refused naming the option."""
    import json
    import subprocess
    import sys

    text = (EXAMPLES / "rubber_ball.toml").read_text().split("[simulate]")[0]
    scene = tmp_path / "ball.toml"
    scene.write_text(text + '[simulate]\nt_end = 1.0\nmethod = "hamiltonized"\nstep = 0.05\n'
                     'symmetry = ["x", "y"]\nthen = ["yaw"]\n')
    run = subprocess.run([sys.executable, "-m", "nhham", "simulate", str(scene), "--json"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)["result"]
    assert result["method"] == "hamiltonized" and result["constraint_residual_max"] < 1e-14
    other = subprocess.run([sys.executable, "-m", "nhham", "simulate", str(scene), "--json",
                            "--method", "rk4", "--t-end", "0.1"], capture_output=True,
                           text=True)
    assert other.returncode == 0, other.stderr    # the table's reduction left out for rk4
    refused = subprocess.run([sys.executable, "-m", "nhham", "simulate", str(scene),
                              "--method", "rk4", "--symmetry", "x", "--t-end", "0.1"],
                             capture_output=True, text=True)
    assert refused.returncode == 2 and "hamiltonized only" in refused.stderr
