"""scipy's solvers stepped by nhham (nhham.numerics.scipy_loop): the projection keeps
the solver's history, dense output and events, against the rolling disk's closed form."""

from __future__ import annotations

import numpy as np
import pytest

from nhham.errors import InputError
from nhham.numerics.codegen import numeric_model
from nhham.numerics.integrate import simulate

from test_exact_solutions import sleigh_state


@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau", "BDF", "LSODA"])
def test_projection_keeps_solver_history(sleigh, method):
    """Projecting after each step must not restart the solver: the number of
    steps stays close to the unprojected run."""
    plain = simulate(sleigh, (0, 10), sleigh_state(), method=method, warn=False)
    proj = simulate(sleigh, (0, 10), sleigh_state(), method=method, projection=True, warn=False)
    assert proj.nsteps <= 1.3 * plain.nsteps + 5
    assert proj.constraint_residual_max <= 1e-14


def test_dense_output_against_the_exact_solution():
    """The rolling disk: theta = theta0 + w t, x and y on a circle (closed form)."""
    from test_exact_solutions import rolling_disk, rolling_disk_exact

    model = numeric_model(rolling_disk())
    y0, _ = rolling_disk_exact(np.array(0.0))
    for method in ("DOP853", "Radau"):
        res = simulate(model, (0, 4), y0, method=method, rtol=1e-10, atol=1e-12,
                       dense_output=True, warn=False)
        assert res.settings["loop"] == "scipy" and res.sol is not None
        t = np.linspace(0, 4, 41)
        exact, _ = rolling_disk_exact(t)
        assert res.sol(t).shape == (8, 41) and res.sol(1.3).shape == (8,)
        assert np.max(np.abs(res.sol(t) - exact)) < 1e-6, method
        assert (res.sol.t_min, res.sol.t_max) == (0.0, 4.0)
    assert simulate(model, (0, 1), y0, warn=False).sol is None


def test_events_located_and_terminal():
    """theta = 0.3 + 1.1 t crosses 1 at t = 0.7/1.1 and 2 at t = 1.7/1.1 (closed form);
    cos(theta) changes sign downwards at theta = pi/2."""
    from test_exact_solutions import rolling_disk, rolling_disk_exact

    model = numeric_model(rolling_disk())
    y0, _ = rolling_disk_exact(np.array(0.0))

    def theta_is_1(t, y):
        return y[2] - 1.0

    def cos_theta(t, y):
        return np.cos(y[2])

    def theta_is_2(t, y):
        return y[2] - 2.0

    cos_theta.direction = -1
    theta_is_2.terminal = True
    res = simulate(model, (0, 5), y0, rtol=1e-11, atol=1e-12,
                   events=[theta_is_1, cos_theta, theta_is_2], warn=False)
    assert res.status == 1 and res.success and "termination event" in res.message
    assert res.t_events[0] == pytest.approx([0.7 / 1.1], abs=1e-9)
    assert res.t_events[1] == pytest.approx([(np.pi / 2 - 0.3) / 1.1], abs=1e-9)
    assert res.t[-1] == pytest.approx(1.7 / 1.1, abs=1e-9)
    exact, _ = rolling_disk_exact(np.array(res.t_events[0]))
    assert res.y_events[0].shape == (1, 8)
    assert np.allclose(res.y_events[0][0], exact[:, 0], atol=1e-8)
    with pytest.raises(InputError, match="dense_output/events"):
        simulate(model, (0, 1), y0, method="rattle", step=0.1, events=theta_is_1)
    with pytest.raises(InputError, match="dense_output and events"):
        simulate(model, (0, 1), y0, loop="compiled", dense_output=True)


def test_a_python_kernel_that_raises_mid_run_stops_the_run_not_the_process():
    """sqrt(1 - x) is not real past x = 1 (x = t here): the numpy kernels raise where the
    compiled ones give NaN; both stop the run with the non-finite status."""
    import nhham
    from nhham.numerics.integrate import simulate
    from nhham.numerics.model import NumericsWarning

    s = nhham.System(["x", "y"], "(x_dot**2 + y_dot**2)/2", constraints=["x_dot - y_dot"],
                     forces={"x": "sqrt(1 - x)"})
    with pytest.warns(NumericsWarning, match="run stopped: non-finite"):
        result = simulate(s, (0.0, 3.0), {"x": 0.0, "y": 0.0, "x_dot": 1.0, "y_dot": 1.0},
                          backend="numpy")
    assert not result.success and int(result.status) == -2
    assert 0.5 < result.t[-1] < 1.0   # x'' = sqrt(1 - x)/2 > 0: x passes 1 before t = 1
