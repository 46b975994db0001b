"""Linearising a steady motion under a nonlinear (Chetaev) constraint: the dependent
velocities of the chart are solved by Newton's method from the state's own (its branch),
through the complex step, and the Jacobian is compared with a hand derivation.

The isokinetic orbit: L = (r'^2 + r^2 theta'^2)/2 - k r^2/2 with r'^2 + r^2 theta'^2 = c^2.
The reaction -lambda (2 r', 2 r^2 theta') is along v; its power -2 lambda c^2 balances the
potential's -k r r', so lambda = -k r r'/(2 c^2) is first order in r' and -2 lambda r' is
second order. To first order theta' = c/r and r'' = r theta'^2 - k r = c^2/r - k r: the
circular orbit r0 = c/sqrt(k) is steady, d r''/dr = -c^2/r0^2 - k = -2k, so the
eigenvalues are +-i sqrt(2k); theta (neutral) has d theta'/dr = -c/r0^2 on the branch
theta' > 0 and +c/r0^2 on theta' < 0.
"""

import math

import numpy as np
import pytest

import nhham
from nhham.numerics.codegen import numeric_model
from nhham.numerics.linearization import linearize, linearize_many

ORBIT = nhham.System(["r", "theta"], "(r_dot**2 + r**2*theta_dot**2)/2 - k*r**2/2",
                     ["r_dot**2 + r**2*theta_dot**2 - c**2"],
                     parameters={"k": 4.0, "c": 2.0}, name="isokinetic orbit")


@pytest.fixture(scope="module")
def model():
    return numeric_model(ORBIT, backend="numpy")


@pytest.mark.parametrize("sign", [1, -1])
def test_the_orbit_s_jacobian_is_the_hand_one_on_either_branch(model, sign):
    k, c = 4.0, 2.0
    r0 = c / math.sqrt(k)
    lin = linearize(model, dict(r=r0, theta=0.0, r_dot=0.0, theta_dot=sign * c / r0))
    assert lin.dependent == ("theta_dot",) and lin.chart == ("r", "theta", "r_dot")
    expected = np.array([[0.0, 0.0, 1.0], [-sign * c / r0**2, 0.0, 0.0], [-2 * k, 0.0, 0.0]])
    np.testing.assert_allclose(lin.full_matrix, expected, atol=1e-12)
    np.testing.assert_allclose(sorted(lin.eigenvalues.imag), [-math.sqrt(2 * k),
                                                              math.sqrt(2 * k)], atol=1e-12)


def test_many_orbits_in_one_batch(model):
    ks = (1.0, 2.25, 4.0)
    states = [dict(r=2.0 / math.sqrt(k), theta=0.0, r_dot=0.0, theta_dot=math.sqrt(k))
              for k in ks]
    chart = linearize(model.with_parameters(k=ks[0]), states[0]).chart
    lins = linearize_many([model.with_parameters(k=k) for k in ks], states, chart)
    for k, lin in zip(ks, lins):
        np.testing.assert_allclose(sorted(lin.eigenvalues.imag),
                                   [-math.sqrt(2 * k), math.sqrt(2 * k)], atol=1e-12)


def test_the_command_s_answer_at_the_steady_motion(model):
    """nhham.linearize on the system with its steady state: the same matrix (its exact
    route for n <= 4)."""
    from nhham.system.scene import loads_scene

    scene = loads_scene('name = "isokinetic orbit"\ncoordinates = ["r", "theta"]\n'
                        'parameters = { k = 4.0, c = 2.0 }\n'
                        'lagrangian = "(r_dot**2 + r**2*theta_dot**2)/2 - k*r**2/2"\n'
                        'constraints = ["r_dot**2 + r**2*theta_dot**2 - c**2"]\n'
                        '[steady]\nr = 1.0\ntheta = 0.0\nr_dot = 0.0\ntheta_dot = 2.0\n')
    answer = nhham.linearize(scene)
    assert answer.failure is None
    np.testing.assert_allclose(answer.data["matrix"], [[0.0, 1.0], [-8.0, 0.0]], atol=1e-12)
