"""Many runs at once (simulate_many) against the sleigh's closed form and single runs."""

import math

import numpy as np

from nhham.numerics.ensemble import simulate_many
from nhham.numerics.integrate import simulate
from nhham.numerics.status import Status

from test_exact_solutions import sleigh_exact, sleigh_state


def _u_w(y):
    th = y[2]
    return math.cos(th) * y[3] + math.sin(th) * y[4], y[5]


def test_each_end_is_the_closed_form_and_the_single_run(sleigh):
    starts = [(0.3, 0.4, 1.5), (0.0, -0.2, 0.7), (1.1, 0.9, -2.0)]
    Y0 = np.array([sleigh_state(*s) for s in starts])
    many = simulate_many(sleigh, Y0, (0.0, 3.0), rtol=1e-10, atol=1e-12)
    assert many.loop == "compiled" and (many.status == 0).all()
    for (th0, u0, w0), y0, y1 in zip(starts, Y0, many.y_final):
        u, w, th = sleigh_exact(3.0, th0, u0, w0)
        assert abs(_u_w(y1)[0] - u) < 1e-8 and abs(y1[5] - w) < 1e-8 and abs(y1[2] - th) < 1e-8
        single = simulate(sleigh, (0.0, 3.0), y0, rtol=1e-10, atol=1e-12, warn=False)
        assert np.max(np.abs(single.y[:, -1] - y1)) <= 1e-12
    # no forces but the constraint's, which do no work on M_1: the work is the integration
    # error of the constraint's power (1e-12 here)
    assert np.max(np.abs(many.work)) < 1e-10


def test_parameters_per_run_and_a_method_without_the_compiled_loop(sleigh):
    y0 = sleigh_state()
    names = sleigh.parameter_names
    P = np.tile(np.asarray(sleigh.parameter_values), (2, 1))
    P[1, names.index("a")] = 0.8
    many = simulate_many(sleigh, np.array([y0, sleigh_state(a=0.8)]), (0.0, 2.0),
                         parameters=P, method="Radau", rtol=1e-10, atol=1e-12)
    assert many.loop == "simulate" and (many.status == 0).all()
    u, w, th = sleigh_exact(2.0, a=0.8)
    assert abs(many.y_final[1, 5] - w) < 1e-7 and abs(many.y_final[1, 2] - th) < 1e-7


def test_the_time_limit_ends_the_runs_not_finished(sleigh):
    Y0 = np.tile(sleigh_state(), (50, 1))
    many = simulate_many(sleigh, Y0, (0.0, 1e6), rtol=1e-12, atol=1e-14, time_limit=0.05)
    assert (many.status == int(Status.TIME_LIMIT)).any()
    assert many.messages and "time limit" in " ".join(many.messages)
