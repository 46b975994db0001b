"""Simulation studies: each end state against a single run and the sleigh's closed form."""

import math

import numpy as np
import pytest

import nhham
from nhham.study.sweep import sweep

from numerics.test_exact_solutions import sleigh_exact

SLEIGH = """
name = "Chaplygin sleigh"
coordinates = ["x", "y", "theta"]
parameters = { m = 1.0, I = 0.3, a = 0.5 }
lagrangian = "m*(x_dot**2 + y_dot**2)/2 + I*theta_dot**2/2"
constraints = ["-sin(theta)*x_dot + cos(theta)*y_dot - a*theta_dot"]

[initial]
x = 0.0
y = 0.0
theta = 0.3
x_dot = 0.1389622633
y_dot = 0.8303012098
theta_dot = 1.5

[simulate]
t_end = 2.0
rtol = 1e-11
atol = 1e-13
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("sleigh") / "sleigh.toml"
    th0, u0, w0, a = 0.3, 0.4, 1.5, 0.5
    e1 = np.array([math.cos(th0), math.sin(th0)])
    e2 = np.array([-math.sin(th0), math.cos(th0)])
    v = u0 * e1 + a * w0 * e2
    path.write_text(SLEIGH.replace("0.1389622633", repr(float(v[0]))).replace("0.8303012098",
                                                                        repr(float(v[1]))))
    return path


def test_a_parameter_grid_gives_what_single_runs_and_the_closed_form_give(scene):
    result = sweep(scene, "simulate", ["a=0.2:0.8:4", "I=0.3,0.6"], workers=1)
    ds = result.dataset
    assert result.complete and ds["success"].all()
    loaded = nhham.load_scene(scene, check_initial=False)
    model = nhham.numeric_model(loaded.system)
    for i, a in enumerate(ds["a"].values):
        for j, inertia in enumerate(ds["I"].values):
            y0 = ds["initial_state"].values[i, j]
            m = model.with_parameters(a=a, I=inertia)
            single = nhham.simulate(m, (0.0, 2.0), y0, rtol=1e-11, atol=1e-13, warn=False)
            assert np.max(np.abs(single.y[:, -1] - ds["final_state"].values[i, j])) <= 1e-10
            # the state moved onto M_1 for this a: theta' and u as the closed form's start
            th0 = y0[2]
            u0 = math.cos(th0) * y0[3] + math.sin(th0) * y0[4]
            u, w, th = sleigh_exact(2.0, th0, u0, y0[5], I=inertia, a=a)
            assert abs(ds["final_state"].values[i, j, 5] - w) < 1e-8
            assert abs(ds["final_state"].values[i, j, 2] - th) < 1e-8
    assert np.abs(ds["energy_error"].values).max() < 1e-9
    assert ds["constraint_residual"].values.max() < 1e-8
    assert (ds["projection_distance"].values[ds["a"].values != 0.5] > 0).all()


def test_an_ensemble_of_perturbed_starts_stays_on_the_constraint(scene):
    result = sweep(scene, "simulate", [], samples_count=40, initial_perturbation=[
        "theta=0.05", "theta_dot=0.1"], seed=3, workers=1)
    ds = result.dataset
    assert ds.sizes["sample"] == 40 and list(ds["perturbed"].values) == ["theta", "theta_dot"]
    model = nhham.numeric_model(nhham.load_scene(scene).system)
    start = model.state(nhham.load_scene(scene).initial)
    y0 = ds["initial_state"].values
    # the perturbed values are kept; the velocities move onto M_1 (the constraint)
    assert np.allclose(y0[:, 2], start[2] + ds["initial_perturbation"].values[:, 0])
    assert model.scaled_residuals(y0).max() < 1e-12
    assert ds["success"].all() and np.abs(ds["energy_error"].values).max() < 1e-9
    # every run keeps its energy, whatever it started with: E(t) = E(0)
    assert np.allclose(model.energy(ds["final_state"].values), model.energy(y0), rtol=1e-9)


def test_what_a_simulation_study_refuses(scene):
    with pytest.raises(nhham.InputError, match="--over: 'z' is neither a parameter"):
        sweep(scene, "simulate", ["z=0:1:2"], workers=1)
    with pytest.raises(nhham.InputError, match="--initial-perturbation: only for"):
        sweep(scene, "linearize", ["a=0:1"], samples_count=3, initial_perturbation=["x=1"],
              workers=1)
    with pytest.raises(nhham.InputError, match="a study runs the adaptive methods"):
        sweep(scene, "simulate", ["a=0.2:0.8:2"], run_options={"method": "rk4"}, workers=1)


def test_starts_projected_because_initial_gives_dependent_velocities_say_so(scene):
    """[initial] gives x' and y', which the blade constraint determines (x' the first
    velocity whose column of mu raises its rank): moving a = 0.5 puts the start off M_1
    at a = 0.2 and 0.8, each projected, and the warning says to leave x' out."""
    from nhham.study.ensemble import summary, summary_warnings

    s = summary(sweep(scene, "simulate", ["a=0.2:0.8:3"], workers=1).dataset)
    assert s["projected_starts"] == 2 and s["given_dependent"] == ["x_dot"]
    (warning,) = summary_warnings(s)
    assert "[initial] gives x_dot, which the constraints determine; leave it out" in warning
